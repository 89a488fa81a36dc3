#!/usr/bin/env bash
# `pip install .` and a wheel (README "Install with pip"), offline, in a temporary
# directory: the package installs into a venv (--system-site-packages: Debian's numpy), imports
# outside the build tree, finds the built-in scenes it carries, and renders frame 12 of drift
# equal to the CLI's EXR bit for bit; `python3 -m build --wheel --no-isolation` makes a wheel
# that does the same in a second, fresh venv.
# Usage: test_pip_install.sh SOURCE_DIR CMAKE_BUILD_DIR IMPULSE_CLI (CTest: -L pip).
# Exit 77 (skipped) when Debian's python3-venv, python3-pip or python3-build is missing.
set -euo pipefail
src=$1 build=$2 cli=$3
py=/usr/bin/python3
for module in venv pip build setuptools numpy; do
    "$py" -c "import $module" 2> /dev/null || { echo "skipped: $py has no module $module (scripts/setup.sh installs it)"; exit 77; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# The package's module is built in the configured build directory (setup.py): nothing twice.
export IMPULSE_CMAKE_BUILD_DIR=$build
unset PYTHONPATH IMPULSE_SCENES_DIR

"$py" -m venv --system-site-packages "$tmp/pip"
"$tmp/pip/bin/pip" install --no-build-isolation --no-index --quiet "$src" > "$tmp/pip.log" 2>&1 \
    || { cat "$tmp/pip.log"; exit 1; }
(cd "$src" && "$py" -m build --wheel --no-isolation --outdir "$tmp/dist" .) > "$tmp/build.log" 2>&1 \
    || { cat "$tmp/build.log"; exit 1; }
"$py" -m venv --system-site-packages "$tmp/wheel"
"$tmp/wheel/bin/pip" install --no-index --quiet "$tmp"/dist/impulse-*.whl

"$cli" render drift --size 96x54 --frames 12-12 -o "$tmp/f.exr" -q
oiiotool "$tmp/f.exr" -d float -o "$tmp/f.fits"
cat > "$tmp/check.py" << 'PY'
import os
import sys

sys.path.insert(0, sys.argv[2])  # conftest's FITS reader
import numpy as np
from conftest import read_fits

import impulse

venv = os.path.realpath(sys.prefix)
package = os.path.dirname(os.path.realpath(impulse.__file__))
assert package.startswith(venv + os.sep), (package, venv)
scene = impulse.load_scene("drift", size=(96, 54))
assert os.path.realpath(scene.path).startswith(package + os.sep), scene.path  # its own scenes
frame = scene.render(12)
cli = read_fits(sys.argv[1])
assert frame.dtype == np.float32 and frame.shape == cli.shape, (frame.dtype, frame.shape, cli.shape)
assert np.array_equal(frame.view(np.uint32), cli.view(np.uint32)), "frame 12 differs from the CLI's"
print(f"{sys.prefix}: impulse from {package}, drift frame 12 equals the CLI's bit for bit")
PY
for venv in pip wheel; do
    (cd "$tmp" && "$tmp/$venv/bin/python" check.py "$tmp/f.fits" "$src/python/tests")
done
