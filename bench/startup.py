#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Start-up and whole-process cost of short `impulse` commands, side by side with oiiotool.

    python3 bench/startup.py build/app/impulse [--runs 11] [--compression]

Each command runs --runs times, the commands interleaved run by run (a change of machine load
hits them alike); printed: the median wall time and the median CPU time (user + sys of the
child, from wait4's rusage: not inflated when other processes take the cores). On a loaded
machine trust the CPU column; the wall column needs a quiet one. --compression adds a table
of EXR compressions for one 1080p frame of drift: CPU time of the whole render and file size.
"""
import argparse
import os
import resource
import shutil
import statistics
import subprocess
import tempfile
import time


def run_once(cmd):
    """Wall seconds and child CPU seconds of one run (stdout and stderr discarded)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    rc = subprocess.call(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if rc != 0:
        raise SystemExit(f"failed ({rc}): {' '.join(cmd)}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def measure(commands, runs):
    """{name: (median wall ms, median cpu ms)} over interleaved runs."""
    samples = {name: [] for name in commands}
    for _ in range(runs):
        for name, cmd in commands.items():
            samples[name].append(run_once(cmd))
    return {name: (1e3 * statistics.median(w for w, _ in s), 1e3 * statistics.median(c for _, c in s))
            for name, s in samples.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("impulse")
    ap.add_argument("--runs", type=int, default=11)
    ap.add_argument("--compression", action="store_true")
    args = ap.parse_args()
    exe = os.path.abspath(args.impulse)
    tmp = tempfile.mkdtemp(prefix="impulse-startup-")
    try:
        commands = {
            "impulse --help": [exe, "--help"],
            "impulse scenes": [exe, "scenes"],
            "impulse info drift": [exe, "info", "drift"],
            "impulse render still 1080p -o s.png": [exe, "render", "still", "--size", "1920x1080", "-q",
                                                    "-o", os.path.join(tmp, "s.png")],
        }
        if shutil.which("oiiotool"):
            commands["oiiotool --help"] = ["oiiotool", "--help"]
        print(f"load average {os.getloadavg()[0]:.1f}; {args.runs} runs each, interleaved")
        print(f"{'command':40s} {'wall ms':>9s} {'cpu ms':>9s}")
        for name, (wall, cpu) in measure(commands, args.runs).items():
            print(f"{name:40s} {wall:9.1f} {cpu:9.1f}")
        if args.compression:
            names = ["none", "rle", "zips", "zip", "piz", "pxr24", "b44", "dwaa"]
            cmds = {c: [exe, "render", "drift", "--frames", "0", "-q", "--set",
                        f'output.compression="{c}"', "-o", os.path.join(tmp, c + ".exr")] for c in names}
            print(f"\n{'EXR compression (drift frame 0, 1080p)':40s} {'wall ms':>9s} {'cpu ms':>9s} {'bytes':>10s}")
            for c, (wall, cpu) in measure(cmds, max(3, args.runs // 3)).items():
                size = os.path.getsize(os.path.join(tmp, c + ".exr"))
                print(f"{c:40s} {wall:9.1f} {cpu:9.1f} {size:10d}")
    finally:
        shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
