#!/usr/bin/env bash
# Installs what impulse needs from Debian's packages (when missing), configures and builds.
#   scripts/setup.sh              the tool: its packages, build/ configured without the tests,
#                                 benches and Python module, and only the `impulse` target built
#                                 (what it links and loads: libimpulse_io.so, impulse-mesh).
#                                 Used by run.sh.
#   scripts/setup.sh --tests      also the packages only the tests, benches and Python module
#                                 need (and the flipbook page's three.js: npm ci in web/flipbook);
#                                 build/ configured with all of them and everything built.
#                                 Used by test.sh.
#   --deps-only                   install, do not build (with --tests: the tests' packages too;
#                                 sanitized_build.sh uses `--tests --deps-only`)
# Safe to run again: it only installs what is missing and rebuilds what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

tests=0
deps_only=0
for arg in "$@"; do
    case "$arg" in
        --tests) tests=1 ;;
        --deps-only) deps_only=1 ;;
        *) echo "setup.sh: unknown option $arg (expected --tests, --deps-only)" >&2; exit 2 ;;
    esac
done

# What building and running the tool needs.
run_packages=(build-essential cmake pkg-config libeigen3-dev libtbb-dev libopenimageio-dev
              libavformat-dev libavcodec-dev libavutil-dev libswscale-dev
              libtomlplusplus-dev libcli11-dev librandom123-dev libfftw3-dev nlohmann-json3-dev
              # `impulse preview`'s server
              libcpp-httplib-dev
              # the charts of `impulse analyze --report`: Vega's modules, read at run time
              libjs-vega
              # volumes (output/) and the porous meshes (mesh/); meshes in and out
              libopenvdb-dev libboost-dev libassimp-dev
              # rebuilds of an unchanged tree (a fresh clone in CI) from the cache
              ccache)

# TEST_ONLY_PACKAGES: what only the tests, the benches and the Python module need. Add a
# package a new test needs here, not above, so `run.sh` stays short on a fresh machine.
test_only_packages=(
          # the Catch2 suite
          catch2
          # the Python module (build/python/) and its pytest suite, which reads images back
          # through oiiotool
          python3-dev pybind11-dev python3-numpy python3-pytest openimageio-tools
          # the preview's browser test (tests/preview/)
          chromium
          # `impulse farm --submit` on a real single-node Slurm (tests/cluster/test_slurm.sh);
          # GNU parallel for the farm's one-machine command line
          slurm-wlm munge parallel
          # the gallery script's test (scripts/gallery.sh: webp pictures)
          webp
          # pip install . and the wheel (python/test_pip_install.sh); the Blender add-on's
          # headless test (blender/test_blender_addon.sh)
          python3-venv python3-pip python3-setuptools python3-wheel python3-build blender
          # the ffmpeg tool: the SSIM of video presets in bench/README.md
          ffmpeg
          # the durable-writes test traces the tool's fsync and rename calls
          # (tests/app/test_durable_writes.sh)
          strace
          # the SIMD-path tests run the command line on emulated CPUs without AVX2 / AVX-512
          # (tests/simd/test_simd_paths.sh, tests/app/test_solid_simd.sh)
          qemu-user)

packages=("${run_packages[@]}")
[ "$tests" -eq 1 ] && packages+=("${test_only_packages[@]}")
# The flipbook page's three.js comes from the npm registry (web/flipbook/package-lock.json): npm,
# from Debian's packages when the machine has no Node.js of its own.
[ "$tests" -eq 1 ] && ! command -v npm > /dev/null && packages+=(nodejs npm)
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

# The flipbook page's test (tests/web/) serves web/flipbook/ with its pinned three.js.
if [ "$tests" -eq 1 ]; then
    (cd web/flipbook && npm ci --no-audit --no-fund --loglevel=error)
fi

[ "$deps_only" -eq 1 ] && exit 0

# ccache, when the machine has it, makes a rebuild of an unchanged tree (a fresh clone in CI) fast.
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# paths inside the checkout hashed relative to it, so clones at other paths share the cache
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"
if [ "$tests" -eq 1 ]; then
    parts=(-DIMPULSE_BUILD_TESTS=ON -DIMPULSE_BUILD_BENCH=ON -DIMPULSE_BUILD_PYTHON=ON)
    targets=(all)
else
    # A build/ that test.sh configured keeps its tests (ctest still finds them); a new one is
    # configured for the tool alone, so configuring needs none of the tests' packages.
    parts=()
    [ -f build/CMakeCache.txt ] ||
        parts=(-DIMPULSE_BUILD_TESTS=OFF -DIMPULSE_BUILD_BENCH=OFF -DIMPULSE_BUILD_PYTHON=OFF)
    targets=(impulse)
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${parts[@]}" "${launcher[@]}" > build.log 2>&1 \
    || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" --target "${targets[@]}" >> build.log 2>&1 \
    || { tail -50 build.log; exit 1; }
