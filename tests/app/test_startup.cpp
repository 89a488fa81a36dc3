// SPDX-License-Identifier: Apache-2.0
// The tool starts without the image and video libraries (output/io_module.h): they are in
// libimpulse_io.so, loaded when a command reads or writes a file. Speed is measured in
// bench/startup.sh, not here; these tests guard the mechanism.

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>

#include "output/output.h"
#include "tests/support.h"

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;

/// `impulse` copied alone into `dir`: no module beside it, none in ../lib/impulse.
std::string lone_copy(const TempDir& dir) {
    fs::create_directories(dir / "bin");
    const std::string exe = dir / "bin/impulse";
    fs::copy_file(IMPULSE_BINARY, exe);
    return exe;
}

}  // namespace

TEST_CASE("the tool links no image or video library", "[app][startup]") {
    // What the dynamic loader maps at start (ldd's mechanism): linking OpenImageIO, libav or
    // OpenVDB into the tool again puts ~260 libraries back on every start and fails here.
    TempDir dir;
    const Result r = shell(dir, "LD_TRACE_LOADED_OBJECTS=1 " + quote(IMPULSE_BINARY));
    REQUIRE(r.status == 0);
    REQUIRE_THAT(r.out, Contains("libtbb"));  // the listing is there
    for (const char* lib : {"libOpenImageIO", "libavcodec", "libavformat", "libswscale",
                            "libopenvdb", "libOpenEXR", "libpng"})
        CHECK_THAT(r.out, !Contains(lib));
}

TEST_CASE("help scenes and info run without the module and render names it", "[app][startup]") {
    TempDir dir;
    const std::string exe = quote(lone_copy(dir));
    CHECK(shell(dir, exe + " --help").status == 0);
    const Result scenes = shell(dir, exe + " scenes");
    CHECK(scenes.status == 0);
    CHECK_THAT(scenes.out, Contains("drift"));
    const Result info = shell(dir, exe + " info drift");
    CHECK(info.status == 0);
    CHECK_THAT(info.out, Contains("variance"));
    // A command that writes an image needs the module: one line naming it, nothing written.
    const Result render = shell(dir, exe + " render still --size 32x32 -o " + quote(dir / "s.png"));
    CHECK(render.status == 1);
    CHECK_THAT(render.err, Contains("libimpulse_io.so") && Contains("reinstall"));
    CHECK(render.err_lines().size() == 1);
    CHECK_FALSE(fs::exists(dir / "s.png"));
    // With the module beside it (as built, and as installed under ../lib/impulse), it renders.
    fs::create_directories(dir / "lib/impulse");
    fs::copy_file(fs::path(IMPULSE_BINARY).parent_path() / "libimpulse_io.so",
                  dir / "lib/impulse/libimpulse_io.so");
    CHECK(shell(dir, exe + " render still --size 32x32 -q -o " + quote(dir / "s.png")).status == 0);
    CHECK(fs::exists(dir / "s.png"));
}

TEST_CASE("output.compression chooses the EXR compression and keeps the pixels", "[app][startup]") {
    TempDir dir;
    const std::string scene = "still --size 64x48 -q --set output.compression=";
    for (const char* c : {"none", "zip", "piz"}) {
        const std::string out = dir / (std::string(c) + ".exr");
        REQUIRE(shell(dir, quote(IMPULSE_BINARY) + " render " + scene + "'\"" + c + "\"' -o " +
                               quote(out))
                    .status == 0);
    }
    // Different files, identical pixels: the compression is lossless.
    CHECK(read_file(dir / "none.exr") != read_file(dir / "zip.exr"));
    const auto none = impulse::output::read_image(dir / "none.exr");
    CHECK(impulse::output::read_image(dir / "zip.exr").data == none.data);
    CHECK(impulse::output::read_image(dir / "piz.exr").data == none.data);
    const Result bad = shell(dir, quote(IMPULSE_BINARY) + " render " + scene +
                                      "'\"zipp\"' -o " + quote(dir / "bad.exr"));
    CHECK(bad.status == 1);
    CHECK_THAT(bad.err, Contains("compression") && Contains("dwaa"));
    CHECK_FALSE(fs::exists(dir / "bad.exr"));
}
