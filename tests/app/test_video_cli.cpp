// SPDX-License-Identifier: Apache-2.0
// `impulse render` on an animated scene, run as separate processes (design.md §4): videos
// (frame count, size, frame rate; FFV1 decoded back against the PNG sequence), sequence
// patterns, --resume, split frame ranges in two processes and under GNU parallel giving the
// same bytes as one run, and the refusals (frame range, codec, output directory).

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"

namespace output = impulse::output;
namespace render = impulse::render;

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;

/// Names of the entries of a directory, sorted.
std::vector<std::string> entries(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

/// `impulse render <args>` (quiet).
Result impulse_render(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " render " + args + " -q");
}

/// A tiny animated scene: 64x48 (even, for 4:2:0 codecs), 24 fps, wind + vortex, Hann lifetimes.
std::string write_scene(const TempDir& dir, int frames) {
    const std::string path = dir / "scene.toml";
    write_file(path,
               "[output]\nsize = [64, 48]\nfps = 24\nframes = " + std::to_string(frames) +
                   "\ncodec = \"auto\"\npreset = \"ultrafast\"\n\n"
                   "[[layer]]\nseed = 21\ndensity = 16.0\nlifetime = 1.0\nenvelope = \"hann\"\n"
                   "[layer.kernel]\ntype = \"cosine\"\nradius = 6.0\n\n"
                   "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [20.0, 6.0]\n\n"
                   "[[layer.flow]]\ntype = \"vortex\"\ncenter = [32.0, 24.0]\n"
                   "circulation = 1500.0\ncore = 12.0\n");
    return path;
}

bool has_parallel() { return std::system("parallel --version >/dev/null 2>&1 </dev/null") == 0; }

}  // namespace

TEST_CASE("video CLI: an mp4 holds the requested frames at the scene's size and rate",
          "[cli][video]") {
    TempDir dir;
    const std::string scene = write_scene(dir, 30);
    const Result r =
        impulse_render(dir, quote(scene) + " -o " + quote(dir / "out.mp4") + " --frames 0-23");
    INFO(r.err);
    REQUIRE(r.status == 0);
    const output::VideoInfo info = output::probe_video(dir / "out.mp4");
    CHECK(info.frame_count == 24);
    CHECK(info.width == 64);
    CHECK(info.height == 48);
    CHECK(info.fps == Approx(24.0).margin(1e-9));
    CHECK(info.codec_name == "h264");
    // Only the video: no temporary left beside it.
    CHECK(entries(dir.path()) == std::vector<std::string>{"out.mp4", "scene.toml"});
}

TEST_CASE("video CLI: an mp4 has the same bytes with 1 and 2 threads", "[cli][video][determinism]") {
    // The render loop overlaps rendering frame f + 1 with encoding frame f, the shading writes
    // the encoder's planes in parallel bands, and x264 runs kEncoderThreads frame threads
    // whatever --threads says: the file must not depend on any of it. drift's own preset
    // (veryfast) and shading, a few frames at a small size.
    TempDir dir;
    std::string bytes[3];
    const char* runs[3] = {"--threads 1", "--threads 2", ""};
    for (int i = 0; i < 3; ++i) {
        const fs::path out = dir / ("t" + std::to_string(i) + ".mp4");
        const Result r = impulse_render(dir, std::string("drift --size 192x108 --frames 0-9 ") +
                                                 runs[i] + " -o " + quote(out));
        INFO(r.err);
        REQUIRE(r.status == 0);
        bytes[i] = read_file(out);
    }
    REQUIRE(bytes[0].size() > 1000);
    CHECK(bytes[0] == bytes[1]);
    CHECK(bytes[0] == bytes[2]);
    CHECK(output::probe_video(dir / "t0.mp4").frame_count == 10);
}

TEST_CASE("video CLI: FFV1 decodes back to the PNG sequence of the same frames", "[cli][video]") {
    // Both paths quantise the same display value m = (v - lo) / (hi - lo) to 8 bits: the PNG by
    // OIIO's round-to-nearest, the video writer by clamp * 255 + 0.5 (the same, up to float ties:
    // <= 1 LSB between them). FFV1 stores the grey RGB triple losslessly (BGR0); the decoder's
    // luma is swscale's fixed-point BT.709 reduction 0.2126 R + 0.7152 G + 0.0722 B of R = G = B,
    // exact up to its rounding: <= 1 LSB. Hence |video - png| <= 2/255.
    TempDir dir;
    const std::string scene = write_scene(dir, 12);
    fs::create_directories(dir.path() / "png");
    const Result v = impulse_render(dir, quote(scene) + " -o " + quote(dir / "out.mkv"));
    INFO(v.err);
    REQUIRE(v.status == 0);
    const Result p = impulse_render(dir, quote(scene) + " -o " + quote(dir / "png/f_####.png"));
    INFO(p.err);
    REQUIRE(p.status == 0);
    const output::VideoInfo info = output::probe_video(dir / "out.mkv");
    CHECK(info.codec_name == "ffv1");
    int w = 0, h = 0;
    const auto frames = output::decode_video_luma(dir / "out.mkv", w, h);
    REQUIRE(frames.size() == 12);
    REQUIRE(w == 64);
    REQUIRE(h == 48);
    double worst = 0.0, spread = 0.0;
    for (size_t f = 0; f < frames.size(); ++f) {
        char name[32];
        std::snprintf(name, sizeof name, "png/f_%04zu.png", f);
        const render::Frame png = output::read_image(dir / name);
        REQUIRE(png.width == 64);
        REQUIRE(png.height == 48);
        for (size_t i = 0; i < png.data.size(); ++i) {
            worst = std::max(worst, std::abs(double(frames[f][i]) - png.data[i]));
            spread = std::max(spread, std::abs(double(png.data[i]) - png.data[0]));
        }
    }
    if (std::getenv("IMPULSE_TEST_REPORT"))
        std::printf("[ffv1] max |video - png| = %.5f = %.2f LSB (band 2 LSB)\n", worst,
                    worst * 255.0);
    CHECK(spread > 0.2);  // the frames carry an image, not a flat grey
    CHECK(worst <= 2.0 / 255.0 + 1e-6);
}

TEST_CASE("video CLI: a sequence pattern writes exactly the requested frames", "[cli]") {
    TempDir dir;
    const std::string scene = write_scene(dir, 10);
    fs::create_directories(dir.path() / "seq");
    const Result r = impulse_render(
        dir, quote(scene) + " -o " + quote(dir / "seq/f_####.png") + " --frames 3-5");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(entries(dir.path() / "seq") ==
          std::vector<std::string>{"f_0003.png", "f_0004.png", "f_0005.png"});
}

TEST_CASE("video CLI: --resume skips frames that exist and writes the others", "[cli]") {
    TempDir dir;
    const std::string scene = write_scene(dir, 10);
    fs::create_directories(dir.path() / "seq");
    fs::create_directories(dir.path() / "plain");
    REQUIRE(impulse_render(
                dir, quote(scene) + " -o " + quote(dir / "plain/f_####.png") + " --frames 3-5")
                .status == 0);
    // A frame that checks out (test_data_loss.cpp: the ones that do not) is kept as it is.
    fs::copy_file(dir / "plain/f_0004.png", dir / "seq/f_0004.png");
    const auto stamp = fs::file_time_type::clock::now() - std::chrono::hours(1);
    fs::last_write_time(dir / "seq/f_0004.png", stamp);
    const Result r = impulse_render(
        dir, quote(scene) + " -o " + quote(dir / "seq/f_####.png") + " --frames 3-5 --resume");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.empty());
    CHECK_THAT(r.out, Contains("(2 frames, 1 already present,"));
    CHECK(fs::last_write_time(dir / "seq/f_0004.png") == stamp);
    CHECK(entries(dir.path() / "seq") ==
          std::vector<std::string>{"f_0003.png", "f_0004.png", "f_0005.png"});
    // The written ones are the frames a plain run writes.
    CHECK(read_file(dir / "seq/f_0003.png") == read_file(dir / "plain/f_0003.png"));
    CHECK(read_file(dir / "seq/f_0005.png") == read_file(dir / "plain/f_0005.png"));
}

TEST_CASE("video CLI: a range split across two processes gives the same EXR bytes as one run",
          "[cli][determinism]") {
    TempDir dir;
    const std::string scene = write_scene(dir, 10);
    fs::create_directories(dir.path() / "one");
    fs::create_directories(dir.path() / "split");
    REQUIRE(
        impulse_render(dir, quote(scene) + " -o " + quote(dir / "one/f_####.exr") + " --frames 0-9")
            .status == 0);
    REQUIRE(impulse_render(
                dir, quote(scene) + " -o " + quote(dir / "split/f_####.exr") + " --frames 0-4")
                .status == 0);
    REQUIRE(impulse_render(
                dir, quote(scene) + " -o " + quote(dir / "split/f_####.exr") + " --frames 5-9")
                .status == 0);
    const auto names = entries(dir.path() / "one");
    REQUIRE(names.size() == 10);
    CHECK(entries(dir.path() / "split") == names);
    for (const auto& n : names) {
        INFO(n);
        CHECK(read_file(dir / ("one/" + n)) == read_file(dir / ("split/" + n)));
    }
    // Not trivially equal: frames differ from each other.
    CHECK(read_file(dir / "one/f_0000.exr") != read_file(dir / "one/f_0009.exr"));
}

TEST_CASE("video CLI: GNU parallel over frame ranges gives the same EXR bytes as one run",
          "[cli][determinism]") {
    if (!has_parallel()) {
        WARN("GNU parallel is not installed: skipped");
        return;
    }
    TempDir dir;
    const std::string scene = write_scene(dir, 10);
    fs::create_directories(dir.path() / "one");
    fs::create_directories(dir.path() / "par");
    REQUIRE(impulse_render(dir, quote(scene) + " -o " + quote(dir / "one/f_####.exr")).status == 0);
    const Result r = shell(dir, "parallel --will-cite -j 3 " + quote(IMPULSE_BINARY) + " render " +
                                    quote(scene) + " -o " + quote(dir / "par/f_####.exr") +
                                    " --frames {} -q ::: 0-2 3-6 7-9");
    INFO(r.err);
    REQUIRE(r.status == 0);
    const auto names = entries(dir.path() / "one");
    REQUIRE(names.size() == 10);
    CHECK(entries(dir.path() / "par") == names);
    for (const auto& n : names) {
        INFO(n);
        CHECK(read_file(dir / ("one/" + n)) == read_file(dir / ("par/" + n)));
    }
}

TEST_CASE("video CLI: bad requests are refused with the reason and write nothing",
          "[cli][errors]") {
    TempDir dir;
    const std::string scene = write_scene(dir, 10);

    SECTION("a frame range beyond the scene") {
        const Result r =
            impulse_render(dir, quote(scene) + " -o " + quote(dir / "out.mp4") + " --frames 0-99");
        CHECK(r.status != 0);
        CHECK_THAT(r.err, Contains("--frames"));
        CHECK_THAT(r.err, Contains("0-99"));
        CHECK_FALSE(fs::exists(dir / "out.mp4"));
    }
    SECTION("an unknown codec") {
        const Result r =
            impulse_render(dir, quote(scene) + " -o " + quote(dir / "out.mp4") + " --codec h265x");
        CHECK(r.status != 0);
        CHECK_THAT(r.err, Contains("h265x"));
        for (const char* codec : {"h264", "prores", "ffv1", "vp9"})
            CHECK_THAT(r.err, Contains(codec));
        CHECK_FALSE(fs::exists(dir / "out.mp4"));
    }
    SECTION("a missing output directory") {
        const std::string missing = dir / "no/such/dir";
        const Result r = impulse_render(dir, quote(scene) + " -o " + quote(missing + "/out.mp4"));
        CHECK(r.status != 0);
        CHECK_THAT(r.err, Contains(missing));
        CHECK_FALSE(fs::exists(dir / "no"));
        const Result s =
            impulse_render(dir, quote(scene) + " -o " + quote(missing + "/f_####.png"));
        CHECK(s.status != 0);
        CHECK_THAT(s.err, Contains(missing));
        CHECK_FALSE(fs::exists(dir / "no"));
    }
    // Nothing but the scene in the directory, whatever was refused.
    CHECK(entries(dir.path()) == std::vector<std::string>{"scene.toml"});
}
