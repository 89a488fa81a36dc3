#!/usr/bin/env bash
# The Blender add-on in headless Blender (docs/blender.md): installed from the zip
# scripts/blender_addon.sh makes, with a temporary user configuration (nothing of the user's is
# read or written), it fills an Image equal to `impulse render drift --frames 12-12` bit for bit,
# then checks the sliders, the EXR bake (rendered by Cycles), the volume, the mesh operators
# (blender/test_addon.py; docs/blender.md "Tested").
# Usage: test_blender_addon.sh SOURCE_DIR MODULE_DIR IMPULSE_CLI (CTest: -L blender).
# Exit 77 (skipped) without Debian's blender.
set -euo pipefail
src=$1 module=$2 cli=$3
command -v blender > /dev/null || { echo "skipped: no blender (apt-get install blender)"; exit 77; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BLENDER_USER_CONFIG=$tmp/config BLENDER_USER_SCRIPTS=$tmp/scripts BLENDER_USER_DATAFILES=$tmp/data
bash "$src/scripts/blender_addon.sh" -o "$tmp/impulse_addon.zip"
"$cli" render drift --size 192x108 --frames 12-12 -o "$tmp/f.exr" -q
oiiotool "$tmp/f.exr" -d float -o "$tmp/f.fits"
blender -b --factory-startup --python-exit-code 1 --python "$src/blender/test_addon.py" -- \
    "$tmp/impulse_addon.zip" "$module" "$tmp/f.fits" "$src/python/tests" "$cli" > "$tmp/blender.log" 2>&1 \
    || { cat "$tmp/blender.log"; exit 1; }
grep "^impulse add-on:" "$tmp/blender.log"
