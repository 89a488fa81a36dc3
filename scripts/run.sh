#!/usr/bin/env bash
# Installs the tool's Debian packages and builds the tool alone (scripts/setup.sh: no tests,
# benches or Python module; scripts/test.sh builds those), then renders the default scene
# (drift: flowing clouds) to out/drift.mp4.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p out
./build/app/impulse render drift -o out/drift.mp4
echo "output: $(pwd)/out/drift.mp4"
