# SPDX-License-Identifier: Apache-2.0
# Run by blender/test_mantaflow.sh after blender/bake_mantaflow.py baked TMP/cache:
#   python3 test_mantaflow.py TMP IMPULSE_CLI CONFTEST_DIR
# 1. Units: the smoke's density moves between the cache's frames by the stored velocity times
#    Mantaflow's frame length, 0.1 (25 / fps) time units (docs/scenes.md "A Blender cache").
# 2. A texture rendered on the vertical slice y = 0 of the cache, mapped as that section says,
#    moves between consecutive frames as Blender's own velocity grid says, window by window,
#    within a band derived below; with the velocity scale doubled, or the frames read 6 late, it
#    does not.
#    analyze --scene finds the texture stationary with sqrt(J) and its variance Campbell's
#    (and not across the jump outside = "zero" makes at the cache box's edge); jacobian = false
#    is refused in one line.
# 3. A volume scene carried by the same cache renders to OpenVDB frames.
# The seeds, frame pairs and windows are fixed.
import json
import os
import subprocess
import sys

import numpy as np

tmp, cli, conftest_dir = sys.argv[1:4]
sys.path.insert(0, conftest_dir)
from conftest import read_fits  # noqa: E402

cache = os.path.join(tmp, "cache")
velocity = np.load(os.path.join(cache, "blender_velocity.npy"))  # frames, z, y, x, 3
density = np.load(os.path.join(cache, "blender_density.npy"))    # frames, z, y, x
frames, nz, ny, nx, _ = velocity.shape
FPS = 24.0
DOMAIN_MIN, DOMAIN = -1.0, 2.0    # the domain cube of bake_mantaflow.py, Blender units
CELL = DOMAIN / max(nx, ny, nz)   # Blender units per voxel
# Mantaflow's time: a frame is 0.1 (25 / fps) time_scale of its units, and velocities are in
# voxels per unit (Blender's fluid.cc, frame_length)
FRAME_LENGTH = 0.1 * 25.0 / FPS
PX = 64.0                         # pixels (texture units) per Blender unit
SIZE = int(PX * DOMAIN)           # the picture covers the domain's x-z square
VOXEL_PX = CELL * PX              # pixels per voxel


def fail(message):
    print("FAIL:", message)
    sys.exit(1)


# ---------------------------------------------------------------------------------------------
# 1. Units from the smoke itself. Mantaflow's step carries frame n's density to frame n + 1
#    with frame n's velocity (semi-Lagrangian: rho(n+1, x) = rho(n, x - k v(n, x)), k the
#    frame's length in the velocity's units): the k whose trilinear back-trace best predicts
#    frame n + 1 from frame n over the plume (voxels away from the inflow, frames 4-18, before
#    the plume meets the domain's top; every other pair), scanned in steps of 0.0025. The model leaves out the
#    scheme's own error correction (MacCormack), its substeps and the buoyancy added within the
#    step, so the band is 10 %: 0.9 .. 1.1 x FRAME_LENGTH. Other readings of the units are far
#    outside: voxels per frame (k = 1), Blender units per second (1 / (CELL FPS) = 0.67),
#    voxels per second (1 / FPS = 0.042).

def centred(v):
    """A MAC grid's face components (component c on the face below the voxel along c) averaged
    to the voxel centres, the last voxel along c keeping its face value (as impulse does)."""
    out = v.copy()
    for c, axis in ((0, 2), (1, 1), (2, 0)):
        comp = v[..., c]
        upper = np.concatenate([np.take(comp, range(1, comp.shape[axis]), axis=axis),
                                np.take(comp, [comp.shape[axis] - 1], axis=axis)], axis=axis)
        out[..., c] = 0.5 * (comp + upper)
    return out


def trilinear(g, z, y, x):
    """g at fractional voxel indices, clamped to the grid."""
    z, y, x = np.clip(z, 0, nz - 1), np.clip(y, 0, ny - 1), np.clip(x, 0, nx - 1)
    z0, y0, x0 = (np.minimum(c.astype(int), m - 2) for c, m in ((z, nz), (y, ny), (x, nx)))
    fz, fy, fx = z - z0, y - y0, x - x0
    out = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                w = (fz if dz else 1 - fz) * (fy if dy else 1 - fy) * (fx if dx else 1 - fx)
                out = out + w * g[z0 + dz, y0 + dy, x0 + dx]
    return out


zz, yy, xx = np.meshgrid(np.arange(nz), np.arange(ny), np.arange(nx), indexing="ij")
inflow = ((xx + 0.5) * CELL + DOMAIN_MIN + 0.35) ** 2 + ((yy + 0.5) * CELL + DOMAIN_MIN) ** 2 + \
    ((zz + 0.5) * CELL + DOMAIN_MIN + 0.6) ** 2 < (0.25 + 3 * CELL) ** 2
ks = np.arange(0.07, 0.14, 0.0025)
residual = np.zeros_like(ks)
for n in range(3, 18, 2):   # Blender frames n + 1 -> n + 2
    v = centred(velocity[n])
    use = (np.maximum(density[n], density[n + 1]) > 0.05) & ~inflow
    for i, k in enumerate(ks):
        predicted = trilinear(density[n], zz - k * v[..., 2], yy - k * v[..., 1], xx - k * v[..., 0])
        residual[i] += np.sum((density[n + 1] - predicted)[use] ** 2)
still = sum(np.sum((density[n + 1] - density[n])[(np.maximum(density[n], density[n + 1]) > 0.05) & ~inflow] ** 2)
            for n in range(3, 18, 2))
k = ks[np.argmin(residual)]
print(f"units: the smoke moves {k:.4f} voxels a frame per stored unit (residual "
      f"{residual.min() / still:.3f} of the still prediction's); Mantaflow's frame length "
      f"{FRAME_LENGTH:.4f}, ratio {k / FRAME_LENGTH:.3f} (band 0.9 .. 1.1)")
if not 0.9 <= k / FRAME_LENGTH <= 1.1:
    fail("the stored velocity is not in voxels per Mantaflow time unit")

# ---------------------------------------------------------------------------------------------
# 2. The texture's motion.
# The cache's VDB transform is the voxel size alone: index i at i CELL, where Blender's voxel
# centre is DOMAIN_MIN + (i + 1/2) CELL. The plane y = 0 (Blender's front view, x right, z up);
# texture x = PX x_blender + SIZE / 2, texture y = -PX z_blender + SIZE / 2 (rows run down).
SHIFT = DOMAIN_MIN + 0.5 * CELL   # Blender world minus VDB world
VELOCITY_SCALE = FRAME_LENGTH * FPS * CELL   # stored units -> Blender units per second


def sequence_flow(velocity_scale=VELOCITY_SCALE, start=0, volume=False, outside="clamp"):
    """The flow table of docs/scenes.md "A Blender cache": impulse frame n reads Blender frame
    n (start = 0, the frame before the first held), velocities in Blender units per second,
    the field beyond the cache's box continuous (clamp: "zero" jumps there, which sqrt(J)
    cannot see)."""
    common = f"""type = "sequence"
path = "cache/data/fluid_data_####.vdb"
fps = {FPS}
start = {start}
velocity_scale = {velocity_scale}
outside = "{outside}"
"""
    if volume:
        # voxels of the volume = the domain's: X = world / CELL + 1/2 (voxel centres at i + 1/2)
        return f"[[volume.flow]]\n{common}scale = {1 / CELL}\noffset = [0.5, 0.5, 0.5]\n"
    return f"""[[layer.flow]]
{common}scale = [{PX}, {-PX}]
offset = [{PX * SHIFT + SIZE / 2}, {-PX * SHIFT + SIZE / 2}]
plane = "slice"
axis = "y"
height = {-SHIFT}
"""


def texture_scene(flow, jacobian=True, count=frames):
    # Small Gaussian impulses (sigma 1.5 px) alive 0.5 s (12 frames; longer lives stretch
    # further in the rising plume, which sqrt(J) makes few and bright), dense enough to cover
    # the picture: detail in the windows for the cross-correlation to lock onto.
    return f"""[output]
size = [{SIZE}, {SIZE}]
frames = {count}
fps = {FPS}
[[layer]]
seed = 7
density = 16.0
amplitude = "normal"
lifetime = 0.5
substeps = 4
jacobian = {str(jacobian).lower()}
[layer.kernel]
type = "gaussian"
sigma = 1.5
radius = 5.6
""" + flow


def write_scene(name, text):
    path = os.path.join(tmp, name + ".toml")
    with open(path, "w") as f:
        f.write(text)
    return path


def render_frames(name, text, first, last):
    """Frames first..last of a scene, as float arrays (rows top first)."""
    out = os.path.join(tmp, name)
    os.makedirs(out, exist_ok=True)
    subprocess.run([cli, "render", write_scene(name, text), "-o", os.path.join(out, "f_####.exr"),
                    "--frames", f"{first}-{last}", "-q"], check=True)
    subprocess.run(["oiiotool", "--frames", f"{first}-{last}", os.path.join(out, "f_#.exr"), "--ch", "0",
                    "-d", "float", "-o", os.path.join(out, "f_#.fits")], check=True)
    return [read_fits(os.path.join(out, f"f_{n:04d}.fits")) for n in range(first, last + 1)]


def plane_motion(n):
    """Blender's velocity of frame n (1-based) on the slice y = 0 (between voxel layers
    ny/2 - 1 and ny/2) as the picture's motion in pixels per frame, (right, down), and where
    the VDB holds it (active: smoke in both layers), rows from the top (z high) down."""
    v = centred(velocity[n - 1])
    mid = 0.5 * (v[:, ny // 2 - 1] + v[:, ny // 2])
    active = (density[n - 1][:, ny // 2 - 1] > 0) & (density[n - 1][:, ny // 2] > 0)
    scale = FRAME_LENGTH * VOXEL_PX
    return (mid[..., 0] * scale)[::-1], (-mid[..., 2] * scale)[::-1], active[::-1]


def shift(a, b, r0, c0, size, reach):
    """The displacement (right, down) in pixels carrying a's window at (r0, c0) onto b: the
    normalised cross-correlation's peak over integer shifts within reach, refined by a parabola
    through the peak and its neighbours along each axis; and the peak's correlation."""
    patch = a[r0:r0 + size, c0:c0 + size]
    patch = (patch - patch.mean()) / patch.std()
    region = np.pad(b, reach, mode="edge")[r0:r0 + size + 2 * reach, c0:c0 + size + 2 * reach]
    # sum(patch * window) for every shift by FFT (patch has mean 0, so the window's mean
    # drops out), the windows' standard deviations from summed-area tables
    cross = np.fft.irfft2(np.fft.rfft2(region) * np.conj(np.fft.rfft2(patch, region.shape)),
                          region.shape)[:2 * reach + 1, :2 * reach + 1]

    def window_sums(x):
        c = np.pad(np.cumsum(np.cumsum(x, 0), 1), ((1, 0), (1, 0)))
        return c[size:, size:] - c[:-size, size:] - c[size:, :-size] + c[:-size, :-size]

    n = size * size
    var = window_sums(region ** 2) / n - (window_sums(region) / n) ** 2
    scores = cross / (n * np.sqrt(np.maximum(var, 1e-30)))
    i, j = np.unravel_index(np.argmax(scores), scores.shape)

    def vertex(m, c, p):
        d = m - 2 * c + p
        return 0.0 if d >= 0 else 0.5 * (m - p) / d

    di = vertex(*scores[i - 1:i + 2, j]) if 0 < i < 2 * reach else 0.0
    dj = vertex(*scores[i, j - 1:j + 2]) if 0 < j < 2 * reach else 0.0
    return j - reach + dj, i - reach + di, scores[i, j]


WINDOW = 24         # pixels (6 voxels)
STEP = 8
REACH = 16          # pixels a frame: above the fastest motion on the plane over the run (15)
RESOLUTION = 0.5    # px: half the correlation's integer step (the parabola only refines it)
# A window the texture does not carry recognisably to the next frame (sheared or renewed
# within the frame: the plume's core moves 5-15 px a frame with a spread of several px across
# 16 px) has no displacement to measure: windows whose correlation peak is below this are left
# out (a standard validity test of block matching, on the images alone, not on the truth).
MIN_PEAK = 0.6


def bilinear(g, rows, cols):
    """A plane grid (voxel centres at pixel ((j + 1/2), (i + 1/2)) VOXEL_PX) at pixel points."""
    r = np.clip(rows / VOXEL_PX - 0.5, 0, g.shape[0] - 1)
    c = np.clip(cols / VOXEL_PX - 0.5, 0, g.shape[1] - 1)
    r0, c0 = np.minimum(r.astype(int), g.shape[0] - 2), np.minimum(c.astype(int), g.shape[1] - 2)
    fr, fc = r - r0, c - c0
    return ((1 - fr) * (1 - fc) * g[r0, c0] + (1 - fr) * fc * g[r0, c0 + 1] +
            fr * (1 - fc) * g[r0 + 1, c0] + fr * fc * g[r0 + 1, c0 + 1])


def motion_errors(images, first):
    """For each frame pair (n, n + 1) and each window with texture (its standard deviation at
    least half the picture's) lying where the VDB holds the velocity (smoke at the window's
    voxels and their neighbours, in both frames): the measured shift minus the truth, and the
    band. The truth is the midpoint rule of each pixel's path: Blender's velocity, bilinear as
    impulse samples it and linear in time (the mean of the two frames), at the pixel moved by
    half the window's mean displacement, averaged over the window. The correlation's peak is
    a mean of the window's displacements weighted by its texture, within a few standard
    deviations of their plain mean: the band is RESOLUTION + 3 sd per component."""
    errors, bands, rejected = [], [], 0
    ys, xs = np.mgrid[0:WINDOW, 0:WINDOW] + 0.5
    picture_sd = np.std(images[0])
    for n in range(len(images) - 1):
        frame = first + n   # impulse frame n reads Blender frame n (start = 0)
        (u0, w0, a0), (u1, w1, a1) = plane_motion(frame), plane_motion(frame + 1)
        u, w = 0.5 * (u0 + u1), 0.5 * (w0 + w1)
        for r0 in range(0, SIZE - WINDOW + 1, STEP):
            for c0 in range(0, SIZE - WINDOW + 1, STEP):
                i0, i1 = max(int(r0 / VOXEL_PX) - 1, 0), int((r0 + WINDOW) / VOXEL_PX) + 1
                j0, j1 = max(int(c0 / VOXEL_PX) - 1, 0), int((c0 + WINDOW) / VOXEL_PX) + 1
                if not (a0[i0:i1, j0:j1].all() and a1[i0:i1, j0:j1].all()):
                    continue
                if np.std(images[n][r0:r0 + WINDOW, c0:c0 + WINDOW]) < 0.5 * picture_sd:
                    continue
                rows, cols = r0 + ys, c0 + xs
                du, dw = bilinear(u, rows, cols).mean(), bilinear(w, rows, cols).mean()
                us, ws = bilinear(u, rows + dw / 2, cols + du / 2), bilinear(w, rows + dw / 2, cols + du / 2)
                dx, dy, peak = shift(images[n], images[n + 1], r0, c0, WINDOW, REACH)
                if peak < MIN_PEAK:
                    rejected += 1
                    continue
                errors.append((dx - us.mean(), dy - ws.mean()))
                bands.append((RESOLUTION + 3 * us.std(), RESOLUTION + 3 * ws.std()))
    return np.array(errors), np.array(bands), rejected


FIRST, LAST = 8, 23   # frames with smoke across much of the slice
results = {}
for label, flow in (("right", sequence_flow()),
                    ("velocity doubled", sequence_flow(velocity_scale=2 * VELOCITY_SCALE)),
                    ("6 frames late", sequence_flow(start=-6))):
    images = render_frames("texture_" + label.split()[0], texture_scene(flow), FIRST, LAST)
    errors, bands, rejected = motion_errors(images, FIRST)
    outside = np.mean(np.any(np.abs(errors) > bands, axis=1))
    np.save(os.path.join(tmp, "errors_" + label.split()[0] + ".npy"), np.concatenate([errors, bands], axis=1))
    rms = np.sqrt(np.mean(errors ** 2))
    results[label] = outside
    print(f"motion, {label}: {len(errors)} windows ({rejected} without a clear peak), rms error {rms:.3f} px/frame, median band "
          f"{np.median(bands):.2f} px, {100 * outside:.1f} % outside the band")
if results["right"] > 0.01:
    fail("the texture does not move with the simulation's velocity")
for label in ("velocity doubled", "6 frames late"):
    if results[label] < 0.25:
        fail(f"the motion check cannot tell a wrong flow ({label})")

# The scenes of test_scenes "[.mantaflow]" (the frame variance with and without sqrt(J)):
# 240 frames, the sequence's 24 and its last held.
write_scene("variance", texture_scene(sequence_flow(), count=240))
write_scene("still", texture_scene("", count=240))


def analyze(name, text):
    """impulse analyze --scene on the frames of a scene (120: 10 lifetimes): its stationarity verdict and the
    measured variance against Campbell's theorem (README "Stationarity", docs/stationarity.md)."""
    out = os.path.join(tmp, name)
    os.makedirs(out, exist_ok=True)
    scene = write_scene(name, text)
    subprocess.run([cli, "render", scene, "-o", os.path.join(out, "f_####.exr"), "-q"], check=True,
                   stderr=subprocess.DEVNULL)
    result = subprocess.run([cli, "analyze", os.path.join(out, "f_####.exr"), "--scene", scene, "--json"],
                            check=True, capture_output=True, text=True)
    report = json.loads(result.stdout)
    v = report["theory"]["variance"]
    print(f"analyze --scene, {name}: {report['stationarity']['verdict']}; variance {v['measured']:.4f} "
          f"against {v['expected']:.4f} +- {v['sd']:.4f} (z {v['z']:.2f})")
    return report["stationarity"]["stationary"] and v["agrees"]


# With sqrt(J) analyze --scene finds the texture on the slice stationary, its variance
# Campbell's. Its control: outside = "zero", where the field jumps from the edge of the cache's
# box (the smoke's, moving) to 0 beyond: a divergence the interpolant does not hold, so sqrt(J)
# misses it and the impulses pile up there.
if not analyze("analyzed", texture_scene(sequence_flow(), count=120)):
    fail("analyze --scene does not find the texture on the slice stationary with sqrt(J)")
if analyze("analyzed_zero", texture_scene(sequence_flow(outside="zero"), count=120)):
    fail("analyze --scene finds the texture stationary across the jump of outside = zero")
# jacobian = false is refused where the slice diverges, in one line naming the frame
refused = subprocess.run([cli, "render", write_scene("no_jacobian", texture_scene(sequence_flow(), False)),
                          "--frames", "0-0", "-o", os.path.join(tmp, "no.exr"), "-q"],
                         capture_output=True, text=True)
message = refused.stderr.strip().splitlines()
print("jacobian = false:", message[-1] if message else "(nothing)")
if refused.returncode == 0 or len(message) != 1 or "the velocity sequence diverges" not in message[0] \
        or "fluid_data_0001.vdb" not in message[0] or os.path.exists(os.path.join(tmp, "no.exr")):
    fail("jacobian = false on a diverging cache is not refused in one line naming the frame")

# ---------------------------------------------------------------------------------------------
# 3. A volume carried by the cache, written as OpenVDB frames.
volume = write_scene("cloud", f"""[output]
size = [64, 64]
frames = {frames}
fps = {FPS}
[volume]
size = [{nx}, {ny}, {nz}]
voxel_size = {CELL}
octaves = 1
lifetime = 0.5
[volume.kernel]
radius = 6
""" + sequence_flow(volume=True))
out = os.path.join(tmp, "cloud")
os.makedirs(out, exist_ok=True)
subprocess.run([cli, "render", volume, "-o", os.path.join(out, "cloud_####.vdb"),
                "--frames", "10-12", "-q"], check=True)
written = sorted(os.listdir(out))
if written != [f"cloud_{n:04d}.vdb" for n in (10, 11, 12)]:
    fail(f"volume frames: {written}")
print("volume: frames 10-12 written as OpenVDB")
print("mantaflow test: passed")
