#!/usr/bin/env bash
# Sets everything up, then renders the default scene (drift: flowing clouds) to out/drift.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
./build/app/impulse render drift -o out/drift.mp4
echo "output: $(pwd)/out/drift.mp4"
