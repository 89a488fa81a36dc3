#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""`impulse render drift -o x.mp4` end to end: CPU per frame and wall fps, binaries side by side,
and the x264 presets by SSIM against a lossless render.

    python3 bench/drift_e2e.py build/app/impulse [OTHER_IMPULSE ...] [--frames 240] [--runs 3]
    python3 bench/drift_e2e.py build/app/impulse --presets [--frames 120]

Whole processes (start-up included), the binaries interleaved run by run so a change of machine
load hits them alike. Printed per binary: the median CPU time per frame (user + sys of the child
from wait4's rusage: the main figure on a shared machine, where other processes take the cores),
the median wall fps, and the 1-minute load average before each run (/proc/loadavg).
--presets renders the frames once per x264 preset (ultrafast, superfast, veryfast, faster) with
the scene's crf, and once to FFV1 (lossless RGB, .mkv) as the reference, then runs
`ffmpeg -lavfi ssim` with both sides taken to yuv444p (bench/README.md gives the command).
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import tempfile

import startup  # bench/startup.py: one whole run, wall and the child's CPU from wait4


def load1():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def run_once(cmd):
    """Wall seconds, child CPU seconds (startup.py's measurement) and the load average before."""
    load = load1()
    wall, cpu = startup.run_once(cmd)
    return wall, cpu, load


def render_cmd(exe, frames, out, extra=()):
    return [exe, "render", "drift", "--frames", f"0-{frames - 1}", "-q", *extra, "-o", out]


def side_by_side(exes, frames, runs, tmp):
    samples = {exe: [] for exe in exes}
    for _ in range(runs):
        for exe in exes:
            samples[exe].append(run_once(render_cmd(exe, frames, os.path.join(tmp, "x.mp4"))))
    print(f"drift 1920x1080, {frames} frames, scene preset, {runs} runs (medians; min-max)")
    print(f"{'binary':<40} {'CPU ms/frame':>22} {'wall fps':>18} {'load':>10}")
    for exe, s in samples.items():
        cpu = [1e3 * c / frames for _, c, _ in s]
        fps = [frames / w for w, _, _ in s]
        loads = [l for _, _, l in s]
        print(f"{exe:<40} {statistics.median(cpu):8.1f} ({min(cpu):.1f}-{max(cpu):.1f})"
              f" {statistics.median(fps):8.2f} ({min(fps):.1f}-{max(fps):.1f})"
              f" {statistics.median(loads):6.1f}")


def ssim(a, b):
    """SSIM All of a against b, both taken to yuv444p."""
    out = subprocess.run(["ffmpeg", "-v", "info", "-nostats", "-i", a, "-i", b, "-lavfi",
                          "[0:v]format=yuv444p[a];[1:v]format=yuv444p[b];[a][b]ssim",
                          "-f", "null", "-"], capture_output=True, text=True).stderr
    m = re.search(r"All:([0-9.]+) \(([0-9.inf]+)\)", out)
    if not m:
        raise SystemExit("no SSIM in ffmpeg's output:\n" + out[-2000:])
    return float(m.group(1)), m.group(2)


def presets(exe, frames, runs, tmp):
    ref = os.path.join(tmp, "ref.mkv")
    run_once(render_cmd(exe, frames, ref))
    names = ["ultrafast", "superfast", "veryfast", "faster"]
    cpu = {p: [] for p in names}
    for _ in range(runs):
        for p in names:
            out = os.path.join(tmp, p + ".mp4")
            _, c, _ = run_once(render_cmd(exe, frames, out, ["--set", f'output.preset="{p}"']))
            cpu[p].append(1e3 * c / frames)
    print(f"x264 presets, drift 1920x1080, {frames} frames, crf of the scene, {runs} runs")
    print(f"{'preset':<10} {'CPU ms/frame':>14} {'bytes':>10} {'SSIM All':>10} {'dB':>7}")
    for p in names:
        out = os.path.join(tmp, p + ".mp4")
        s, db = ssim(out, ref)
        print(f"{p:<10} {statistics.median(cpu[p]):14.1f} {os.path.getsize(out):10d} {s:10.4f} {db:>7}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("impulse", nargs="+")
    ap.add_argument("--frames", type=int, default=240)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--presets", action="store_true")
    args = ap.parse_args()
    exes = [os.path.abspath(e) for e in args.impulse]
    tmp = tempfile.mkdtemp(prefix="impulse-drift-e2e-")
    try:
        if args.presets:
            presets(exes[0], args.frames, args.runs, tmp)
        else:
            side_by_side(exes, args.frames, args.runs, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
