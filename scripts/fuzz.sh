#!/usr/bin/env bash
# Fuzzes the scene loader with libFuzzer for a bounded time (default 60 s) from a seed corpus of
# the built-in scenes. Needs clang (Debian's clang and libclang-rt-dev: installed if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
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
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DIMPULSE_FUZZ=ON -DIMPULSE_BUILD_TESTS=OFF -DIMPULSE_BUILD_BENCH=OFF > build-fuzz.log 2>&1 \
    || { cat build-fuzz.log; exit 1; }
cmake --build build-fuzz -j"$(nproc)" --target fuzz_scene >> build-fuzz.log 2>&1 \
    || { tail -40 build-fuzz.log; exit 1; }
corpus=$(mktemp -d)
cp scenes/*.toml "$corpus"/
[ -d tests/scenes/corpus ] && cp tests/scenes/corpus/*.toml "$corpus"/ 2>/dev/null || true
mkdir -p build-fuzz/crashes
./build-fuzz/fuzz/fuzz_scene "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix=build-fuzz/crashes/ -print_final_stats=1 2>&1 | tee build-fuzz/fuzz.log | tail -15
rm -rf "$corpus"
echo "fuzz: $(grep -E 'stat::number_of_executed_units' build-fuzz/fuzz.log | awk '{print $2}') executions, no crash"
