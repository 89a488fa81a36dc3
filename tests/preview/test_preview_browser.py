# SPDX-License-Identifier: Apache-2.0
# `impulse preview` in a real browser (Debian's chromium, headless): a frame is shown, an edit
# of the scene file changes the picture, a broken file shows its one-line error and keeps the
# picture; the server's HTTP bounds. Run by CTest (preview_browser) with IMPULSE_CLI set.
import html
import http.client
import json
import os
import re
import select
import shutil
import signal
import subprocess
import time

import pytest

SCENE = """# a small animated scene for the preview test
[output]
size = [160, 120]
frames = 24
fps = 24

[[layer]]
seed = 3
density = 12.0
lifetime = 1.0
[layer.kernel]
type = "gaussian"
radius = 12.0
sigma = 4.0
"""
RADIUS_LINE = SCENE.splitlines().index("radius = 12.0") + 1


def wait_for(what, condition, timeout_s):
    """Polls `condition` until it returns a true value (bounded)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what}")


class Server:
    def __init__(self, cli, scene, *args):
        self.proc = subprocess.Popen([cli, "preview", str(scene), "--port", "0", *args],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        ready, _, _ = select.select([self.proc.stdout], [], [], 20)
        line = self.proc.stdout.readline() if ready else ""
        m = re.match(r"preview: http://127\.0\.0\.1:(\d+)/", line)
        if not m:
            self.proc.kill()
            pytest.fail(f"no preview line: {line!r} {self.proc.stderr.read()!r}")
        self.port = int(m.group(1))
        self.url = f"http://127.0.0.1:{self.port}/"

    def request(self, method, path):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=5)
        try:
            conn.request(method, path)
            r = conn.getresponse()
            return r.status, r.read()
        finally:
            conn.close()

    def state(self):
        return json.loads(self.request("GET", "/state")[1])

    def stop(self):
        self.proc.send_signal(signal.SIGTERM)
        # A frame being rendered finishes first: a clouds frame at 960x540 takes over a minute
        # under the sanitizers (measured: stop not done after 60 s on the 2-core machine).
        return self.proc.wait(timeout=300 if os.environ.get("IMPULSE_SANITIZED") else 60)


@pytest.fixture
def cli():
    path = os.environ.get("IMPULSE_CLI", "")
    if not os.access(path, os.X_OK):
        pytest.fail("IMPULSE_CLI must name the built impulse tool (ctest sets it)")
    return path


def browser_dom(url, profile):
    """The page's DOM after ~3 s of its (virtual) time in headless chromium."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if not chromium:
        pytest.fail("chromium is not installed (scripts/setup.sh installs it)")
    run = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu",
                          "--disable-dev-shm-usage", "--no-first-run", f"--user-data-dir={profile}",
                          "--virtual-time-budget=3000", "--dump-dom", url],
                         capture_output=True, text=True, timeout=40)
    body = re.search(r"<body([^>]*)>", run.stdout)
    assert body, f"no DOM from chromium: {run.stderr[-500:]}"
    attributes = re.findall(r'data-([a-z-]+)="([^"]*)"', body.group(1))
    return {k: html.unescape(v) for k, v in attributes}, run.stdout


def all_frames_rendered(server, generation):
    """Waits until the server holds every frame of `generation` (so the page finds them, however
    slow the machine)."""
    wait_for(f"the frames of generation {generation}",
             lambda: server.state()["generation"] == generation and
             server.state()["cached"] == 24, 20)


def test_preview_in_a_browser(cli, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    server = Server(cli, scene, "--expose", "layer.0.kernel.radius")
    try:
        all_frames_rendered(server, 1)

        # A frame is shown.
        dom, _ = browser_dom(server.url, tmp_path / "profile")
        assert int(dom["shown-frame"]) >= 0 and dom["shown-digest"] and dom["error"] == ""
        first = dom["shown-digest"]

        # Saving the file re-renders within a second.
        t0 = time.monotonic()
        scene.write_text(SCENE.replace("seed = 3", "seed = 4"))
        wait_for("the reload", lambda: server.state()["generation"] >= 2, 5)
        wait_for("a frame of the edited scene",
                 lambda: server.request("GET", "/frame?g=2&i=0")[0] == 200, 5)
        reloaded_s = time.monotonic() - t0
        print(f"edit to first new frame: {reloaded_s:.3f} s")
        assert reloaded_s < 1.0
        all_frames_rendered(server, 2)
        dom, _ = browser_dom(server.url, tmp_path / "profile")
        assert dom["shown-generation"] == "2" and dom["shown-digest"] != first

        # A slider: the override applies and the TOML line to paste back follows it.
        assert server.request("POST", "/set?key=layer.0.kernel.radius&value=9.5")[0] == 200
        wait_for("the slider's reload", lambda: server.state()["generation"] >= 3, 5)
        assert server.state()["exposed"][0]["line"] == "radius = 9.5  # in [layer.kernel] of [[layer]] 0"
        status, body = server.request("POST", "/set?key=output.fps&value=3")
        assert status == 400 and body.decode().startswith('unknown key "output.fps"')
        status, body = server.request("POST", "/set?key=layer.0.kernel.radius&value=-4")
        wait_for("the override's error", lambda: "radius" in server.state()["error"], 5)
        assert server.request("POST", "/set?key=layer.0.kernel.radius&value=12")[0] == 200
        wait_for("the override fixed", lambda: server.state()["error"] == "", 5)
        all_frames_rendered(server, 4)

        # A broken file: the error line with file:line:col, the last good picture kept.
        scene.write_text(SCENE.replace("seed = 3", "seed = 4").replace("radius = 12.0", "radius = -12.0"))
        wait_for("the error", lambda: server.state()["error"], 5)
        dom, page = browser_dom(server.url, tmp_path / "profile")
        assert re.match(re.escape(str(scene)) + rf":{RADIUS_LINE}:\d+: layer\[0\]\.kernel\.radius",
                        dom["error"]), dom["error"]
        assert dom["shown-digest"] and 'src="blob:' in page
        assert f"<div id=\"error\">{html.escape(dom['error'], quote=False)}</div>" in page

        # The file disappears: the server keeps serving and says so; back, it reloads.
        text = scene.read_text()
        scene.unlink()
        wait_for("the missing file", lambda: "cannot open" in server.state()["error"], 5)
        scene.write_text(text.replace("radius = -12.0", "radius = 12.0"))
        wait_for("the file back", lambda: server.state()["error"] == "", 5)

        # Paths outside what it serves are refused.
        assert server.request("GET", "/../../etc/passwd")[0] == 403
        assert server.request("GET", "/etc/passwd")[0] == 404
        assert server.request("GET", "/frame?g=x&i=0")[0] == 400
    finally:
        assert server.stop() == 0


def test_port_in_use_is_one_line(cli, tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text(SCENE)
    server = Server(cli, scene)
    try:
        run = subprocess.run([cli, "preview", str(scene), "--port", str(server.port)],
                             capture_output=True, text=True, timeout=20)
        assert run.returncode == 1
        assert run.stderr == f"error: 127.0.0.1:{server.port}: port in use (another program " \
                             "listens on it; --port N or --port 0 for a free one)\n"
    finally:
        assert server.stop() == 0


def test_the_server_answers_while_a_slow_scene_renders(cli, tmp_path):
    # clouds (perspective) at 960x540 takes a good fraction of a second a frame: /state must
    # not wait for it.
    server = Server(cli, "clouds", "--size", "960x540")
    try:
        worst = 0.0
        for _ in range(20):
            t0 = time.monotonic()
            server.state()
            worst = max(worst, time.monotonic() - t0)
            time.sleep(0.05)
        assert worst < 0.25, f"/state took {worst:.3f} s"
    finally:
        assert server.stop() == 0
