# SPDX-License-Identifier: Apache-2.0
"""Compares impulse_frame_dump's frames (tests/cross/frame_dump.cpp) of several builds with a
reference build's, bit for bit, and prints a table (scripts/arm64_check.sh).

  compare_frames.py DIR WxH FRAMES REFERENCE "OTHER..." SCENE...

DIR/SCENE-BUILD-fF.f32 holds frame F of SCENE from BUILD: the field (or a volume scene's density
grid), then the display RGB, W x H x 3 floats. A cell says "same", or how many values of the
field and of the RGB differ and by how much at most (absolute, and in units in the last place).
Exit status 1 when any frame differs or is missing.
"""
import array
import os
import sys


def read_floats(path):
    values = array.array("f")
    with open(path, "rb") as f:
        values.frombytes(f.read())
    return values


def ordered(x):
    """The float's bits as an integer that increases with the float (ulp distance = difference)."""
    i = array.array("i", array.array("f", [x]).tobytes())[0]
    return i if i >= 0 else -(i & 0x7FFFFFFF)


def part_difference(a, b):
    """(values that differ, max |a - b|, max ulp distance) of two equally long float arrays."""
    count, largest, ulps = 0, 0.0, 0
    for x, y in zip(a, b):
        if x != y or (x != x) != (y != y):
            count += 1
            if x == x and y == y:
                largest = max(largest, abs(x - y))
                ulps = max(ulps, abs(ordered(x) - ordered(y)))
    return count, largest, ulps


def cell(reference, other, rgb_size):
    """'same', or what differs between two dumps of one frame."""
    if not os.path.exists(other):
        return "missing", True
    a, b = read_floats(reference), read_floats(other)
    if a.tobytes() == b.tobytes():
        return "same", False
    if len(a) != len(b):
        return f"{len(b)} values, not {len(a)}", True
    split = len(a) - rgb_size
    words = []
    for name, lo, hi in (("field", 0, split), ("rgb", split, len(a))):
        n, d, u = part_difference(a[lo:hi], b[lo:hi])
        if n:
            words.append(f"{name} {n}/{hi - lo} max {d:.2g} ({u} ulp)")
    return "; ".join(words), True


def main(argv):
    folder, size, frames, reference, others = argv[1:6]
    scenes = argv[6:]
    width, height = (int(v) for v in size.split("x"))
    rgb_size = width * height * 3
    others = others.split()
    rows = [["scene", "frame"] + [f"{o} vs {reference}" for o in others]]
    failed = False
    for scene in scenes:
        for frame in frames.split(","):
            ref = os.path.join(folder, f"{scene}-{reference}-f{frame}.f32")
            row = [scene, frame]
            for o in others:
                text, bad = cell(ref, os.path.join(folder, f"{scene}-{o}-f{frame}.f32"), rgb_size)
                row.append(text)
                failed |= bad
            rows.append(row)
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        print("  ".join(text.ljust(w) for text, w in zip(r, widths)).rstrip())
    print(("FAIL: frames differ" if failed else "ok: every frame has the same bits") +
          f" ({len(scenes)} scenes, frames {frames}, {size})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
