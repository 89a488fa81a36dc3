#!/usr/bin/env bash
# Sets everything up (scripts/setup.sh --tests: the tests' packages too; the tests, benches and
# Python module built beside the tool), then runs the whole test suite (Catch2 tests and
# scripts through CTest), the fast subset again under AddressSanitizer and UBSan
# (scripts/sanitize.sh --fast; the whole suite under them is scripts/sanitize.sh, too long for
# CI), then fuzzes the scene target and the image readers side by side, 45 s each from their start
# or their whole corpus if that is longer (libFuzzer, ASan, UBSan) in the same sanitized build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --tests
ctest --test-dir build --output-on-failure -j"$(nproc)"
bash scripts/sanitize.sh --fast
bash scripts/fuzz.sh 45 fuzz_scene fuzz_image
