#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The same bits on arm64 (README "Other CPUs"; docs/contributing.md "Other CPUs"): cross-builds
# the core libraries and tests/cross's frame dumper for arm64 with Debian's cross compiler,
# against an arm64 Debian root made by mmdebstrap in build-arm64/sysroot (made once, then
# reused), runs it under qemu-aarch64 for every built-in scene's frames 0 and 7, runs the same
# dumper built for this x86-64 machine on each SIMD path (IMPULSE_SIMD = avx512, avx2,
# baseline), and compares the float fields and display RGB byte for byte. Prints a table and
# exits 1 on any difference. Not in CTest: 12 minutes once built (mostly emulation).
#   scripts/arm64_check.sh                 the check
#   scripts/arm64_check.sh --break-fma     the arm64 side compiled with -ffp-contract=fast
#                                          (FMA contraction, GCC's default outside ISO mode):
#                                          shows the check fails, and by how much
#   --size WxH                             the frames' size (default 96x54, as render --size)
#   --scenes "a b"                         only these built-in scenes (default: all of them)
#   --keep                                 keep the frames (build-arm64/frames/)
# Installs what it needs from Debian's packages when missing: g++-aarch64-linux-gnu, mmdebstrap,
# qemu-user (and the core's own -dev packages, through scripts/setup.sh --deps-only).
set -euo pipefail
cd "$(dirname "$0")/.."

size=96x54
break_fma=0
keep=0
only=""
while [ $# -gt 0 ]; do
    case "$1" in
        --break-fma) break_fma=1 ;;
        --keep) keep=1 ;;
        --size) size=${2:?--size needs WxH}; shift ;;
        --scenes) only=${2:?--scenes needs names}; shift ;;
        *) echo "arm64_check.sh: unknown option $1 (expected --break-fma, --size WxH, --scenes \"a b\", --keep)" >&2
           exit 2 ;;
    esac
    shift
done
[[ $size =~ ^[1-9][0-9]*x[1-9][0-9]*$ ]] ||
    { echo "arm64_check.sh: --size $size: expected WxH in pixels, e.g. 96x54" >&2; exit 2; }
start=$(date +%s)
frames=0,7
out=build-arm64
root=$out/sysroot
log=$out/arm64_check.log
mkdir -p "$out"
: > "$log"
step() { echo "== $* ($(($(date +%s) - start)) s)"; }

# --- packages -----------------------------------------------------------------------------------
bash scripts/setup.sh --deps-only
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
need=""
for p in g++-aarch64-linux-gnu mmdebstrap qemu-user; do installed "$p" || need="$need $p"; done
if [ -n "$need" ]; then
    step "installing$need"
    as_root=$([ "$(id -u)" -eq 0 ] || echo sudo)
    $as_root apt-get update -qq &&
        DEBIAN_FRONTEND=noninteractive $as_root apt-get install -y -qq --no-install-recommends $need
fi

# --- the arm64 root -----------------------------------------------------------------------------
# The extract variant unpacks the packages and their dependencies without running any of their
# scripts (no arm64 emulation needed to make it): a root to compile against and for qemu's -L.
# The packages: what the core's headers include (Eigen, oneTBB, toml++, Random123, FFTW,
# nlohmann-json) and the C and C++ runtimes the cross compiler links against.
root_packages=libc6-dev,libstdc++-12-dev,libeigen3-dev,libtbb-dev,libtomlplusplus-dev,librandom123-dev,libfftw3-dev,nlohmann-json3-dev
if [ "$(cat "$root/.packages" 2>/dev/null)" != "$root_packages" ]; then
    step "making the arm64 root $root (mmdebstrap, bookworm)"
    rm -rf "$root" "$root.tmp"
    mmdebstrap --variant=extract --architectures=arm64 --include="$root_packages" bookworm \
        "$root.tmp" >> "$log" 2>&1 || { tail -20 "$log"; exit 1; }
    echo "$root_packages" > "$root.tmp/.packages"
    mv "$root.tmp" "$root"
fi

# --- builds -------------------------------------------------------------------------------------
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
arm=$out/aarch64
if [ "$break_fma" -eq 1 ]; then
    # The deliberate break: every compile of the arm64 side ends with -ffp-contract=fast, which
    # overrides the project's -ffp-contract=off (the last flag wins), so GCC fuses a * b + c into
    # one fmadd where it can.
    arm=$out/aarch64-fma
    mkdir -p "$arm"
    printf '#!/bin/sh\nexec "$@" -ffp-contract=fast\n' > "$arm/contract_fast.sh"
    chmod +x "$arm/contract_fast.sh"
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER="$PWD/$arm/contract_fast.sh")
fi
build() {  # build DIR [cmake options...]
    local dir=$1
    shift
    cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DIMPULSE_CORE_ONLY=ON "$@" >> "$log" 2>&1 ||
        { tail -30 "$log"; exit 1; }
    nice -n 10 cmake --build "$dir" -j"$(nproc)" --target impulse_frame_dump >> "$log" 2>&1 ||
        { tail -30 "$log"; exit 1; }
}
step "building the frame dumper for x86-64 ($out/x86_64)"
build "$out/x86_64" -DCMAKE_CXX_COMPILER_LAUNCHER=ccache
step "cross-building it for arm64 ($arm)"
build "$arm" "${launcher[@]}" -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake \
    -DIMPULSE_ARM64_ROOT="$PWD/$root"
x86_dump=$out/x86_64/tests/cross/impulse_frame_dump
arm_dump=$arm/tests/cross/impulse_frame_dump

# --- frames -------------------------------------------------------------------------------------
scenes=$only
[ -n "$scenes" ] || scenes=$(ls scenes/*.toml | xargs -n1 basename | sed 's/\.toml$//')
dir=$out/frames
rm -rf "$dir" && mkdir -p "$dir"
[ "$keep" -eq 1 ] || trap 'rm -rf "$dir"' EXIT
paths=(avx512 avx2 baseline arm64)
# The root's libraries are found through qemu's -L, which maps the guest's /usr/lib to the root's.
arm_run=(qemu-aarch64 -L "$root" -E LD_LIBRARY_PATH=/usr/lib/aarch64-linux-gnu:/lib/aarch64-linux-gnu)
for scene in $scenes; do
    for path in "${paths[@]:0:3}"; do
        t0=$(date +%s)
        IMPULSE_SIMD=$path "$x86_dump" "$scene" "$size" "$frames" "$dir/$scene-$path"
        echo "$scene $path $(($(date +%s) - t0)) s" >> "$log"
    done
    step "$scene under qemu-aarch64"
    t0=$(date +%s)
    "${arm_run[@]}" "$arm_dump" "$scene" "$size" "$frames" "$dir/$scene-arm64"
    echo "$scene arm64 $(($(date +%s) - t0)) s" >> "$log"
done

# --- the table ----------------------------------------------------------------------------------
step "comparing"
status=0
python3 scripts/compare_frames.py "$dir" "$size" "$frames" avx512 "${paths[*]:1}" $scenes || status=$?
echo "arm64_check: $(($(date +%s) - start)) s; the arm64 side $( [ "$break_fma" -eq 1 ] &&
    echo "with -ffp-contract=fast (the deliberate break)" || echo "as the project builds it")"
exit $status
