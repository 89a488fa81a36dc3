#!/usr/bin/env bash
# Zips the Blender add-on (blender/impulse_addon, docs/blender.md) for Blender's
# Edit > Preferences > Add-ons > Install...: scripts/blender_addon.sh [-o impulse_addon.zip]
set -euo pipefail
out=impulse_addon.zip
if [ "${1:-}" = "-o" ] && [ -n "${2:-}" ]; then out=$2; elif [ $# -gt 0 ]; then
    echo "usage: $0 [-o impulse_addon.zip]" >&2; exit 2
fi
addon="$(cd "$(dirname "$0")/../blender" && pwd)/impulse_addon"
/usr/bin/python3 - "$addon" "$out" << 'PY'
import os, sys, zipfile
addon, out = sys.argv[1], sys.argv[2]
tmp = out + ".partial"
with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
    for name in sorted(os.listdir(addon)):
        if name.endswith(".py"):
            z.write(os.path.join(addon, name), "impulse_addon/" + name)
os.replace(tmp, out)
print(f"wrote {out}")
PY
