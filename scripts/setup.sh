#!/usr/bin/env bash
# Installs what impulse needs from Debian's packages (when missing), configures and builds.
# Used by run.sh, test.sh and sanitize.sh (--deps-only: install, do not build); safe to run
# again (it only installs what is missing).
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake pkg-config libeigen3-dev libtbb-dev libopenimageio-dev
          libavformat-dev libavcodec-dev libavutil-dev libswscale-dev catch2
          libtomlplusplus-dev libcli11-dev librandom123-dev libfftw3-dev nlohmann-json3-dev parallel
          openimageio-tools slurm-wlm munge libopenvdb-dev libboost-dev webp libassimp-dev
          # rebuilds of an unchanged tree (a fresh clone, the sanitized build) from the cache
          ccache
          # the Python module (build/python/) and its tests; the preview server and its
          # browser test
          python3-dev pybind11-dev python3-numpy python3-pytest libcpp-httplib-dev chromium
          python3-venv python3-pip python3-setuptools python3-wheel python3-build blender  # python/test_pip_install.sh, blender/test_blender_addon.sh
          # the ffmpeg tool: the SSIM of video presets in bench/README.md
          ffmpeg
          # the SIMD-path tests run the command line on emulated CPUs without AVX2 / AVX-512
          # (tests/simd/test_simd_paths.sh, tests/app/test_solid_simd.sh)
          qemu-user)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing: ${missing[*]}"
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

[ "${1:-}" = "--deps-only" ] && exit 0

# ccache, when the machine has it, makes a rebuild of an unchanged tree (a fresh clone in CI) fast.
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# paths inside the checkout hashed relative to it, so clones at other paths share the cache
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" > build.log 2>&1 \
    || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
