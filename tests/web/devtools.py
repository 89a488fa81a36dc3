# SPDX-License-Identifier: Apache-2.0
# Headless chromium driven over the DevTools protocol, for the page tests of tests/web/ (the
# flipbook page, the `impulse analyze --report` page): one browser per test module, a page that
# says on its <body data-*> when it has drawn (data-ready="1") or what went wrong (data-error).
import base64
import fcntl
import json
import os
import select
import shutil
import subprocess
import sys
import time

import pytest


def no_chromium():
    """Why chromium cannot be started here, or None."""
    if not (shutil.which("chromium") or shutil.which("chromium-browser")):
        return "chromium is not installed (scripts/setup.sh --tests installs it)"
    return None


def main(test_file, reason):
    """Runs a test module as a script (as CTest does): exit 77, skipped, with `reason` when it
    is not None, else pytest's exit status."""
    if reason:
        print(f"skipped: {reason}")
        sys.exit(77)
    sys.exit(pytest.main([test_file, "-q", "-s", "-p", "no:cacheprovider", *sys.argv[1:]]))


def impulse_cli():
    """The built tool ctest names in IMPULSE_CLI; fails the test without it."""
    cli = os.environ.get("IMPULSE_CLI", "")
    if not os.access(cli, os.X_OK):
        pytest.fail("IMPULSE_CLI must name the built impulse tool (ctest sets it)")
    return cli


class Browser:
    """One headless chromium for the whole module, driven over the DevTools protocol on a pipe
    (--remote-debugging-pipe: commands in on its fd 3, answers out on its fd 4, each a JSON text
    ended by NUL): one start (~4 s) instead of one per picture."""

    def __init__(self, profile, size=(1280, 800)):
        self.size = size  # the viewport open() sets, CSS pixels
        self.events = []  # the protocol's events (no id) seen so far, oldest first
        binary = shutil.which("chromium") or shutil.which("chromium-browser")
        to_browser, self.out = os.pipe()
        self.inp, from_browser = os.pipe()

        def wire_pipes():  # in the child: its fds 3 and 4, via fds above them
            high_in, high_out = fcntl.fcntl(to_browser, fcntl.F_DUPFD, 10), fcntl.fcntl(from_browser, fcntl.F_DUPFD, 10)
            os.dup2(high_in, 3)
            os.dup2(high_out, 4)
            os.close(high_in)
            os.close(high_out)

        # WebGL without a GPU: ANGLE on SwiftShader, the CPU rasteriser chromium ships.
        self.log = profile.parent / "chromium.log"
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen(
                [binary, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                 "--disable-dev-shm-usage", "--no-first-run", "--disable-quic", "--disable-background-networking",
                 "--disable-component-update", "--disable-sync", "--hide-scrollbars", "--remote-debugging-pipe",
                 f"--user-data-dir={profile}", "about:blank"],
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=log,
                preexec_fn=wire_pipes, close_fds=False)
        os.close(to_browser)
        os.close(from_browser)
        self.buffer, self.next_id = b"", 0
        target = self.call("Target.createTarget", url="about:blank")["targetId"]
        self.session = self.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]

    def call(self, method, session=None, timeout_s=30, **params):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = session
        os.write(self.out, json.dumps(message).encode() + b"\0")
        end = time.monotonic() + timeout_s
        while True:
            while b"\0" not in self.buffer:
                left = end - time.monotonic()
                ready, _, _ = select.select([self.inp], [], [], max(left, 0))
                if not ready:
                    pytest.fail(f"chromium did not answer {method} within {timeout_s} s ({self.log_tail()})")
                chunk = os.read(self.inp, 1 << 20)
                if not chunk:
                    pytest.fail(f"chromium closed its pipe during {method} ({self.log_tail()})")
                self.buffer += chunk
            text, self.buffer = self.buffer.split(b"\0", 1)
            answer = json.loads(text)
            if "method" in answer and "id" not in answer:
                self.events.append(answer)
            if answer.get("id") == self.next_id:
                assert "error" not in answer, f"{method}: {answer['error']}"
                return answer["result"]

    def log_tail(self):
        return "chromium.log ends: " + self.log.read_text(errors="replace")[-600:]

    def page(self, method, **params):
        return self.call(method, session=self.session, **params)

    def evaluate(self, expression):
        return self.page("Runtime.evaluate", expression=expression, returnByValue=True,
                         awaitPromise=True)["result"].get("value")

    def open(self, url, size=None):
        """Loads `url` in a viewport of `size` CSS pixels at one device pixel per CSS pixel and
        waits until the page has drawn or said what is wrong: its <body data-*>."""
        size = size or self.size
        self.page("Emulation.setDeviceMetricsOverride", width=size[0], height=size[1], deviceScaleFactor=1,
                  mobile=False)
        # A mark on the page being left, so its state is never taken for the new page's.
        self.evaluate("window.leftBehind = true")
        self.page("Page.navigate", url=url)
        end = time.monotonic() + 20
        while time.monotonic() < end:
            state = self.evaluate("!window.leftBehind && document.readyState === 'complete' && document.body ? "
                                  "Object.assign({}, document.body.dataset) : null")
            if state and (state.get("ready") == "1" or state.get("error")):
                # Two animation frames: the drawn canvas has reached the compositor.
                self.evaluate("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
                return state
            time.sleep(0.05)
        pytest.fail(f"{url}: the page neither drew nor said why within 20 s")

    def screenshot(self, path):
        path.write_bytes(base64.b64decode(self.page("Page.captureScreenshot", format="png")["data"]))

    def close(self):
        try:
            self.call("Browser.close", timeout_s=10)
        except BaseException:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self.out)
        os.close(self.inp)
