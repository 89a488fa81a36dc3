# SPDX-License-Identifier: Apache-2.0
# The flipbook page (web/flipbook/, docs/export.md "The flipbook page") in headless chromium: a looping,
# tileable PNG atlas from the built tool, served on 127.0.0.1, held at a frame and screenshotted
# with the plane filling the window at one texel per pixel, repeated 3x3. The page shows cell N
# for frame N; the steps across the tile borders are among the steps inside the tiles; and two
# controls show the same measure finds a seam where there is one: an atlas exported without a
# period, and the page's sampling without the cell inset (`sampling=naive`), which bleeds the
# neighbouring cells across the border. Run by CTest (flipbook_page) with IMPULSE_CLI set; exits
# 77 (skipped, with the reason) without chromium or the page's npm package. ~17 s on the 2-core
# machine with another build running (most of it chromium's start and its first WebGL page).
import http.server
import json
import pathlib
import struct
import subprocess
import threading
import time
import urllib.parse
import zlib

import pytest

import devtools  # tests/web/devtools.py
from devtools import Browser, impulse_cli, no_chromium

PAGE_DIR = pathlib.Path(__file__).resolve().parents[2] / "web" / "flipbook"
THREE = PAGE_DIR / "node_modules" / "three" / "build" / "three.module.js"
W, H, REPEAT = 96, 64, 3  # one cell; the plane shows 3x3 of them, one texel per pixel
FRAMES, COLUMNS = 24, 5  # loop = 2 s at 12 fps: a 5x5 atlas
HELD = 12  # cell (2, 2): every side has a neighbouring cell, which the naive sampling bleeds in

# The page's example scene: tileable and looping, with neighbouring cells that differ (so a
# bleed from them is a seam); the control drops its period.
SCENE = PAGE_DIR / "example.toml"
PERIOD_LINE = "period = [96, 64]\n"

# The seam criterion. Each line between neighbouring pixel columns (rows) gets its mean |step|
# over the picture's height (width); the lines are grouped by their place in the tile (line j
# in class j mod W). The field is stationary and, on a tileable atlas, periodic with the tile,
# so a border class's mean step is one more draw from the distribution of the inside classes'
# means, whose spread is the standard error of one line's mean, measured (so it includes the
# field's correlation along the line). A border class passes when its mean lies below the
# inside means' mean + K of their standard deviations: by Cantelli's inequality an honest border
# exceeds that with probability < 1 / (1 + K^2) = 1/26 for any distribution (< 4/26 for the
# worst of the up to 4 border classes), ~3e-7 each were the line means normal (each averages
# 64 or 96 distinct pixels, 4 to 6 diameters of the radius-8 kernel). The seed is fixed; the
# tileable atlas measures z < 0.6 and the two seams z = 12.8 and 24.6
# (docs/export.md "The flipbook page").
K = 5.0


def prerequisites():
    """The reason the test cannot run here, or None."""
    if no_chromium():
        return no_chromium()
    if not THREE.is_file():
        return "three.js is not installed in web/flipbook/node_modules (scripts/setup.sh --tests runs npm ci there)"
    return None


if prerequisites() and __name__ != "__main__":
    pytest.skip(prerequisites(), allow_module_level=True)


# ---- a PNG reader (8-bit grey/RGB/RGBA, non-interlaced: what chromium and the tool write) ----

def _unfilter(raw, width, height, bpp):
    stride = width * bpp
    rows, prev, at = [], bytearray(stride), 0
    for _ in range(height):
        kind, line = raw[at], bytearray(raw[at + 1:at + 1 + stride])
        at += 1 + stride
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if kind == 1:
                line[i] = (line[i] + a) & 255
            elif kind == 2:
                line[i] = (line[i] + b) & 255
            elif kind == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif kind == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line)
        prev = line
    return rows


def read_png_grey(path):
    """The first channel of an 8-bit PNG as rows of ints, and whether all colour channels agree."""
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    at, idat, header = 8, b"", None
    while at < len(data):
        length, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert depth == 8 and interlace == 0 and colour in (0, 2, 6), f"{path}: unexpected PNG {header}"
    bpp = {0: 1, 2: 3, 6: 4}[colour]
    rows = _unfilter(zlib.decompress(idat), width, height, bpp)
    grey = all(r[i] == r[i + 1] == r[i + 2] for r in rows for i in range(0, len(r), bpp)) if bpp > 1 else True
    return [list(r[0::bpp]) for r in rows], grey


# ---- the measure ----

def mean(values):
    return sum(values) / len(values)


def sd(values):
    m = mean(values)
    return (sum((v - m) ** 2 for v in values) / (len(values) - 1)) ** 0.5


def column_line_means(image, period):
    """Mean |step| between columns j and j + 1, averaged over the rows and over the lines of the
    same class j mod period: one mean per class, indexed by the class."""
    sums, counts = [0.0] * period, [0] * period
    for row in image:
        for j in range(len(row) - 1):
            sums[j % period] += abs(row[j + 1] - row[j])
            counts[j % period] += 1
    return [s / n for s, n in zip(sums, counts)]


def transpose(image):
    return [list(column) for column in zip(*image)]


def border_z(line_means, border_classes):
    """How many standard deviations of the inside classes' means each border class lies above
    their mean."""
    inside = [m for c, m in enumerate(line_means) if c not in border_classes]
    return [(line_means[c] - mean(inside)) / sd(inside) for c in border_classes]


def border_classes(period, offset):
    """The lines touching the tile's edge. At offset 0 pixel centres sit on texel centres and the
    edge lies between pixels period - 1 and period (class period - 1); at offset 0.5 pixel
    period - 1 is centred on the edge, and both its lines touch it."""
    return [period - 1] if offset == 0 else [period - 2, period - 1]


def seam_z(image, offset, what):
    """The worst border z over the columns and the rows; prints the line means it compares."""
    worst = -1e9
    for axis, picture, period in (("columns", image, W), ("rows", transpose(image), H)):
        means, borders = column_line_means(picture, period), border_classes(period, offset)
        inside = [m for c, m in enumerate(means) if c not in borders]
        worst = max([worst] + border_z(means, borders))
        print(f"{what}, {axis}: border lines' mean |step| " + ", ".join(f"{means[c]:.2f}" for c in borders) +
              f" codes; inside lines {mean(inside):.2f} +- {sd(inside):.2f}")
    print(f"{what}: worst border z = {worst:.2f} (K = {K})")
    return worst


def cell_of(atlas, index):
    x0, y0 = index % COLUMNS * W, index // COLUMNS * H
    return [row[x0:x0 + W] for row in atlas[y0:y0 + H]]


def variance(image):
    return sd([v for row in image for v in row]) ** 2


# ---- the machinery: the tool, the server, the browser ----

@pytest.fixture(scope="module")
def work(tmp_path_factory):
    cli = impulse_cli()
    folder = tmp_path_factory.mktemp("flipbook")
    text = SCENE.read_text()
    assert PERIOD_LINE in text
    (folder / "tile.toml").write_text(text)
    (folder / "free.toml").write_text(text.replace(PERIOD_LINE, ""))
    for name, flags in (("tile", ["--loop", "--tileable"]), ("free", ["--loop"])):
        run = subprocess.run([cli, "export", "flipbook", str(folder / f"{name}.toml"), *flags,
                              "-o", str(folder / f"{name}.png")], capture_output=True, text=True, timeout=60)
        assert run.returncode == 0, run.stderr
    return folder


class Handler(http.server.SimpleHTTPRequestHandler):
    """/page/... is web/flipbook, /data/... the test's folder."""
    data_dir = None

    def translate_path(self, path):
        path = urllib.parse.unquote(urllib.parse.urlsplit(path).path)
        for prefix, root in (("/page/", PAGE_DIR), ("/data/", self.data_dir)):
            if path.startswith(prefix):
                target = (root / path[len(prefix):]).resolve()
                if target == root.resolve() or root.resolve() in target.parents:
                    return str(target)
        return "/nonexistent"

    def log_message(self, *args):
        pass


@pytest.fixture(scope="module")
def server(work):
    handler = type("BoundHandler", (Handler,), {"data_dir": work})
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)  # a free port
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()
    thread.join(timeout=10)


@pytest.fixture(scope="module")
def browser(work):
    b = Browser(work / "profile", size=(REPEAT * W, REPEAT * H))
    yield b
    b.close()


def screenshot(browser, server, folder, name, sidecar, frame, sampling, extra=""):
    """The page's pixels (first channel) holding `frame` of `sidecar` in a 3W x 3H viewport,
    drawn with `sampling` (the page's default for the atlas unless `extra` sets it), and the
    PNG kept in the test's folder."""
    query = f"sidecar=/data/{sidecar}&frame={frame}{extra}"
    state = browser.open(f"{server}/page/index.html?{query}")
    assert state.get("error") == "", f"{query}: {state.get('error')}"
    assert (state.get("frame"), state.get("sampling")) == (str(frame), sampling), state
    out = folder / f"{name}.png"
    browser.screenshot(out)
    pixels, grey = read_png_grey(out)
    assert len(pixels) == REPEAT * H and len(pixels[0]) == REPEAT * W, f"{name}: {len(pixels[0])}x{len(pixels)}"
    assert grey, f"{name}: the atlas is grey but the screenshot is not"
    return pixels


# ---- the tests ----

def test_the_page_shows_cell_n_for_frame_n(work, server, browser):
    atlas, _ = read_png_grey(work / "tile.png")
    sidecar = json.loads((work / "tile.json").read_text())
    assert sidecar["layout"] == {"rows": 5, "columns": 5, "order": "row-major from the top-left"}
    for frame in (HELD, FRAMES - 1):
        shot = screenshot(browser, server, work, f"frame{frame}", "tile.json", frame, "wrap")
        cell = cell_of(atlas, frame)
        # One texel per pixel, centres on centres: every pixel is its texel, within the 8-bit
        # rounding of the bilinear weights (0 or 1 up to float error).
        worst = max(abs(shot[y][x] - cell[y % H][x % W]) for y in range(REPEAT * H) for x in range(REPEAT * W))
        print(f"frame {frame}: largest |screen - cell| = {worst} codes")
        assert worst <= 1
        # Not blank, and not another cell: the cell varies (the PNG maps the mean +- 3 sd to
        # 0..255, a variance near (255 / 6)^2 ~ 1800 codes^2; a flat cell has 0), and the cell
        # before it differs from it by far more than the rounding allowed above.
        assert variance(cell) > 100
        other = cell_of(atlas, frame - 1)
        assert max(abs(a - b) for ra, rb in zip(cell, other) for a, b in zip(ra, rb)) > 20


def test_no_seam_at_the_tile_borders(work, server, browser):
    atlas, _ = read_png_grey(work / "tile.png")
    # The page's sampling of a tileable atlas, with pixel centres on texel centres and half a
    # texel off them; and the half-texel clamp, which guards the page's choice of no mipmaps:
    # with them the wrapped coordinate's jump inside a 2x2 pixel quad picks the coarsest level
    # along the border (measured z = 6.11 with mipmaps, 1.48 without).
    for offset, sampling in ((0, "wrap"), (0.5, "wrap"), (0.5, "clamp")):
        shot = screenshot(browser, server, work, f"tile{offset}{sampling}", "tile.json", HELD, sampling,
                          f"&offset={offset}&sampling={sampling}")
        # Drawn: the half-texel offset averages 2x2 texels, which keeps most of the variance of a
        # field whose kernel has a radius of 8 texels (measured: 1.000 at offset 0, 0.972 at 0.5);
        # a blank or constant page has none.
        ratio = variance(shot) / variance(cell_of(atlas, HELD))
        print(f"tileable atlas, {sampling}, offset {offset}: variance on screen / in the cell = {ratio:.3f}")
        assert ratio > 0.5
        assert seam_z(shot, offset, f"tileable atlas, {sampling}, offset {offset}") < K


def test_a_seam_is_found_without_a_period(work, server, browser):
    # Control: the same scene without `period`: a cell's opposite edges don't meet.
    shot = screenshot(browser, server, work, "free", "free.json", HELD, "clamp")
    assert seam_z(shot, 0, "atlas without a period") > K


def test_a_seam_is_found_without_the_cell_inset(work, server, browser):
    # Control: hardware bilinear over the cell's full extent bleeds the neighbouring cells (other
    # frames) into the border pixels once pixel centres are off the texel centres.
    shot = screenshot(browser, server, work, "naive", "tile.json", HELD, "naive", "&offset=0.5&sampling=naive")
    assert seam_z(shot, 0.5, "naive sampling, offset 0.5") > K


def test_it_plays_at_the_sidecars_fps(work, server, browser):
    first = browser.open(f"{server}/page/index.html?sidecar=/data/tile.json")
    assert first["error"] == "" and first["sampling"] == "wrap" and first["frames"] == str(FRAMES)
    time.sleep(0.5)
    second = browser.evaluate("Object.assign({}, document.body.dataset)")
    # Frame i is shown during [i, i + 1) / fps of the page's clock, the sidecar's 12 fps.
    for state in (first, second):
        assert int(state["frame"]) == int(float(state["time"]) * 12) % FRAMES, state
    assert float(second["time"]) > float(first["time"]) + 0.25, "the page does not play"
    print(f"playing: frame {first['frame']} at {float(first['time']):.3f} s, {second['frame']} at {float(second['time']):.3f} s")
    # Past the last frame it starts over (the loop; 24 frames at 60 fps last 0.4 s).
    browser.open(f"{server}/page/index.html?sidecar=/data/tile.json&fps=60")
    time.sleep(0.6)
    state = browser.evaluate("Object.assign({}, document.body.dataset)")
    assert float(state["time"]) > FRAMES / 60 and int(state["frame"]) == int(float(state["time"]) * 60) % FRAMES, state


def test_bad_input_is_one_line(work, server, browser):
    base = f"{server}/page/index.html?"
    sidecar = json.loads((work / "tile.json").read_text())
    (work / "exr.json").write_text(json.dumps(dict(sidecar, image="tile.exr")))
    (work / "short.json").write_text(json.dumps(dict(sidecar, frames=26)))
    cases = {
        "sidecar=/data/tile.json&frame=24": "?frame=24: expected a whole number in [0, 23]",
        "sidecar=/data/tile.json&sampling=nearest": "?sampling=nearest: expected one of wrap, clamp, naive",
        "sidecar=/data/none.json": f"{server}/data/none.json: HTTP 404",
        "sidecar=/data/tile.toml": "/data/tile.toml: not JSON",
        "sidecar=/data/tile.json&image=free.png": "",  # the same size: accepted
        "sidecar=/data/tile.json&image=tile.toml": f"{server}/data/tile.toml: cannot load the image",
        "sidecar=/data/exr.json": '/data/exr.json: image = "tile.exr": expected a PNG atlas',
        "sidecar=/data/short.json": "/data/short.json: frames = 26: expected at most layout.rows x layout.columns = 25",
        "sidecar=/data/tile.json&image=frame12.png": "/data/frame12.png: 288x192 pixels: expected 5x5 cells of 96x64 = 480x320",
        "": "no ?sidecar=URL: give the flipbook's JSON sidecar, e.g. ?sidecar=atlas.json",
    }
    for query, message in cases.items():
        state = browser.open(base + query)
        assert state["error"].startswith(message), (query, state["error"])
        assert "\n" not in state["error"]


if __name__ == "__main__":
    devtools.main(__file__, prerequisites())
