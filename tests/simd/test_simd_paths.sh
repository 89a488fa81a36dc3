#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The vectorised loops have the same bits on every path: renders small frames of built-in scenes
# with IMPULSE_SIMD forced to avx512, avx2 and baseline and compares the files byte for byte.
# With --qemu CPU...: instead renders on emulated CPUs (qemu-x86_64 -cpu Nehalem: no AVX;
# Haswell: AVX2 without AVX-512) and compares with this machine's render; exit 77 (skipped) when
# qemu-x86_64 is not installed.
# Usage: test_simd_paths.sh IMPULSE_BINARY [--qemu CPU...]
set -euo pipefail
impulse=$1
shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

render() {  # render OUT SCENE SIZE [launcher...]
    local out=$1 scene=$2 size=$3
    shift 3
    "$@" "$impulse" render "$scene" --frames 0 --size "$size" -q -o "$out" > /dev/null
}

same() {  # same A B WHAT
    if cmp -s "$1" "$2"; then
        echo "ok: $3"
    else
        echo "FAIL: $3: $(basename "$1") and $(basename "$2") differ"
        fail=1
    fi
}

if [[ ${1:-} == --qemu ]]; then
    shift
    command -v qemu-x86_64 > /dev/null || { echo "skipped: qemu-x86_64 not installed"; exit 77; }
    # An ASan binary reserves terabytes of shadow address space, which qemu-user cannot map.
    [ -z "${IMPULSE_SANITIZED:-}" ] || { echo "skipped: qemu-user cannot run a sanitized binary (the release build runs this test)"; exit 77; }
    # One tiny frame: the emulator runs AVX code a hundred times slower than the machine (and
    # a scene's set-up takes seconds there), so only the cosine scene, a few seconds a CPU.
    for scene in still; do
        render "$tmp/$scene.exr" "$scene" 48x27
        for cpu in "$@"; do
            render "$tmp/$scene-$cpu.exr" "$scene" 48x27 qemu-x86_64 -cpu "$cpu" 2> /dev/null
            same "$tmp/$scene.exr" "$tmp/$scene-$cpu.exr" "$scene on this CPU and on qemu -cpu $cpu"
        done
    done
    exit $fail
fi

# Orthographic scenes of every evaluator loop the gallery uses: cosine (polynomial envelope,
# the isotropic loop), gabor (rotated carrier), gaussian (separable), and a perspective sky.
for scene in still veins marble fire ink clouds; do
    for path in avx512 avx2 baseline; do
        IMPULSE_SIMD=$path render "$tmp/$scene-$path.exr" "$scene" 160x90
    done
    same "$tmp/$scene-avx512.exr" "$tmp/$scene-avx2.exr" "$scene: avx512 = avx2"
    same "$tmp/$scene-avx512.exr" "$tmp/$scene-baseline.exr" "$scene: avx512 = baseline"
done
# A kernel scale field (examples/scale_field.toml): its classes of scaled kernels, too.
example=$(dirname "$0")/../../examples/scale_field.toml
for path in avx512 avx2 baseline; do
    IMPULSE_SIMD=$path render "$tmp/scale-$path.exr" "$example" 160x90
done
same "$tmp/scale-avx512.exr" "$tmp/scale-avx2.exr" "scale field: avx512 = avx2"
same "$tmp/scale-avx512.exr" "$tmp/scale-baseline.exr" "scale field: avx512 = baseline"
# A misspelt path is refused with one line naming the variable, not silently ignored.
if IMPULSE_SIMD=avx3 render "$tmp/bad.exr" still 16x9 2> "$tmp/err"; then
    echo "FAIL: IMPULSE_SIMD=avx3 was accepted"
    fail=1
elif ! grep -q 'IMPULSE_SIMD = "avx3": expected one of baseline, avx2, avx512' "$tmp/err"; then
    echo "FAIL: IMPULSE_SIMD=avx3: unexpected message: $(cat "$tmp/err")"
    fail=1
fi
[[ ! -e $tmp/bad.exr ]] || { echo "FAIL: a file was written for IMPULSE_SIMD=avx3"; fail=1; }
exit $fail
