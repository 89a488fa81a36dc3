#!/usr/bin/env bash
# Builds impulse with AddressSanitizer and UBSan (scripts/sanitized_build.sh: clang,
# RelWithDebInfo, -fno-sanitize-recover, in build-asan/, shared with the fuzz targets) and runs the test suite under it with ctest -j2; fails on a failing test and on any
# sanitizer report, including one from a child process (the CLI tests run the impulse binary and
# may expect it to fail: its report goes to a log file, not to the exit status a test checks).
#   scripts/sanitize.sh          the whole suite
#   scripts/sanitize.sh --fast   the fast subset CI runs: the tests labelled kernels and scenes
#                                but those tagged [slow] (below): kernel design and tables, the
#                                scene loader, its error corpus, the built-in scenes and the
#                                docs' scenes, composition; building only their two test programs
set -euo pipefail
cd "$(dirname "$0")/.."
fast=0
[ "${1:-}" = "--fast" ] && fast=1
build=build-asan
targets=(all)
selection=()
# The fast subset leaves out the tests tagged [slow]: each took over 20 s under the sanitizers on
# the 2-core machine (up to 520 s: they render many fields to measure a spectrum, a marginal or
# a law, at sizes a statistic needs). The code they run is run here by smaller tests and by the
# fuzz targets; the whole suite under the sanitizers (no --fast) runs them. In CI the subset
# takes ~5 minutes; with them it took ~30.
[ "$fast" -eq 1 ] && targets=(test_kernels test_scenes)
bash scripts/sanitized_build.sh "${targets[@]}"
if [ "$fast" -eq 1 ]; then
    # ctest -E takes a regex: the [slow] tests' names as listed by their programs, escaped
    # (Catch2's --list-test-names-only exits with the number of tests listed).
    slow=$(for t in test_kernels test_scenes; do
               { "$build/tests/$t" --list-test-names-only "[slow]" || true; } | sed '/^$/d'
           done | sed 's/[][\\.*^$()+?{}|]/\\&/g' | paste -sd'|')
    [ -n "$slow" ] || { echo "sanitize: no [slow] test listed (tags renamed?)"; exit 1; }
    selection=(-L '^(kernels|scenes)$' -E "^($slow)\$")
fi

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
