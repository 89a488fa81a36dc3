#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Solid noise gives the same bits whatever loop the CPU runs (docs/solid.md "Determinism"):
# `impulse synth solid` on a small grid (EXR) and at points (CSV), with the AVX2 loops where the
# CPU has them, then with IMPULSE_SIMD=baseline, then (`nehalem`) under `qemu-x86_64 -cpu Nehalem`,
# an emulated CPU without AVX2; the outputs must be byte-identical.
# Usage: test_solid_simd.sh IMPULSE_BINARY baseline|nehalem. Exit 77 (CTest's skip) for nehalem
# when qemu-x86_64 is not installed (scripts/setup.sh installs Debian's qemu-user).
set -uo pipefail
impulse=$(realpath "$1")
mode=$2
skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }

if [ "$mode" = nehalem ]; then
    qemu=$(command -v qemu-x86_64) || skip "qemu-x86_64 not found (Debian's qemu-user)"
    # An ASan binary reserves terabytes of shadow address space, which qemu-user cannot map.
    [ -z "${IMPULSE_SANITIZED:-}" ] || skip "qemu-user cannot run a sanitized binary (the release build runs this test)"
    run_other() { "$qemu" -cpu Nehalem "$impulse" "$@"; }
else
    run_other() { IMPULSE_SIMD=baseline "$impulse" "$@"; }
fi
work=$(mktemp -d "${TMPDIR:-/tmp}/impulse-simd-XXXXXX") || fail "mktemp"
trap 'rm -rf "$work"' EXIT
# Points: a few hundred scattered (whole cells) and a dense block (half cells), both loops.
awk 'BEGIN { for (i = 0; i < 300; i++) printf "%.4f,%.4f,%.4f\n", (i * 7.31) % 61 - 20, (i * 3.17) % 47, (i * 1.93) % 29 - 9;
             for (z = 0; z < 6; z++) for (y = 0; y < 6; y++) for (x = 0; x < 6; x++) printf "%.2f,%.2f,%.2f\n", x * 0.5, y * 0.5 + 3, z * 0.5 }' \
    > "$work/points.csv"
cases=("--method sparse --radius 4 --density 16 --size 20x18x12"
       "--method sparse --kernel gaussian --radius 3 --density 30 --size 16x16x8"
       "--method sparse --kernel autocorrelation --model gaussian --length 3 --size 12x12x6"
       "--method sparse --radius 5 --points $work/points.csv"
       "--method perlin --radius 4 --points $work/points.csv")
n=0
for c in "${cases[@]}"; do
    n=$((n + 1))
    ext=exr
    case "$c" in *--points*) ext=csv ;; esac
    # shellcheck disable=SC2086
    "$impulse" synth solid $c --seed 3 -o "$work/native$n.$ext" || fail "native run: $c"
    # shellcheck disable=SC2086
    run_other synth solid $c --seed 3 -o "$work/other$n.$ext" || fail "$mode run: $c"
    cmp -s "$work/native$n.$ext" "$work/other$n.$ext" || fail "$mode output differs from the native one: $c"
    echo "same bytes ($mode): $c ($(stat -c %s "$work/native$n.$ext") bytes)"
done
echo "PASSED: $n cases byte-identical ($mode)"
