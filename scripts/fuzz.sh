#!/usr/bin/env bash
# Fuzzes with libFuzzer, AddressSanitizer and UBSan, for a bounded time per target (default 60 s):
#   fuzz_scene  scene text -> loader, theory, two 64x48 frames under a tight budget
#   fuzz_image  file bytes -> the image and video readers (OpenImageIO, libav) and the scene
#               inputs that read images
# Each target starts from its minimized corpus in fuzz/corpus/<target>/ (plus, for scenes, the
# built-in scenes and the error corpus): every corpus input runs first, then fuzzing, until the
# time given since the target started (libFuzzer's -max_total_time counts from the start: a
# target whose corpus replay takes longer replays it whole and then stops). With
# --merge, inputs that reach new coverage are merged back into the corpus (-merge=1, which runs
# the corpus once more), so it grows with what fuzzing finds; a maintainer commits that. CI runs
# without it (a clean clone's corpus changes are thrown away). A crash, hang, leak or sanitizer
# report fails the script and leaves its reproducer in build-asan/crashes/.
#   scripts/fuzz.sh [--merge] [seconds] [target...]
# Built in the sanitized build the test suite shares (scripts/sanitized_build.sh: clang, ASan,
# UBSan, coverage instrumentation on every library).
set -euo pipefail
cd "$(dirname "$0")/.."
merge=false
if [ "${1:-}" = --merge ]; then merge=true; shift; fi
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene fuzz_image)
bash scripts/sanitized_build.sh "${targets[@]}"
mkdir -p build-asan/crashes
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp"

# fuzz TARGET: run it, then (with --merge) merge what it found into its corpus.
fuzz() {
    local target=$1 name=${1#fuzz_}
    local corpus=fuzz/corpus/$name found seeds=() max_len=8192
    local t0=$SECONDS
    found=$(mktemp -d)
    mkdir -p "$corpus"
    if [ "$name" = scene ]; then
        # the built-in scenes (only the .toml files of scenes/, not the library's sources)
        # and the error corpus
        cp scenes/*.toml "$found"/
        seeds=(tests/scenes/errors)
    else
        max_len=65536
    fi
    ./build-asan/fuzz/"$target" "$found" "$corpus" "${seeds[@]}" -max_total_time="$seconds" \
        -timeout=60 -rss_limit_mb=2048 -max_len="$max_len" -artifact_prefix=build-asan/crashes/"$name"- \
        -print_final_stats=1 > build-asan/"$target".log 2>&1 \
        || { tail -60 build-asan/"$target".log; rm -rf "$found"; return 1; }
    if $merge; then
        ./build-asan/fuzz/"$target" -merge=1 -max_len="$max_len" -timeout=60 \
            -artifact_prefix=build-asan/crashes/"$name"- "$corpus" "$found" \
            > build-asan/"$target"-merge.log 2>&1 || { tail -20 build-asan/"$target"-merge.log; return 1; }
    fi
    rm -rf "$found"
    local runs cov
    runs=$(awk '/stat::number_of_executed_units/ {print $2}' build-asan/"$target".log)
    cov=$(grep -oE 'cov: [0-9]+' build-asan/"$target".log | tail -1)
    echo "$target: $runs executions in $((SECONDS - t0)) s (corpus first, then fuzzing to ${seconds} s)," \
        "$cov edges, no crash;" \
        "corpus $(ls "$corpus" | wc -l) files"
}
# The targets run side by side, one a core: each libFuzzer process is single-threaded, and most of
# a target's time in CI is its corpus replay (fuzz_scene's ~2 200 inputs take ~3 min under ASan).
# Each target's summary is printed when all are done, in the order given.
pids=()
for t in "${targets[@]}"; do
    fuzz "$t" > build-asan/"$t".summary 2>&1 &
    pids+=($!)
done
status=0
for i in "${!targets[@]}"; do
    wait "${pids[$i]}" || status=1
    cat build-asan/"${targets[$i]}".summary
done
exit "$status"
