#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# `cmake --install` into a temporary prefix, then a tiny consumer project built against the
# installed tree twice: with find_package(impulse) (imported target impulse::scenes) and with
# pkg-config (impulse.pc). Each renders a 16x16 frame of a scene given as a string and prints
# its mean: the two must agree. The installed tool renders and lists its built-in scenes. The
# installed headers are the facades and their lists, named as a consumer writes them
# (<impulse/scenes/scenes.h>; docs/design.md §2 "Facades"): the short in-tree name does not
# compile against them, and no detail/ or app/ header is installed.
# Usage: test_install.sh BUILD_DIR
set -euo pipefail
# A sanitized build installs instrumented libraries that only a consumer compiled with the same
# sanitizer and coverage options could link; the release build runs this test.
[ -z "${IMPULSE_SANITIZED:-}" ] || { echo "SKIPPED: a sanitized build's install (the release build runs this test)"; exit 77; }
build=$(realpath "$1")
work=$(mktemp -d "${TMPDIR:-/tmp}/impulse-install-XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log" || { cat "$work/install.log"; exit 1; }
for f in bin/impulse lib/impulse/libimpulse_io.so include/impulse/scenes/scenes.h lib/libimpulse_scenes.a \
         lib/cmake/impulse/impulseConfig.cmake lib/pkgconfig/impulse.pc share/impulse/scenes/still.toml; do
    [ -e "$prefix/$f" ] || { echo "FAILED: $f not installed"; exit 1; }
done

for f in include/impulse/app include/impulse/scenes/detail include/impulse/render/detail lib/libimpulse_app.a; do
    [ ! -e "$prefix/$f" ] || { echo "FAILED: $f installed (internal, not the API)"; exit 1; }
done
if grep -rn '#include "' "$prefix/include/impulse" | grep -v '#include "[^/"]*"$' | head -3 | grep .; then
    echo "FAILED: installed headers include the project's headers by their in-tree names"; exit 1
fi

mkdir -p "$work/consumer"
cat >"$work/consumer/main.cpp" <<'CPP'
// A consumer of the installed impulse: one small frame of a scene given as text.
#include <cstdio>

#include <impulse/scenes/scenes.h>

int main() {
    auto scene = impulse::scenes::load_scene_string(
        "[output]\nsize = [16, 16]\nframes = 1\n[[layer]]\nseed = 3\n"
        "[layer.kernel]\ntype = \"cosine\"\nradius = 4.0\n",
        "consumer.toml");
    impulse::scenes::Renderer renderer(std::move(scene));
    impulse::render::Frame frame;
    renderer.render(0, frame);
    double sum = 0;
    for (float v : frame.data) sum += v;
    std::printf("%dx%d mean %.9g\n", frame.width, frame.height, sum / double(frame.data.size()));
    return 0;
}
CPP
cat >"$work/consumer/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.20)
project(consumer LANGUAGES CXX)
set(CMAKE_CXX_STANDARD 20)
find_package(impulse 0.1 REQUIRED)
add_executable(consumer main.cpp)
target_link_libraries(consumer PRIVATE impulse::scenes)
CMAKE
cmake -S "$work/consumer" -B "$work/consumer/build" -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/consumer/build" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
with_cmake=$("$work/consumer/build/consumer")

PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs impulse >"$work/flags" ||
    { echo "FAILED: pkg-config impulse"; exit 1; }
# shellcheck disable=SC2046
c++ -O2 "$work/consumer/main.cpp" -o "$work/consumer/with_pc" $(cat "$work/flags") 2>"$work/pc.log" ||
    { echo "FAILED: c++ \$(pkg-config --cflags --libs impulse):"; cat "$work/pc.log"; exit 1; }
with_pc=$("$work/consumer/with_pc")
# The in-tree name is not a name of the installed tree.
printf '#include "scenes/scenes.h"\nint main() { return 0; }\n' >"$work/short.cpp"
if c++ -fsyntax-only "$work/short.cpp" $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags impulse) 2>/dev/null; then
    echo "FAILED: #include \"scenes/scenes.h\" compiles against the installed tree"; exit 1
fi

# The installed tool on the same scene.
printf '[output]\nsize = [16, 16]\nframes = 1\n[[layer]]\nseed = 3\n[layer.kernel]\ntype = "cosine"\nradius = 4.0\n' \
    >"$work/consumer.toml"
"$prefix/bin/impulse" render "$work/consumer.toml" -o "$work/frame.exr" -q >/dev/null
"$prefix/bin/impulse" scenes | grep -q '^still' || { echo "FAILED: installed impulse scenes"; exit 1; }
echo "find_package: $with_cmake; pkg-config: $with_pc"
[ "$with_cmake" = "$with_pc" ] || { echo "FAILED: the two consumers differ"; exit 1; }
[[ "$with_cmake" == "16x16 mean "* ]] || { echo "FAILED: unexpected output"; exit 1; }
echo "PASSED"
