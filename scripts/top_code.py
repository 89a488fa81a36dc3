#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
# Share of an 8-bit image's pixels at the top code value (issue 20: a gallery frame keeps at
# most 0.5 % there): "any" has some channel at 255, "white" has every channel at 255.
# Usage: scripts/top_code.py IMAGE.png...   (reads through oiiotool; needs python3-numpy)
import os
import subprocess
import sys
import tempfile

import numpy as np


def read_ppm(path):
    """8-bit pixels of any image oiiotool reads, as an (h, w, channels) uint8 array (grey or RGB:
    oiiotool writes a PGM or a PPM)."""
    with tempfile.TemporaryDirectory() as tmp:
        ppm = os.path.join(tmp, "x.pnm")
        subprocess.run(["oiiotool", path, "-d", "uint8", "-o", ppm], check=True,
                       stdout=subprocess.DEVNULL)
        data = open(ppm, "rb").read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval, separated by whitespace
        while data[pos:pos + 1].isspace():
            pos += 1
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    channels = {b"P5": 1, b"P6": 3}.get(fields[0])
    if channels is None or fields[3] != b"255":
        sys.exit(f"{path}: expected an 8-bit grey or RGB image, oiiotool wrote {fields[0]!r}")
    w, h = int(fields[1]), int(fields[2])
    return np.frombuffer(data, np.uint8, w * h * channels, pos + 1).reshape(h, w, channels)


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: top_code.py IMAGE...")
    print(f"{'image':40s} {'any 255 %':>10s} {'white %':>8s}")
    for path in sys.argv[1:]:
        px = read_ppm(path)
        top = px == 255
        print(f"{os.path.basename(path):40s} {100 * top.any(axis=2).mean():10.2f} "
              f"{100 * top.all(axis=2).mean():8.2f}")


if __name__ == "__main__":
    main()
