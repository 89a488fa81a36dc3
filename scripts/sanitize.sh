#!/usr/bin/env bash
# Builds impulse with AddressSanitizer and UBSan (scripts/sanitized_build.sh: clang,
# RelWithDebInfo, -fno-sanitize-recover, in build-asan/, shared with the fuzz targets) and runs the test suite under it with ctest -j2; fails on a failing test and on any
# sanitizer report, including one from a child process (the CLI tests run the impulse binary and
# may expect it to fail: its report goes to a log file, not to the exit status a test checks).
#   scripts/sanitize.sh          the whole suite
#   scripts/sanitize.sh --fast   the fast subset CI runs: the tests labelled kernels and scenes
#                                but the five heaviest (below)
#                                (kernel design and tables, the scene loader, its error corpus,
#                                composition), building only their two test programs
set -euo pipefail
cd "$(dirname "$0")/.."
fast=0
[ "${1:-}" = "--fast" ] && fast=1
build=build-asan
targets=(all)
selection=()
# The fast subset leaves out the five statistical tests that take longest under ASan (each
# 35-600 s on the 2-core machine: they render 1024^2 fields many times to measure a spectrum or a
# marginal). The code they run is run here by smaller tests (ITAM, the kernel design, the shot-noise
# law, the shaping); the whole suite under the sanitizers (no --fast) runs them.
heavy='^(pre-correction gives the shaped field|designed kernels reproduce the target spectrum in a rendered'
heavy+='|scene kernels of type spectrum and autocorrelation|shaped marginals are within KS 0.01'
heavy+='|the shot-noise law matches a direct simulation)'
[ "$fast" -eq 1 ] && targets=(test_kernels test_scenes) && selection=(-L '^(kernels|scenes)$' -E "$heavy")
bash scripts/sanitized_build.sh "${targets[@]}"

reports="$PWD/$build/sanitizer-reports"
rm -rf "$reports" && mkdir -p "$reports"
export ASAN_OPTIONS="log_path=$reports/asan:detect_leaks=1"
export UBSAN_OPTIONS="log_path=$reports/ubsan:print_stacktrace=1:halt_on_error=1"
# print_suppressions=0: a suppressed leak (fuzz/lsan.supp) is not a report; its summary would
# land in the reports folder and fail the run.
export LSAN_OPTIONS="suppressions=$PWD/fuzz/lsan.supp:print_suppressions=0"
start=$SECONDS
status=0
ctest --test-dir "$build" --output-on-failure -j2 "${selection[@]}" || status=$?
if compgen -G "$reports/*" > /dev/null; then
    echo "sanitize: sanitizer reports:"
    for f in "$reports"/*; do echo "== $f"; head -40 "$f"; done
    exit 1
fi
[ "$status" -eq 0 ] || { echo "sanitize: failing tests (see above)"; exit "$status"; }
echo "sanitize: every selected test passes under ASan+UBSan with no sanitizer report" \
    "($((SECONDS - start)) s)"
