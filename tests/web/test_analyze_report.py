# SPDX-License-Identifier: Apache-2.0
# The page `impulse analyze --report` writes, in headless chromium: 12 frames of the built-in
# drift scene, analysed with its theory, give all 9 plots; the page, opened from the file with
# nothing served, draws every plot with the Vega it inlines (design.md §6, "The report's plots
# drawn by Vega"), with marks in each, log axes on the radial spectrum, a value on hover and a
# zoom with the wheel on each, and no JavaScript error. The control: the same report with its
# inlined vega-view module replaced by a comment is caught by the same checks.
# Shown able to fail, by hand: with an empty library inlined, linear scales for log ones, the
# wheel's zoom factor held at 1, empty tooltips, or a drag's pan turned round, the test of that
# mechanism fails. ~30 s on the 2-core machine under load (~5 s of it the tool, the rest chromium).
# Run by CTest (analyze_report_page) with IMPULSE_CLI set; exits 77 (skipped, with the reason)
# without chromium or Debian's libjs-vega.
import math
import os
import pathlib
import subprocess

import pytest

import devtools  # tests/web/devtools.py
from devtools import Browser, impulse_cli, no_chromium

# The folder the tool reads Vega from unless the environment names another (analysis/
# CMakeLists.txt: IMPULSE_VEGA_DIR).
VEGA_DIR = pathlib.Path(os.environ.get("IMPULSE_VEGA_DIR") or "/usr/share/javascript/vega")

PLOTS = 9  # histogram, 2-D periodogram, spectrum, spectrum z, autocovariance, 3 per frame, drift
SPECTRUM = 2  # the radially averaged power spectrum, the plot on log axes


def prerequisites():
    """The reason the test cannot run here, or None."""
    if no_chromium():
        return no_chromium()
    if not (VEGA_DIR / "vega-view.min.js").is_file():
        return f"Vega is not installed ({VEGA_DIR}/vega-view.min.js: scripts/setup.sh installs libjs-vega)"
    return None


if prerequisites() and __name__ != "__main__":
    pytest.skip(prerequisites(), allow_module_level=True)


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    cli = impulse_cli()
    folder = tmp_path_factory.mktemp("report")

    def run(*args):
        done = subprocess.run([cli, *args], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr

    # The built-in drift scene, small: its theory has a spectrum, and 12 frames (>= 10) have a
    # stationarity verdict, so the report has all its plots.
    run("render", "drift", "-q", "--size", "96x96", "--frames", "0-11", "-o", str(folder / "f_####.exr"))
    frames = str(folder / "f_####.exr")
    run("analyze", frames, "--scene", "drift", "--report", str(folder / "report.html"))
    # The control: the same page with the inlined vega-view (View, which draws) replaced.
    page = (folder / "report.html").read_text()
    start = page.index("impulseModule = 'vega-view';\n")
    end = page.index("impulseModule = 'vega-parser';\n")
    (folder / "broken.html").write_text(page[:start] + "/* not Vega's view */\n" + page[end:])
    return folder


@pytest.fixture(scope="module")
def browser(work):
    b = Browser(work / "profile", size=(1400, 1000))
    # Uncaught exceptions, console errors and the browser's own error log come in as events.
    b.page("Runtime.enable")
    b.page("Log.enable")
    yield b
    b.close()


def errors(browser):
    """The JavaScript errors reported since the last call."""
    browser.evaluate("0")  # the events sent so far have reached the pipe
    found = []
    for e in browser.events:
        p = e.get("params", {})
        if e["method"] == "Runtime.exceptionThrown":
            found.append(p["exceptionDetails"].get("exception", {}).get("description") or p["exceptionDetails"]["text"])
        elif e["method"] == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            found.append(" ".join(str(a.get("value", a.get("description"))) for a in p["args"]))
        elif e["method"] == "Log.entryAdded" and p["entry"]["level"] == "error":
            found.append(p["entry"]["text"])
    browser.events.clear()
    return found


# The drawn marks of each figure: SVG paths with a drawing in their `d` (symbols, lines, areas,
# bars and the heat map's cells; Vega draws rules as <line>), the figures' titles, and per figure
# the x and y scales' type and where they put three values a decade apart.
MARKS = """Array.from(document.querySelectorAll('figure.plot')).map((f, i) => {
  const v = window.impulseViews[i];
  const drawn = f.querySelectorAll('g.mark-symbol path, g.mark-line path, g.mark-area path, g.mark-rect path');
  return {
    title: (f.querySelector('g.mark-text.role-title-text text') || {}).textContent || '',
    marks: Array.from(drawn).filter((p) => /[0-9]/.test(p.getAttribute('d') || '')).length,
    x: v.scale('x').type, y: v.scale('y').type,
    decades: [0.01, 0.1, 1].map((k) => v.scale('x')(k))
  };
})"""


def check_page(browser, url):
    """What is wrong with the report at `url`: a list of lines, empty when it is all right."""
    state = browser.open(url)
    wrong = [f"page error: {state['error']}"] if state.get("error") else []
    wrong += [f"JavaScript error: {e}" for e in errors(browser)]
    if wrong:
        return wrong
    plots = browser.evaluate(MARKS)
    if len(plots) != PLOTS:
        return [f"{len(plots)} plots drawn, expected {PLOTS}"]
    for i, p in enumerate(plots):
        print(f"plot {i}: {p['title']!r}: {p['marks']} marks drawn, x {p['x']}, y {p['y']}")
        # Something drawn under a title: a series' points or bars (one path each) or its line.
        if p["marks"] < 1 or not p["title"]:
            wrong.append(f"plot {i} ({p['title']!r}): {p['marks']} marks drawn")
        log = i == SPECTRUM
        if (p["x"], p["y"]) != (("log", "log") if log else ("linear", "linear")):
            wrong.append(f"plot {i} ({p['title']!r}): scales {p['x']}, {p['y']}")
    # On the log axis a decade is the same length everywhere (to rounding to the pixel's 1/100).
    a, b, c = plots[SPECTRUM]["decades"]
    print(f"spectrum's x axis: 0.01, 0.1, 1 at {a:.2f}, {b:.2f}, {c:.2f} px")
    if abs((b - a) - (c - b)) > 0.01:
        wrong.append(f"the spectrum's x axis is not logarithmic: decades of {b - a:.2f} and {c - b:.2f} px")
    return wrong


def test_every_plot_is_drawn_with_log_axes_on_the_spectrum(work, browser):
    wrong = check_page(browser, (work / "report.html").as_uri())
    browser.screenshot(work / "report.png")
    assert not wrong, "\n".join(wrong)
    # The heat map's cells (not its legend's gradient): the 96x96 frames' periodogram in 2x2
    # blocks (analysis/analyze.cpp).
    heat = browser.evaluate("document.querySelectorAll('figure.plot')[1]"
                            ".querySelectorAll('g.mark-rect.role-mark path').length")
    assert heat == 48 * 48


def test_hover_shows_the_values(work, browser):
    # A window a plot wide, so the tip of the last point has no room on its right.
    browser.open((work / "report.html").as_uri(), size=(700, 900))
    # The first and the last measured point of the radial spectrum, under the pointer: the tip
    # shows the values beside it, inside the window (turned left at the right edge).
    for which in ("first", "last"):
        at = browser.evaluate("""(() => {
          const f = document.querySelectorAll('figure.plot')[%d];
          f.scrollIntoView();
          const points = f.querySelectorAll('g.mark-symbol.role-mark path');  // not the legend's
          const s = points[%s].getBoundingClientRect();
          return [s.x + s.width / 2, s.y + s.height / 2];
        })()""" % (SPECTRUM, "0" if which == "first" else "points.length - 1"))
        browser.page("Input.dispatchMouseEvent", type="mouseMoved", x=at[0], y=at[1])
        text, display, box, width = browser.evaluate(
            "(() => { const t = document.querySelector('div.tip'); const r = t.getBoundingClientRect(); "
            "return [t.textContent, getComputedStyle(t).display, [r.left, r.top, r.right, r.bottom], "
            "window.innerWidth]; })()")
        print(f"hover over the spectrum's {which} point at ({at[0]:.0f}, {at[1]:.0f}): {text!r} in {box}")
        # The last point lies under the theory's line, drawn over it.
        assert display == "block" and text.split("\n")[0] in ("series: measured (12 frames)", "series: theory")
        assert "frequency |k| (cycles/pixel): " in text and "power (value^2 pixel^2): " in text
        assert 0 <= box[0] and box[2] <= width
        # 14 px from the pointer on each axis, on one side or the other.
        assert min(abs(box[0] - at[0] - 14), abs(at[0] - box[2] - 14)) < 1
        assert min(abs(box[1] - at[1] - 14), abs(at[1] - box[3] - 14)) < 1
    # Off the marks, it goes.
    browser.page("Input.dispatchMouseEvent", type="mouseMoved", x=5, y=5)
    assert browser.evaluate("getComputedStyle(document.querySelector('div.tip')).display") == "none"
    assert not errors(browser)


def test_the_wheel_zooms_every_plot(work, browser):
    browser.open((work / "report.html").as_uri())
    for i in range(PLOTS):
        before = browser.evaluate(f"window.impulseViews[{i}].signal('xdom')")
        at = browser.evaluate(f"""(() => {{
          const f = document.querySelectorAll('figure.plot')[{i}];
          f.scrollIntoView();
          const r = f.querySelector('.chart svg').getBoundingClientRect();
          return [r.x + r.width / 2, r.y + r.height / 2];
        }})()""")
        # Wheel away from the reader: zoom in, about the pointer (zoom = 1.001^-480 = 0.62).
        browser.page("Input.dispatchMouseEvent", type="mouseWheel", x=at[0], y=at[1], deltaX=0, deltaY=-480)
        browser.evaluate(f"window.impulseViews[{i}].runAsync().then(() => 0)")
        after = browser.evaluate(f"window.impulseViews[{i}].signal('xdom')")
        ratio = (after[1] - after[0]) / (before[1] - before[0])
        if i == SPECTRUM:  # zoomed in log10 |k|
            ratio = math.log(after[1] / after[0]) / math.log(before[1] / before[0])
        print(f"plot {i}: x from {before} to {after}: span x {ratio:.3f}")
        assert abs(ratio - 1.001 ** -480) < 1e-6, (i, before, after)
    assert not errors(browser)


def test_a_drag_pans_and_a_double_click_goes_back(work, browser):
    browser.open((work / "report.html").as_uri())
    box = browser.evaluate("""(() => {
      const f = document.querySelectorAll('figure.plot')[0];
      f.scrollIntoView();
      const r = f.querySelector('.chart svg').getBoundingClientRect();
      return [r.x + r.width / 2, r.y + r.height / 2];
    })()""")
    home, width = browser.evaluate("[window.impulseViews[0].signal('xdom'), window.impulseViews[0].width()]")
    x, y = box
    mouse = dict(button="left", clickCount=1)
    browser.page("Input.dispatchMouseEvent", type="mousePressed", x=x, y=y, **mouse)
    browser.page("Input.dispatchMouseEvent", type="mouseMoved", x=x + 100, y=y, buttons=1)
    browser.page("Input.dispatchMouseEvent", type="mouseReleased", x=x + 100, y=y, **mouse)
    moved = browser.evaluate("window.impulseViews[0].runAsync().then((v) => v.signal('xdom'))")
    # 100 px to the right: the view shows what was 100 px to the left, 100 / width of the span.
    shift = (moved[0] - home[0]) / (home[1] - home[0])
    print(f"histogram: x from {home} to {moved} after a 100 px drag: {shift:.4f} of the span, plot {width} px")
    assert abs(shift + 100 / width) < 1e-9 and abs((moved[1] - moved[0]) - (home[1] - home[0])) < 1e-9
    for kind in ("mousePressed", "mouseReleased"):
        browser.page("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", clickCount=2)
    back = browser.evaluate("window.impulseViews[0].runAsync().then((v) => v.signal('xdom'))")
    assert back == home
    assert not errors(browser)


def test_a_broken_library_is_caught(work, browser):
    # The control: the same checks on the page whose vega-view was replaced.
    wrong = check_page(browser, (work / "broken.html").as_uri())
    print("broken library: " + "; ".join(wrong))
    assert wrong


if __name__ == "__main__":
    devtools.main(__file__, prerequisites())
