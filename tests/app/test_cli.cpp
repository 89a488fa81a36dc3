// SPDX-License-Identifier: Apache-2.0
// The `impulse` command line (design.md §4), run as a separate process: help, error reporting
// (one line on stderr, non-zero exit, no output file), image and sequence output, metadata, and
// byte-identical files for any thread count or tile size.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/support.h"

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

/// Runs `impulse ARGS` with stdout and stderr captured to files in `dir` (never on a terminal,
/// so no progress display).
Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " " + args);
}

void write_text(const std::string& path, const std::string& text) { write_file(path, text); }

// Two layers, one animated with a flow: exercises births, integration and both kernels' paths.
const char* kScene = R"(# CLI test scene
[output]
size = [96, 72]
frames = 4
[[layer]]
seed = 21
density = 12.0
lifetime = 1.0
[layer.kernel]
type = "gaussian"
radius = 12.0
sigma = 4.0
aspect = 1.4
[[layer.flow]]
type = "uniform"
velocity = [20.0, 5.0]
[[layer]]
seed = 22
density = 16.0
gain = 0.5
[layer.kernel]
type = "cosine"
radius = 6.0
)";

const std::vector<std::string> kRenderOptions = {"--output", "--frames",  "--size", "--crop",
                                                 "--seed",   "--set",     "--threads", "--tile",
                                                 "--codec",  "--resume",  "--quiet", "--help"};

}  // namespace

TEST_CASE("help lists the commands and every render option", "[cli]") {
    TempDir dir;
    const Result top = run(dir, "--help");
    CHECK(top.status == 0);
    for (const char* cmd : {"render", "scenes", "info"}) CHECK_THAT(top.out, Contains(cmd));
    const Result render = run(dir, "render --help");
    CHECK(render.status == 0);
    for (const auto& opt : kRenderOptions) CHECK_THAT(render.out, Contains(opt));
    CHECK_THAT(render.out, Contains("scene"));
    // No subcommand, or a missing required argument: a usage error, non-zero (-o has a
    // default: out/SCENE.mp4, tests/app/test_newcomer.cpp).
    CHECK(run(dir, "").status != 0);
    const Result no_scene = run(dir, "render -q");
    CHECK(no_scene.status == 2);
    CHECK_THAT(no_scene.err, Contains("scene"));
}

TEST_CASE("a bad scene exits non-zero with one line on stderr and writes nothing", "[cli][errors]") {
    TempDir dir;
    const std::string scene = dir / "bad.toml";
    write_text(scene, "[output]\nsize = [64, 48]\n[[layer]]\ndensity = -2.0\n");
    const Result r = run(dir, "render " + quote(scene) + " -o " + quote(dir / "out.png"));
    CHECK(r.status != 0);
    REQUIRE(r.err_lines().size() == 1);
    CHECK_THAT(r.err_lines()[0], Contains(scene + ":4:11: layer[0].density = -2: expected a density > 0"));
    CHECK(dir.files() == std::vector<std::string>{"bad.toml"});

    // A --set with a bad value names the override.
    write_text(dir / "good.toml", kScene);
    const Result s = run(dir, "render " + quote(dir / "good.toml") + " -o " + quote(dir / "out.png") +
                                  " --frames 0 --set layer.1.kernel.radius=-1");
    CHECK(s.status != 0);
    REQUIRE(s.err_lines().size() == 1);
    CHECK_THAT(s.err_lines()[0], Contains("--set layer.1.kernel.radius=-1: layer[1].kernel.radius = -1"));
    // A scene that does not exist.
    const Result m = run(dir, "render " + quote(dir / "nope.toml") + " -o " + quote(dir / "out.png"));
    CHECK(m.status != 0);
    REQUIRE(m.err_lines().size() == 1);
    CHECK_THAT(m.err_lines()[0], Contains("nope.toml"));
    CHECK(dir.files() == std::vector<std::string>{"bad.toml", "good.toml"});
}

TEST_CASE("bad output paths and frame ranges are refused before rendering", "[cli][errors]") {
    TempDir dir;
    const std::string scene = dir / "scene.toml";
    write_text(scene, kScene);
    SECTION("output directory that does not exist") {
        const std::string out = dir / "missing/sub/out.png";
        const Result r = run(dir, "render " + quote(scene) + " -o " + quote(out) + " --frames 0");
        CHECK(r.status != 0);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains(dir / "missing/sub"));
        CHECK_FALSE(fs::exists(dir / "missing"));
    }
    SECTION("frame range beyond the scene") {
        write_text(dir / "one.toml", "[output]\nsize = [32, 32]\n[[layer]]\n");
        const Result r = run(dir, "render " + quote(dir / "one.toml") + " -o " + quote(dir / "f_####.png") +
                                      " --frames 5-9");
        CHECK(r.status != 0);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains("--frames 5-9"));
        const Result bad = run(dir, "render " + quote(scene) + " -o " + quote(dir / "f_####.png") +
                                        " --frames 3-1");
        CHECK(bad.status != 0);
        CHECK_THAT(bad.err, Contains("--frames 3-1"));
    }
    SECTION("several frames into one image, an unknown extension, a bad --size") {
        CHECK_THAT(run(dir, "render " + quote(scene) + " -o " + quote(dir / "one.png")).err,
                   Contains("one image but 4 frames requested"));
        CHECK_THAT(run(dir, "render " + quote(scene) + " -o " + quote(dir / "out.xyz") + " --frames 0").err,
                   Contains("unknown output type"));
        CHECK_THAT(run(dir, "render " + quote(scene) + " -o " + quote(dir / "o.png") + " --frames 0 --size 12by4").err,
                   Contains("--size 12by4"));
    }
    SECTION("seeds and frame numbers out of range are refused, not clamped") {
        // CLI11 and strtoll clamp 1e23 to 2^63 - 1, and a negative seed meant "the scene's own".
        for (const char* seed : {"-5", "99999999999999999999999", "1.5"}) {
            const Result r = run(dir, "render " + quote(scene) + " -o " + quote(dir / "o.png") +
                                          " --frames 0 --seed " + seed);
            CHECK(r.status != 0);
            REQUIRE(r.err_lines().size() == 1);
            CHECK_THAT(r.err_lines()[0],
                       Contains(std::string("--seed ") + seed +
                                ": expected an integer in [0, 9223372036854775807]"));
        }
        const Result f = run(dir, "render " + quote(scene) + " -o " + quote(dir / "f_####.png") +
                                      " --frames 0-99999999999999999999999");
        CHECK(f.status != 0);
        CHECK_THAT(f.err, Contains("--frames 0-99999999999999999999999: expected frame numbers"));
    }
    const auto left = dir.files();
    CHECK((left == std::vector<std::string>{"one.toml", "scene.toml"} ||
           left == std::vector<std::string>{"scene.toml"}));
}

TEST_CASE("EXR and PNG output carry the frame and its provenance", "[cli]") {
    TempDir dir;
    const std::string scene = dir / "scene.toml";
    write_text(scene, kScene);
    const Result exr = run(dir, "render " + quote(scene) + " -o " + quote(dir / "f.exr") + " --frames 2");
    REQUIRE(exr.status == 0);
    CHECK(exr.err.empty());
    CHECK_THAT(exr.out, Contains("wrote"));
    const Result png = run(dir, "render " + quote(scene) + " -o " + quote(dir / "f.png") + " --frames 2");
    REQUIRE(png.status == 0);

    // The same frame in process: EXR holds the raw floats bit for bit; PNG the mapped values
    // rounded to 8 bits (|error| <= 0.5/255).
    const auto loaded = impulse::scenes::load_scene(scene);
    impulse::scenes::Renderer renderer(loaded);
    impulse::render::Frame frame;
    renderer.render(2, frame);
    const auto e = impulse::output::read_image(dir / "f.exr");
    REQUIRE(e.width == 96);
    REQUIRE(e.height == 72);
    CHECK(e.data == frame.data);
    const auto p = impulse::output::read_image(dir / "f.png");
    REQUIRE(p.data.size() == frame.data.size());
    const auto m = renderer.mapping();
    double worst = 0.0;
    for (size_t i = 0; i < frame.data.size(); ++i) {
        const double v = std::clamp((frame.data[i] - m.lo) / (m.hi - m.lo), 0.0, 1.0);
        worst = std::max(worst, std::abs(p.data[i] - v));
    }
    CHECK(worst <= 0.5 / 255.0 + 1e-6);

    // Metadata: the seed and the scene hash (read back with oiiotool when it is installed).
    if (std::system("oiiotool --help > /dev/null 2>&1") == 0) {
        const std::string info = dir / "info.txt";
        REQUIRE(std::system(("oiiotool --info -v " + quote(dir / "f.exr") + " > " + quote(info)).c_str()) == 0);
        const std::string text = read_file(info);
        fs::remove(info);
        CHECK_THAT(text, Contains("impulse:scene_hash: \"" + loaded.hash + "\""));
        CHECK_THAT(text, Contains("impulse:seed: \"" + std::to_string(loaded.seed) + "\""));
        CHECK_THAT(text, Contains("impulse:layer_seeds: \"" + std::to_string(loaded.layers[0].process.seed)));
        CHECK_THAT(text, Contains("impulse:frame: \"2\""));
    } else {
        WARN("oiiotool not installed: EXR metadata not checked");
    }
    // No temporary files left behind.
    CHECK(dir.files() == std::vector<std::string>{"f.exr", "f.png", "scene.toml"});
}

TEST_CASE("a spectrum table whose last row is at the Nyquist frequency renders", "[cli]") {
    // The kernel design reads the table at its last k (the default nyquist, 0.5), which used to
    // read past the table's arrays (a child's sanitizer report fails the status check).
    TempDir dir;
    write_text(dir / "tab.csv", "0,1\n0.1,0.5\n0.25,0.1\n0.5,0\n");
    write_text(dir / "scene.toml", "[output]\nsize = [48, 32]\n[[layer]]\n[layer.kernel]\n"
                                   "type = \"spectrum\"\ntable = \"tab.csv\"\n");
    const Result r = run(dir, "render " + quote(dir / "scene.toml") + " -o " + quote(dir / "f.exr"));
    CHECK_THAT(r.err, !Contains("error"));  // the design's warnings only
    REQUIRE(r.status == 0);
    CHECK(impulse::output::read_image(dir / "f.exr").width == 48);
}

TEST_CASE("output files do not depend on the thread count or tile size", "[cli][determinism]") {
    TempDir dir;
    const std::string scene = dir / "scene.toml";
    write_text(scene, kScene);
    const std::string common = "render " + quote(scene) + " --frames 3 --size 320x200 -o ";
    const Result one = run(dir, common + quote(dir / "t1.exr") + " --threads 1");
    REQUIRE(one.status == 0);
    CHECK(one.err.empty());  // no TBB diagnostics or progress when not on a terminal
    const Result two = run(dir, common + quote(dir / "t2.exr") + " --threads 2");
    REQUIRE(two.status == 0);
    CHECK(two.err.empty());
    REQUIRE(run(dir, common + quote(dir / "t2b.exr") + " --threads 2 --tile 24").status == 0);
    REQUIRE(run(dir, common + quote(dir / "t1.png") + " --threads 1").status == 0);
    REQUIRE(run(dir, common + quote(dir / "t2.png") + " --threads 2 --tile 100").status == 0);
    const std::string a = read_file(dir / "t1.exr");
    CHECK(a.size() > 1000);
    CHECK(a == read_file(dir / "t2.exr"));
    CHECK(a == read_file(dir / "t2b.exr"));
    CHECK(read_file(dir / "t1.png") == read_file(dir / "t2.png"));
}

TEST_CASE("a sequence pattern writes one zero-padded file per frame", "[cli]") {
    TempDir dir;
    const std::string scene = dir / "scene.toml";
    write_text(scene, kScene);
    const Result r = run(dir, "render " + quote(scene) + " -o " + quote(dir / "out_####.png"));
    REQUIRE(r.status == 0);
    CHECK(dir.files() == std::vector<std::string>{"out_0000.png", "out_0001.png", "out_0002.png",
                                                  "out_0003.png", "scene.toml"});
    // A printf-style pattern and a sub-range.
    const Result p = run(dir, "render " + quote(scene) + " -o " + quote(dir / "pf_%04d.exr") + " --frames 1-2");
    REQUIRE(p.status == 0);
    CHECK(fs::exists(dir / "pf_0001.exr"));
    CHECK(fs::exists(dir / "pf_0002.exr"));
    CHECK_FALSE(fs::exists(dir / "pf_0000.exr"));
    // Frame 2 of the sequence is the same file as frame 2 rendered alone (random access).
    REQUIRE(run(dir, "render " + quote(scene) + " -o " + quote(dir / "alone.exr") + " --frames 2").status == 0);
    const auto seq = impulse::output::read_image(dir / "pf_0002.exr");
    const auto alone = impulse::output::read_image(dir / "alone.exr");
    CHECK(seq.data == alone.data);
    // --resume skips what exists.
    const Result again = run(dir, "render " + quote(scene) + " -o " + quote(dir / "out_####.png") + " --resume");
    REQUIRE(again.status == 0);
    CHECK_THAT(again.out, Contains("0 frames") && Contains("4 already present"));
}

TEST_CASE("scenes and info report on the built-in and given scenes", "[cli]") {
    TempDir dir;
    const Result list = run(dir, "scenes");
    CHECK(list.status == 0);
    CHECK_THAT(list.out, Contains("still") && Contains("clouds"));
    const std::string scene = dir / "scene.toml";
    write_text(scene, kScene);
    const Result info = run(dir, "info " + quote(scene));
    CHECK(info.status == 0);
    const auto loaded = impulse::scenes::load_scene(scene);
    char var[64];
    std::snprintf(var, sizeof var, "variance   %.6g", impulse::scenes::scene_theory(loaded).variance);
    CHECK_THAT(info.out, Contains(loaded.hash) && Contains(var));
    // A composed built-in scene: each layer's line ends with its composition.
    const Result veins = run(dir, "info veins");
    CHECK(veins.status == 0);
    CHECK_THAT(veins.out, Contains("name=\"wx\" hidden") && Contains("warp=layer[0],layer[1]") &&
                              Contains("blend=multiply"));
}
