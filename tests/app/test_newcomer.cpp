// SPDX-License-Identifier: Apache-2.0
// What a newcomer types (issue 14): --size keeps the scene's view, --crop crops; a default
// output; --version; "did you mean" for scene names; whole descriptions from `impulse scenes`;
// sequence patterns that are refused or padded; analyze --json FILE and sequences that do not
// start at frame 0.

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "app/commands.h"
#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"
#include "numeric/errors.h"

namespace {

using namespace impulse::test;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " " + args);
}

// Broad Gaussian kernels on a flat camera: at half the resolution a kernel is still 4 pixels
// wide (sigma), so the half-size picture is the full one averaged 2x2, up to the pyramid's
// filtering and the quantisation.
const char* kFlat = R"([output]
size = [256, 192]
range = [-3.0, 3.0]
[[layer]]
seed = 5
density = 12.0
[layer.kernel]
type = "gaussian"
radius = 24.0
sigma = 8.0
)";

/// Correlation coefficient of two equal-sized frames.
double correlation(const impulse::render::Frame& a, const impulse::render::Frame& b) {
    REQUIRE(a.data.size() == b.data.size());
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.data.size(); ++i) ma += a.data[i], mb += b.data[i];
    ma /= double(a.data.size()), mb /= double(b.data.size());
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double x = a.data[i] - ma, y = b.data[i] - mb;
        sab += x * y, saa += x * x, sbb += y * y;
    }
    return sab / std::sqrt(saa * sbb);
}

}  // namespace

TEST_CASE("render --size renders the same view at another resolution and --crop crops", "[cli][size]") {
    TempDir dir("size");
    write_file(dir / "flat.toml", kFlat);
    const std::string scene = quote(dir / "flat.toml");
    REQUIRE(run(dir, "render " + scene + " -o " + quote(dir / "full.exr")).status == 0);
    REQUIRE(run(dir, "render " + scene + " --size 128x96 -o " + quote(dir / "half.exr")).status == 0);
    REQUIRE(run(dir, "render " + scene + " --crop 128x96 -o " + quote(dir / "crop.exr")).status == 0);
    REQUIRE(run(dir, "render " + scene + " --size 256x192 -o " + quote(dir / "own.exr")).status == 0);
    const auto full = impulse::output::read_image(dir / "full.exr");
    const auto half = impulse::output::read_image(dir / "half.exr");
    const auto crop = impulse::output::read_image(dir / "crop.exr");
    REQUIRE(half.width == 128);
    REQUIRE(half.height == 96);
    // The full picture averaged over 2x2 pixels is the half one: the same texture region, the
    // same kernels in texture units. A crop (the old --size) shares only a quarter of it and
    // correlates with it about as much as two independent fields (|r| < 0.3 here).
    impulse::render::Frame down;
    down.resize(128, 96);
    for (int y = 0; y < 96; ++y)
        for (int x = 0; x < 128; ++x)
            down.data[size_t(y) * 128 + x] = 0.25f * (full.at(2 * x, 2 * y) + full.at(2 * x + 1, 2 * y) +
                                                      full.at(2 * x, 2 * y + 1) + full.at(2 * x + 1, 2 * y + 1));
    CHECK(correlation(down, half) > 0.97);
    CHECK(std::abs(correlation(down, crop)) < 0.5);
    // The crop is the full picture's top-left window, pixel for pixel.
    double worst = 0;
    for (int y = 0; y < 96; ++y)
        for (int x = 0; x < 128; ++x) worst = std::max(worst, double(std::abs(crop.at(x, y) - full.at(x, y))));
    CHECK(worst < 1e-5);
    // The scene's own size changes nothing: the same bytes.
    CHECK(read_file(dir / "own.exr") == read_file(dir / "full.exr"));
    CHECK_THAT(run(dir, "render " + scene + " --size 0x10 -o " + quote(dir / "x.png")).err,
               Contains("--size 0x10: expected WxH in pixels, each in [1, 32768]"));
}

TEST_CASE("a newcomer's first commands work", "[cli]") {
    TempDir dir("newcomer");
    SECTION("--version") {
        const Result r = run(dir, "--version");
        CHECK(r.status == 0);
        CHECK_THAT(r.out, StartsWith("impulse 0."));
    }
    SECTION("a misspelt scene name gets a suggestion") {
        const Result r = run(dir, "render cloud -q");
        CHECK(r.status == 1);
        CHECK_THAT(r.err, Contains("cloud: no such scene file or built-in scene (did you mean \"clouds\"?)"));
    }
    SECTION("impulse scenes prints whole first sentences") {
        const Result r = run(dir, "scenes");
        CHECK(r.status == 0);
        CHECK_THAT(r.out, Contains("clouds     wind-blown clouds in a perspective sky, kernels rotated with the wind.\n"));
        CHECK_THAT(r.out, Contains("drift      flowing clouds seen straight up"));
    }
    SECTION("info says 1 frame") {
        const Result r = run(dir, "info still");
        CHECK_THAT(r.out, Contains("1024x1024, 1 frame at"));
    }
    SECTION("no -o: out/SCENE.png for one frame, out/SCENE.mp4 for several, printed") {
        write_file(dir / "tiny.toml", "[output]\nsize = [64, 48]\nframes = 3\n[[layer]]\nlifetime = 1.0\n");
        const Result one = shell(dir, "cd " + quote(dir.path().string()) + " && " + quote(IMPULSE_BINARY) +
                                          " render tiny.toml --frames 1 -q");
        CHECK(one.status == 0);
        CHECK_THAT(one.err, Contains("output: out/tiny.png"));
        CHECK_THAT(one.out, Contains("wrote out/tiny.png"));
        CHECK(fs::exists(dir / "out/tiny.png"));
        const Result all = shell(dir, "cd " + quote(dir.path().string()) + " && " + quote(IMPULSE_BINARY) +
                                          " render tiny.toml -q");
        CHECK(all.status == 0);
        CHECK(fs::exists(dir / "out/tiny.mp4"));
    }
}

TEST_CASE("sequence patterns: one, at most 19 digits, a single # is 4 digits", "[cli]") {
    using impulse::app::expand_pattern;
    CHECK(expand_pattern("f_#.png", 7) == "f_0007.png");
    CHECK(expand_pattern("f_##.png", 7) == "f_07.png");
    CHECK(expand_pattern("f_%05d.exr", 42) == "f_00042.exr");
    CHECK(expand_pattern("f_%d.exr", 42) == "f_42.exr");
    CHECK(expand_pattern("plain.png", 3).empty());
    CHECK_THROWS_MATCHES(expand_pattern("a_##_b_##.png", 1), impulse::ValueError,
                         Catch::Message("a_##_b_##.png: two frame-number patterns (\"##\" and \"##\"): "
                                        "expected one, e.g. frame_####.png"));
    CHECK_THROWS_AS(expand_pattern("f_%99999d.png", 1), impulse::ValueError);
    CHECK_THROWS_AS(expand_pattern("f_" + std::string(20, '#') + ".png", 1), impulse::ValueError);
    CHECK(expand_pattern("f_" + std::string(19, '#') + ".png", 1).size() == 2 + 19 + 4);
    TempDir dir("patterns");
    write_file(dir / "tiny.toml", "[output]\nsize = [16, 16]\nframes = 2\n[[layer]]\nlifetime = 1.0\n");
    const Result wide = run(dir, "render " + quote(dir / "tiny.toml") + " -o " + quote(dir / "f_%99999d.png"));
    CHECK(wide.status == 1);
    CHECK(wide.err.size() < 400);  // one short line, not the 100 000-digit name
    CHECK_THAT(wide.err, Contains("frame-number pattern wider than 19 digits"));
    const Result two = run(dir, "render " + quote(dir / "tiny.toml") + " -o " + quote(dir / "a_##_b_##.png"));
    CHECK(two.status == 1);
    CHECK_THAT(two.err, Contains("two frame-number patterns"));
}

TEST_CASE("analyze --json FILE, and a sequence that starts after frame 0", "[cli][analyze]") {
    TempDir dir("analyze-cli");
    write_file(dir / "tiny.toml", "[output]\nsize = [64, 48]\nframes = 20\n[[layer]]\nlifetime = 1.0\n");
    REQUIRE(run(dir, "render " + quote(dir / "tiny.toml") + " -q --frames 5-8 -o " + quote(dir / "f_####.exr")).status == 0);
    const Result r = run(dir, "analyze " + quote(dir / "f_####.exr") + " --json " + quote(dir / "a.json"));
    INFO(r.err);
    CHECK(r.status == 0);
    const std::string json = read_file(dir / "a.json");
    CHECK_THAT(json, StartsWith("{"));
    CHECK_THAT(json, Contains("\"frames\":4,\"first_frame\":5"));
    CHECK_THAT(r.out, Contains("wrote " + dir / "a.json"));
    // --json before the input alone still means: JSON on stdout.
    const Result s = run(dir, "analyze --json " + quote(dir / "f_####.exr"));
    CHECK(s.status == 0);
    CHECK_THAT(s.out, StartsWith("{"));
}
