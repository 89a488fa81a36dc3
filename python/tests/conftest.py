# SPDX-License-Identifier: Apache-2.0
# Shared helpers of the Python module's tests: the CLI next to the module (IMPULSE_CLI, set by
# CTest) and images read back through OpenImageIO's oiiotool as PFM (float32, no loss).
import os
import subprocess

import numpy as np
import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("IMPULSE_CLI", "")
    if not path or not os.access(path, os.X_OK):
        pytest.fail("IMPULSE_CLI must name the built impulse tool (ctest sets it)")
    return path


def read_fits(path):
    """A FITS file as OpenImageIO writes it (float32, big-endian, channels on the first axis),
    as an array H x W or H x W x C, top row first."""
    with open(path, "rb") as f:
        data = f.read()
    cards, offset = {}, 0
    while True:
        card = data[offset:offset + 80].decode("ascii")
        offset += 80
        if card.startswith("END"):
            break
        if "=" in card:
            key, value = card.split("=", 1)
            cards[key.strip()] = value.split("/")[0].strip()
    assert int(cards["BITPIX"]) == -32, cards
    axes = [int(cards[f"NAXIS{i}"]) for i in range(int(cards["NAXIS"]), 0, -1)]
    # The pixels end the file (OpenImageIO pads its header past the 2880-byte block).
    count = int(np.prod(axes))
    values = np.frombuffer(data, dtype=">f4", count=count, offset=len(data) - 4 * count)
    return np.flipud(values.reshape(axes)).astype(np.float32)  # FITS stores the bottom row first


def read_image(path, tmp_path):
    """Any image OpenImageIO reads, as float32 values (8-bit PNG: k / 255), through oiiotool's
    FITS writer (float32 without loss; Debian's OpenImageIO writes no PFM)."""
    fits = str(tmp_path / (os.path.basename(path) + ".fits"))
    subprocess.run(["oiiotool", path, "-d", "float", "-o", fits], check=True, capture_output=True)
    return read_fits(fits)
