#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The gallery: a still of every built-in scene and a short looping animation of each moving one
# (animated WebP), and the page that shows them, docs/gallery.md (linked from the README).
#
# Usage: scripts/gallery.sh [--fast] [--impulse PATH] [--out DIR]
#   --out DIR      where gallery.md and gallery/ go (default: docs)
#   --impulse PATH the impulse binary (default: build/app/impulse, built by scripts/setup.sh)
#   --fast         tiny pictures and 3 frames: checks the script still runs (CTest gallery_script)
# Stills are frame 60 (frame 0 of a one-frame scene) at 640 pixels wide, WebP quality 80;
# animations are frames 0-47 at 320 wide, every second frame at 15 fps (1.6 s), WebP quality
# 50. The whole gallery must stay under 3 MB (it lives in the repository): the script fails
# past that, naming the size.
set -euo pipefail
cd "$(dirname "$0")/.."

out=docs
impulse=""
fast=0
while [ $# -gt 0 ]; do
    case "$1" in
        --fast) fast=1 ;;
        --out) out=${2:?--out needs a directory}; shift ;;
        --impulse) impulse=${2:?--impulse needs a path}; shift ;;
        *) echo "gallery.sh: unknown argument $1 (usage: gallery.sh [--fast] [--impulse PATH] [--out DIR])" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "$impulse" ]; then
    bash scripts/setup.sh >/dev/null
    impulse=build/app/impulse
fi
for tool in img2webp cwebp; do
    command -v "$tool" >/dev/null || { echo "gallery.sh: $tool not found (Debian package webp; scripts/setup.sh installs it)" >&2; exit 1; }
done
[ -x "$impulse" ] || { echo "gallery.sh: $impulse: not an executable" >&2; exit 1; }

if [ $fast = 1 ]; then still_w=64; anim_w=48; anim_last=2; else still_w=640; anim_w=320; anim_last=47; fi
budget=$((3 * 1024 * 1024))

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out/gallery"

# W x H at width w keeping the scene's aspect (even height, as H.264 and WebP like).
size_at() {
    local w=$1 sw=$2 sh=$3
    echo "${w}x$(( (w * sh / sw + 1) / 2 * 2 ))"
}

page="$tmp/gallery.md"
cat > "$page" <<'MD'
# Gallery

Every built-in scene (`impulse scenes`), rendered by `scripts/gallery.sh`: a still (frame 60)
and, for the moving ones, the first 1.6 s as a looping animation at a quarter of the size.
`impulse render NAME` renders the real thing (1080p H.264 for most).

MD
for name in $("$impulse" scenes | awk '{print $1}'); do
    desc=$("$impulse" scenes | awk -v n="$name" '$1 == n { $1 = ""; sub(/^ /, ""); print }')
    read -r sw sh frames < <("$impulse" info "$name" 2>/dev/null |
        awk '/^output/ { split($2, s, "x"); sub(",", "", s[2]); print s[1], s[2], $3 }')
    [ -n "${frames:-}" ] || { echo "gallery.sh: impulse info $name gave no output line" >&2; exit 1; }
    still_frame=$(( frames > 60 ? 60 : 0 ))
    [ $fast = 1 ] && still_frame=0
    echo "gallery: $name"
    "$impulse" render "$name" -q -o "$tmp/$name.png" --frames "$still_frame" \
        --size "$(size_at $still_w "$sw" "$sh")" >/dev/null
    cwebp -quiet -q 80 "$tmp/$name.png" -o "$out/gallery/$name.webp"
    printf '## %s\n\n%s\n\n![%s, frame %d](gallery/%s.webp)' "$name" "$desc" "$name" "$still_frame" "$name" >> "$page"
    if [ "$frames" -gt 1 ]; then
        last=$(( anim_last < frames - 1 ? anim_last : frames - 1 ))
        "$impulse" render "$name" -q -o "$tmp/${name}_####.png" --frames "0-$last" \
            --size "$(size_at $anim_w "$sw" "$sh")" >/dev/null
        # every second frame, shown for two frame times (15 fps)
        img2webp -loop 0 -lossy -q 50 -m 4 -d 67 $(ls "$tmp/${name}"_*.png | awk 'NR % 2 == 1') \
            -o "$out/gallery/${name}_loop.webp" >/dev/null 2>&1
        printf ' ![%s, animated](gallery/%s_loop.webp)' "$name" "$name" >> "$page"
    fi
    printf '\n\n' >> "$page"
done
mv "$page" "$out/gallery.md"

total=$(du -cb "$out/gallery.md" "$out"/gallery/*.webp | tail -1 | cut -f1)
echo "gallery: $out/gallery.md, $(ls "$out"/gallery/*.webp | wc -l) pictures, $total bytes"
if [ "$total" -gt "$budget" ]; then
    echo "gallery.sh: the gallery is $total bytes, over its 3 MB budget ($budget)" >&2
    exit 1
fi
