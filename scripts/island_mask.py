#!/usr/bin/env python3
# Draws data/masks/island.png, the example birth-region mask of docs/scenes.md: a 256 x 256 grey
# island with a wavy coast and a lagoon, soft-edged (about 10 pixels). Plain Python writes a PGM;
# oiiotool (openimageio-tools) turns it into a PNG.
# Usage: python3 scripts/island_mask.py
import math
import os
import subprocess
import tempfile

W = H = 256
pixels = bytearray()
for j in range(H):
    for i in range(W):
        x, y = i + 0.5 - 128, j + 0.5 - 128
        r, t = math.hypot(x, y), math.atan2(y, x)
        coast = (78 + 14 * math.sin(3 * t + 0.4) + 9 * math.sin(5 * t + 1.3)
                 + 5 * math.sin(9 * t + 2.1) + 3 * math.sin(14 * t + 0.2))
        v = min(1.0, max(0.0, 0.5 - (r - coast) / 10))                     # soft coast
        v *= min(1.0, max(0.0, 0.5 + (math.hypot(x - 25, y + 15) - 18) / 8))  # lagoon
        pixels.append(round(255 * v * v * (3 - 2 * v)))
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
with tempfile.TemporaryDirectory() as d:
    pgm = os.path.join(d, "island.pgm")
    with open(pgm, "wb") as f:
        f.write(b"P5 256 256 255\n" + bytes(pixels))
    subprocess.run(["oiiotool", "--nosoftwareattrib", pgm, "--eraseattrib", ".*", "-o", os.path.join(root, "data", "masks", "island.png")], check=True)
