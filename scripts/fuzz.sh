#!/usr/bin/env bash
# Fuzzes with libFuzzer, AddressSanitizer and UBSan, for a bounded time per target (default 60 s):
#   fuzz_scene  scene text -> loader, theory, two 64x48 frames under a tight budget
#   fuzz_image  file bytes -> the image and video readers (OpenImageIO, libav) and the scene
#               inputs that read images
# Each target starts from its minimized corpus in fuzz/corpus/<target>/ (plus, for scenes, the
# built-in scenes and the error corpus); inputs that reach new coverage are merged back into it
# (-merge=1), so the corpus grows with what fuzzing finds. A crash, hang, leak or sanitizer
# report fails the script and leaves its reproducer in build-fuzz/crashes/.
#   scripts/fuzz.sh [seconds] [target...]
# Needs clang (Debian's clang and libclang-rt-dev: installed if missing).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene fuzz_image)
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
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DIMPULSE_FUZZ=ON -DIMPULSE_BUILD_TESTS=OFF -DIMPULSE_BUILD_BENCH=OFF "${launcher[@]}" \
    > build-fuzz.log 2>&1 || { cat build-fuzz.log; exit 1; }
cmake --build build-fuzz -j"$(nproc)" --target "${targets[@]}" >> build-fuzz.log 2>&1 \
    || { tail -40 build-fuzz.log; exit 1; }
mkdir -p build-fuzz/crashes
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp"

# fuzz TARGET: run it, then merge what it found into its corpus.
fuzz() {
    local target=$1 name=${1#fuzz_}
    local corpus=fuzz/corpus/$name found seeds=() max_len=8192
    found=$(mktemp -d)
    mkdir -p "$corpus"
    if [ "$name" = scene ]; then
        seeds=(scenes tests/scenes/errors)
    else
        max_len=65536
    fi
    ./build-fuzz/fuzz/"$target" "$found" "$corpus" "${seeds[@]}" -max_total_time="$seconds" \
        -timeout=60 -rss_limit_mb=2048 -max_len="$max_len" -artifact_prefix=build-fuzz/crashes/"$name"- \
        -print_final_stats=1 > build-fuzz/"$target".log 2>&1 \
        || { tail -60 build-fuzz/"$target".log; rm -rf "$found"; return 1; }
    ./build-fuzz/fuzz/"$target" -merge=1 -max_len="$max_len" -timeout=60 \
        -artifact_prefix=build-fuzz/crashes/"$name"- "$corpus" "$found" \
        > build-fuzz/"$target"-merge.log 2>&1 || { tail -20 build-fuzz/"$target"-merge.log; return 1; }
    rm -rf "$found"
    local runs cov
    runs=$(awk '/stat::number_of_executed_units/ {print $2}' build-fuzz/"$target".log)
    cov=$(grep -oE 'cov: [0-9]+' build-fuzz/"$target".log | tail -1)
    echo "$target: $runs executions in ${seconds} s, $cov edges, no crash;" \
        "corpus $(ls "$corpus" | wc -l) files"
}
for t in "${targets[@]}"; do fuzz "$t"; done
