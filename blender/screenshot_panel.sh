#!/usr/bin/env bash
# The picture of the add-on's panel in docs/blender.md: Blender with a window on a virtual X
# display (Debian's xvfb: headless Blender has no window to draw the panel in), the add-on
# installed from its zip with a temporary user configuration, the Image Editor's sidebar on the
# impulse tab with drift's frame 12 in the Image and two sliders; saves the Image Editor's area.
# Usage: blender/screenshot_panel.sh MODULE_DIR IMPULSE_CLI OUT.png   (not a test; needs
# blender and xvfb-run: apt-get install blender xvfb)
set -euo pipefail
module=$1 cli=$2 out=$3
src="$(cd "$(dirname "$0")/.." && pwd)"
for tool in blender xvfb-run; do
    command -v "$tool" > /dev/null || { echo "no $tool (apt-get install blender xvfb)" >&2; exit 1; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export BLENDER_USER_CONFIG=$tmp/config BLENDER_USER_SCRIPTS=$tmp/scripts BLENDER_USER_DATAFILES=$tmp/data
bash "$src/scripts/blender_addon.sh" -o "$tmp/impulse_addon.zip" > /dev/null
# Software OpenGL (Mesa's llvmpipe) draws the window; event simulation lets the script pick the
# sidebar's tab as the mouse wheel over its tabs would.
xvfb-run -a -s "-screen 0 1200x760x24" blender --factory-startup --enable-event-simulate \
    --python "$src/blender/screenshot_panel.py" -- "$tmp/impulse_addon.zip" "$module" "$cli" "$tmp/shot.png" \
    > "$tmp/blender.log" 2>&1 || true
[ -s "$tmp/shot.png" ] || { cat "$tmp/blender.log"; echo "no screenshot written" >&2; exit 1; }
mv "$tmp/shot.png" "$out"
echo "wrote $out ($(stat -c %s "$out") bytes)"
