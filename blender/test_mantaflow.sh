#!/usr/bin/env bash
# A real simulation drives impulse (docs/scenes.md "Velocity sequences", "A Blender cache"):
# headless Blender bakes a small Mantaflow smoke domain (blender/bake_mantaflow.py), then
# blender/test_mantaflow.py renders a texture and a volume carried by its cache and checks the
# texture moves with the simulation's velocity, and test_scenes "[.mantaflow]" checks the frame
# variance is stationary with sqrt(J) and not without it.
# Usage: test_mantaflow.sh SOURCE_DIR IMPULSE_CLI TEST_SCENES (CTest: -L blender).
# Exit 77 (skipped) without Debian's blender, numpy or oiiotool.
set -euo pipefail
src=$1 cli=$2 test_scenes=$3
command -v blender > /dev/null || { echo "skipped: no blender (apt-get install blender)"; exit 77; }
command -v oiiotool > /dev/null || { echo "skipped: no oiiotool (apt-get install openimageio-tools)"; exit 77; }
/usr/bin/python3 -c "import numpy" 2> /dev/null ||
    { echo "skipped: no numpy for /usr/bin/python3 (apt-get install python3-numpy)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BLENDER_USER_CONFIG=$tmp/config BLENDER_USER_SCRIPTS=$tmp/scripts BLENDER_USER_DATAFILES=$tmp/data
blender -b --factory-startup --python-exit-code 1 --python "$src/blender/bake_mantaflow.py" -- \
    "$tmp/cache" 32 24 > "$tmp/bake.log" 2>&1 || { cat "$tmp/bake.log"; exit 1; }
grep "^mantaflow:" "$tmp/bake.log"
/usr/bin/python3 "$src/blender/test_mantaflow.py" "$tmp" "$cli" "$src/python/tests"
IMPULSE_MANTAFLOW_SCENES=$tmp "$test_scenes" "[.mantaflow]"
