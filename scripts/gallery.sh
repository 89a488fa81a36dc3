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
    command -v "$tool" >/dev/null || { echo "gallery.sh: $tool not found (Debian package webp; scripts/setup.sh --tests installs it)" >&2; exit 1; }
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

# A mesh made by `impulse mesh ...` as a picture: impulse mesh view, then WebP.
mesh_picture() {
    local mesh=$1 name=$2
    "$impulse" mesh view "$mesh" --pixels "$mesh_px" -o "$tmp/$name.png"
    cwebp -quiet -q 80 "$tmp/$name.png" -o "$out/gallery/$name.webp"
}

# The solid-noise applications on meshes (Lewis 1989 §5; docs/mesh.md): the commands, as a
# user would type them, and what they make.
mesh_gallery() {
    local m="$tmp/mesh" f
    mkdir -p "$m"
    echo "gallery: meshes"
    if [ $fast = 1 ]; then mesh_px=64 grid=24 levels=3 frames=3 paths="--particles 10 --steps 40"
    else mesh_px=400 grid=128 levels=6 frames=24 paths="--particles 120 --steps 500"; fi
    "$impulse" mesh porous --iso 0.5 --scale 0.3 --size $grid -o "$m/coral.obj"
    "$impulse" mesh texture "$m/coral.obj" --transform wood -o "$m/coral_wood.ply"
    mesh_picture "$m/coral_wood.ply" mesh_wood
    "$impulse" mesh texture "$m/coral.obj" --transform wood --section z=0 --pixels "$mesh_px" -o "$tmp/section.png"
    cwebp -quiet -q 80 "$tmp/section.png" -o "$out/gallery/mesh_wood_section.webp"
    "$impulse" mesh sphere --levels $levels -o "$m/sphere.obj"
    "$impulse" mesh deform "$m/sphere.obj" --amount 0.05 --scale 0.6 --seed 4 -o "$m/pebble.obj"
    "$impulse" mesh texture "$m/pebble.obj" --transform marble --axis 1,0.4,0.2 -o "$m/pebble_marble.ply"
    mesh_picture "$m/pebble_marble.ply" mesh_marble
    "$impulse" mesh porous --iso 0.3 --envelope box --scale 0.15 --size $grid -o "$m/sponge.obj"
    mesh_picture "$m/sponge.obj" mesh_porous
    "$impulse" mesh deform "$m/sphere.obj" --amount 0.12 --scale 0.5 --frames $frames -o "$m/blob_####.obj"
    for f in "$m"/blob_*.obj; do "$impulse" mesh view "$f" --pixels $((mesh_px / 2)) --azimuth 35 -o "${f%.obj}.png"; done
    img2webp -loop 0 -lossy -q 50 -m 4 -d 67 "$m"/blob_*.png -o "$out/gallery/mesh_deform_loop.webp" >/dev/null 2>&1
    "$impulse" trajectories $paths -o "$m/paths.ply"
    mesh_picture "$m/paths.ply" mesh_trajectories
    cat >> "$page" <<'MD'
## Meshes: solid noise applications (Lewis 1989 §5)

`docs/mesh.md` explains the commands; `impulse mesh view` made the pictures (an orthographic
software render). **Solid wood** (§5.1), carved from a block: a porous object coloured at its
vertices, and the section z = 0 through the same block:

    impulse mesh porous --iso 0.5 --scale 0.3 --size 128 -o coral.obj
    impulse mesh texture coral.obj --transform wood -o coral_wood.ply
    impulse mesh texture coral.obj --transform wood --section z=0 -o section.png

![solid wood on a porous object](gallery/mesh_wood.webp) ![the section z = 0](gallery/mesh_wood_section.webp)

**Solid marble** on a sphere slightly deformed (an "individual", §5.3):

    impulse mesh sphere --levels 6 -o sphere.obj
    impulse mesh deform sphere.obj --amount 0.05 --scale 0.6 --seed 4 -o pebble.obj
    impulse mesh texture pebble.obj --transform marble --axis 1,0.4,0.2 -o pebble_marble.ply

![solid marble](gallery/mesh_marble.webp)

**Porous object** (§5.2): the iso-surface of noise times a box envelope, meshed by OpenVDB:

    impulse mesh porous --iso 0.3 --envelope box --scale 0.15 --size 128 -o sponge.obj

![a porous box](gallery/mesh_porous.webp)

**Stochastic deformation** (§5.3), animated by moving through 4-D noise (24 OBJ frames):

    impulse mesh deform sphere.obj --amount 0.12 --scale 0.5 --frames 24 -o blob_####.obj

![a deforming sphere](gallery/mesh_deform_loop.webp)

**Trajectories** (Figs. 12-13) of 120 particles forced by vector solid noise, blue at the
start, orange at the end:

    impulse trajectories --particles 120 --steps 500 -o paths.ply

![trajectories](gallery/mesh_trajectories.webp)

MD
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
    output_line=$("$impulse" info "$name" 2>/dev/null | grep '^output' || true)
    read -r sw sh frames < <(awk '{ split($2, s, "x"); sub(",", "", s[2]); print s[1], s[2], $3 }' <<<"$output_line")
    [ -n "${frames:-}" ] || { echo "gallery.sh: impulse info $name gave no output line" >&2; exit 1; }
    still_frame=$(( frames > 60 ? 60 : 0 ))
    extra=()
    if [ $fast = 1 ]; then
        still_frame=0
        # a volume scene's grid a quarter of its size along each axis: the voxels, not the
        # picture's pixels, are its cost (cloudvolume's 256x128x112 took 21 of the 63 CPU-s)
        [[ $output_line == *" voxels)" ]] && extra=(--set "volume.size=[64,32,28]")
    fi
    echo "gallery: $name"
    "$impulse" render "$name" -q -o "$tmp/$name.png" --frames "$still_frame" "${extra[@]}" \
        --size "$(size_at $still_w "$sw" "$sh")" >/dev/null
    cwebp -quiet -q 80 "$tmp/$name.png" -o "$out/gallery/$name.webp"
    printf '## %s\n\n%s\n\n![%s, frame %d](gallery/%s.webp)' "$name" "$desc" "$name" "$still_frame" "$name" >> "$page"
    if [ "$frames" -gt 1 ]; then
        last=$(( anim_last < frames - 1 ? anim_last : frames - 1 ))
        "$impulse" render "$name" -q -o "$tmp/${name}_####.png" --frames "0-$last" "${extra[@]}" \
            --size "$(size_at $anim_w "$sw" "$sh")" >/dev/null
        # every second frame, shown for two frame times (15 fps)
        img2webp -loop 0 -lossy -q 50 -m 4 -d 67 $(ls "$tmp/${name}"_*.png | awk 'NR % 2 == 1') \
            -o "$out/gallery/${name}_loop.webp" >/dev/null 2>&1
        printf ' ![%s, animated](gallery/%s_loop.webp)' "$name" "$name" >> "$page"
    fi
    printf '\n\n' >> "$page"
done
mesh_gallery
mv "$page" "$out/gallery.md"

total=$(du -cb "$out/gallery.md" "$out"/gallery/*.webp | tail -1 | cut -f1)
echo "gallery: $out/gallery.md, $(ls "$out"/gallery/*.webp | wc -l) pictures, $total bytes"
if [ "$total" -gt "$budget" ]; then
    echo "gallery.sh: the gallery is $total bytes, over its 3 MB budget ($budget)" >&2
    exit 1
fi
