#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# The layering check (tests/docs/check_layering.py) shown able to fail: on a copy of the tree with
# one violation of each kind planted, it must exit 1 and name each; on the tree itself it passes
# (CTest doc_layering).
set -u
root=${1:?usage: test_layering.sh SOURCE_DIR}
python=${PYTHON:-python3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/docs"
cp "$root/docs/design.md" "$tmp/docs/"
for d in numeric kernels sim render synth output analysis volume mesh scenes app python; do
    cp -r "$root/$d" "$tmp/$d"
done
# an upward include (kernels/ sits below sim/ in no table), a detail/ header from another
# folder, a header the facade does not list, an unlisted header at a library's top level
echo '#include "render/render.h"' >> "$tmp/kernels/kernel.cpp"
echo '#include "scenes/detail/reader.h"' >> "$tmp/app/main.cpp"
echo '#include "volume/unlisted.h"' >> "$tmp/scenes/frame/renderer.cpp"
printf '#pragma once\n' > "$tmp/volume/unlisted.h"
out=$("$python" "$root/tests/docs/check_layering.py" "$tmp")
status=$?
fail=0
[ "$status" -eq 1 ] || { echo "expected exit 1 on the planted violations, got $status"; fail=1; }
for expected in \
    "kernels/ uses render/, which docs/design.md §2 does not allow it" \
    "app/main.cpp: includes scenes/detail/reader.h, internal to scenes/ (its detail/)" \
    "scenes/frame/renderer.cpp: includes volume/unlisted.h, which volume/volume.h does not list" \
    "volume/unlisted.h: at volume/'s top level but not listed in volume/volume.h (move it to volume/detail/)"; do
    grep -qF "$expected" <<<"$out" || { echo "missing: $expected"; fail=1; }
done
[ "$fail" -eq 0 ] && echo "PASSED: every planted violation reported" || echo "$out"
exit "$fail"
