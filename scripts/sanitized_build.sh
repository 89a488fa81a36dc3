#!/usr/bin/env bash
# Configures and builds the one sanitized build that scripts/sanitize.sh and scripts/fuzz.sh
# share (build-asan/): clang, RelWithDebInfo, AddressSanitizer and UBSan on everything, plus
# libFuzzer's coverage instrumentation (-DIMPULSE_FUZZ=ON), so the tests and the fuzz targets are
# compiled once. Installs clang and its runtime from Debian's packages when missing.
#   scripts/sanitized_build.sh TARGET...
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --tests --deps-only
missing=()
for p in clang libclang-rt-dev; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
build=build-asan
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# paths inside the checkout hashed relative to it, so clones at other paths share the cache;
# and, as this build has debug information, without the working directory that ccache hashes
# then by default (hash_dir): a clean clone otherwise missed every object (10 of CI's minutes)
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
export CCACHE_NOHASHDIR=1
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DIMPULSE_FUZZ=ON -DIMPULSE_BUILD_BENCH=OFF "${launcher[@]}" > "$build.log" 2>&1 \
    || { cat "$build.log"; exit 1; }
cmake --build "$build" -j"$(nproc)" --target "$@" >> "$build.log" 2>&1 \
    || { tail -50 "$build.log"; exit 1; }
