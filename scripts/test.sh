#!/usr/bin/env bash
# Sets everything up, then runs the whole test suite (Catch2 tests through CTest), then fuzzes
# the scene loader for a bounded minute (libFuzzer, AddressSanitizer and UBSan).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
ctest --test-dir build --output-on-failure -j"$(nproc)"
bash scripts/fuzz.sh 60
