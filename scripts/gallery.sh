#!/usr/bin/env bash
# Renders every built-in scene to gallery/NAME.mp4, writes a contact sheet of first frames
# (gallery/contact_sheet.png) and a page that plays the videos (gallery/index.html).
# Usage: scripts/gallery.sh [WxH]   (default 960x540; smaller is faster)
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-960x540}
bash scripts/setup.sh
dpkg-query -W -f='${Status}' openimageio-tools 2>/dev/null | grep -q "install ok installed" || {
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends openimageio-tools; }
mkdir -p gallery
impulse=./build/app/impulse
names=$($impulse scenes | awk '{print $1}')
cards=""
firsts=()
for n in $names; do
    desc=$($impulse scenes | awk -v n="$n" '$1 == n { $1 = ""; sub(/^ /, ""); print }')
    echo "rendering $n ($size)"
    frames=$($impulse info "$n" | awk '/^output/ {print $3}')
    if [ "${frames:-1}" -gt 1 ]; then
        $impulse render "$n" -o "gallery/$n.mp4" --size "$size" -q
        cards+="<figure><video src=\"$n.mp4\" autoplay loop muted playsinline></video><figcaption><b>$n</b> — $desc</figcaption></figure>"$'\n'
    else
        $impulse render "$n" -o "gallery/$n.png" --size "$size" -q
        cards+="<figure><img src=\"$n.png\"><figcaption><b>$n</b> — $desc</figcaption></figure>"$'\n'
    fi
    $impulse render "$n" -o "gallery/first_$n.png" --frames 0 --size "$size" -q
    firsts+=("gallery/first_$n.png")
done
cols=3
oiiotool "${firsts[@]}" --mosaic:pad=8 ${cols}x$(( (${#firsts[@]} + cols - 1) / cols )) -o gallery/contact_sheet.png
cat > gallery/index.html <<HTML
<!doctype html>
<html><head><meta charset="utf-8"><title>impulse gallery</title>
<style>body{font-family:sans-serif;background:#111;color:#ddd;margin:2em}
main{display:grid;grid-template-columns:repeat(auto-fill,minmax(420px,1fr));gap:1.5em}
figure{margin:0}video,img{width:100%;border-radius:4px}</style></head>
<body><h1>impulse gallery</h1><p><img src="contact_sheet.png" alt="first frames"></p><main>
$cards</main></body></html>
HTML
echo "gallery: $(pwd)/gallery/index.html"
