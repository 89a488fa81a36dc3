// SPDX-License-Identifier: Apache-2.0
// Scene errors (design.md §4): every bad input gets one line naming the file, line:column, the
// key path, the value and what was expected; requests over the budget are refused with the
// estimate. Line/column numbers below refer to the scene texts as written (line 1 = first line
// after the opening R"( ).

#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using impulse::BudgetError;
using impulse::SceneError;
using impulse::scenes::load_scene;
using impulse::scenes::load_scene_string;

/// The message of the SceneError thrown by loading `text`, checked to be a single line.
std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
    try {
        load_scene_string(text, "errors.toml", overrides);
    } catch (const SceneError& e) {
        const std::string m = e.what();
        CHECK(m.find('\n') == std::string::npos);
        return m;
    }
    FAIL("no SceneError for:\n" << text);
    return "";
}

// A valid scene; the error cases below change one thing. Lines:
//  1 [output]
//  2 size = [64, 48]
//  3 (blank)
//  4 [[layer]]
//  5 seed = 1
//  6 density = 16.0
//  7 [layer.kernel]
//  8 type = "cosine"
//  9 radius = 8.0
const char* kValid = R"([output]
size = [64, 48]

[[layer]]
seed = 1
density = 16.0
[layer.kernel]
type = "cosine"
radius = 8.0
)";

/// kValid with line `line` (1-based) replaced by `replacement` (may hold several lines).
std::string with_line(int line, const std::string& replacement) {
    std::istringstream in(kValid);
    std::string out, l;
    for (int i = 1; std::getline(in, l); ++i) out += (i == line ? replacement : l) + "\n";
    return out;
}

/// A unique temporary path, removed on destruction.
class TempFile {
public:
    explicit TempFile(const std::string& stem) {
        static std::atomic<int> counter{0};
        m_path = fs::temp_directory_path() /
                 ("impulse-test-" + stem + "-" + std::to_string(::getpid()) + "-" +
                  std::to_string(counter++) + ".toml");
    }
    ~TempFile() {
        std::error_code ec;
        fs::remove(m_path, ec);
    }
    std::string path() const { return m_path.string(); }
    void write(const std::string& text) const { std::ofstream(m_path) << text; }

private:
    fs::path m_path;
};

}  // namespace

TEST_CASE("the valid base scene loads", "[scenes]") {
    const auto s = load_scene_string(kValid, "errors.toml");
    REQUIRE(s.layers.size() == 1);
    CHECK(s.layers[0].kernel.radius == 8.0);
    CHECK(s.output.width == 64);
    CHECK(s.warnings.empty());
}

TEST_CASE("TOML syntax errors give file:line:col", "[scenes][errors]") {
    const std::string m = error_of(with_line(6, "density = = 16.0"));
    CHECK_THAT(m, StartsWith("errors.toml:6:"));
    const std::string m2 = error_of(with_line(2, "size = [64, 48"));
    CHECK_THAT(m2, StartsWith("errors.toml:"));
    CHECK_THAT(error_of("[output]\nsize = [64, 48]\n[output]\n"), StartsWith("errors.toml:3:"));
}

TEST_CASE("unknown keys are reported with the nearest valid name", "[scenes][errors]") {
    CHECK(error_of(with_line(6, "density = 16.0\nlifetme = 2.0")) ==
          "errors.toml:7:1: unknown key \"lifetme\" in layer[0] (did you mean \"lifetime\"?)");
    CHECK_THAT(error_of(with_line(9, "radius = 8.0\nradus = 3.0")),
               StartsWith("errors.toml:10:1: unknown key \"radus\" in layer[0].kernel") &&
                   Contains("did you mean \"radius\"?"));
    CHECK_THAT(error_of(with_line(1, "[outptu]")),
               Contains("errors.toml:1:") && Contains("unknown key \"outptu\"") &&
                   Contains("did you mean \"output\"?"));
    // Nothing close: the valid keys are listed instead.
    CHECK_THAT(error_of(with_line(8, "type = \"cosine\"\nzzzzzzzzzz = 1")),
               Contains("unknown key \"zzzzzzzzzz\" in layer[0].kernel (valid keys:") &&
                   Contains("radius"));
}

TEST_CASE("wrong value types name key, value and the expected type", "[scenes][errors]") {
    CHECK(error_of(with_line(9, "radius = \"big\"")) ==
          "errors.toml:9:10: layer[0].kernel.radius = \"big\": expected a number or keyframes "
          "{ keys = [[t, v], ...] }, found string");
    CHECK_THAT(error_of(with_line(6, "density = true")),
               StartsWith("errors.toml:6:11: layer[0].density = true: expected a number or keyframes "
                          "{ keys = [[t, v], ...] }, found boolean"));
    CHECK_THAT(error_of(with_line(2, "size = [64, 48]\nframes = 2.5")),
               Contains("errors.toml:3:10: output.frames = 2.5: expected an integer, found float"));
    CHECK_THAT(error_of(with_line(5, "seed = \"one\"")),
               Contains("errors.toml:5:8: layer[0].seed = \"one\": expected an integer, found string"));
}

TEST_CASE("out-of-range values name key, value and the valid range", "[scenes][errors]") {
    CHECK(error_of(with_line(9, "radius = -1.0")) ==
          "errors.toml:9:10: layer[0].kernel.radius = -1: expected a radius > 0 (texture units)");
    CHECK_THAT(error_of(with_line(9, "radius = 0")),
               StartsWith("errors.toml:9:10: layer[0].kernel.radius = 0: expected a radius > 0"));
    CHECK(error_of(with_line(6, "density = 0.0")) ==
          "errors.toml:6:11: layer[0].density = 0: expected a density > 0 (impulses per kernel area)");
    CHECK_THAT(error_of(with_line(6, "density = -3.5")),
               StartsWith("errors.toml:6:11: layer[0].density = -3.5: expected a density > 0"));
    for (const char* size : {"[0, 48]", "[64, -5]", "[40000, 48]"}) {
        CAPTURE(size);
        CHECK_THAT(error_of(with_line(2, std::string("size = ") + size)),
                   StartsWith(std::string("errors.toml:2:8: output.size = ") + size +
                              ": expected [width, height] with each in [1, 32768]"));
    }
    CHECK_THAT(error_of(with_line(2, "size = [64.5, 48]")),
               Contains("output.size") && Contains("expected [width, height] in whole pixels"));
    CHECK_THAT(error_of(with_line(8, "type = \"gaussian\"\nsigma = -2.0")),
               Contains("errors.toml:9:9: layer[0].kernel.sigma = -2: expected a standard deviation > 0"));
    CHECK_THAT(error_of(with_line(9, "radius = 8.0\naspect = 0.5")),
               Contains("errors.toml:10:10: layer[0].kernel.aspect = 0.5: expected a ratio >= 1"));
}

TEST_CASE("NaN and infinity are refused, not clamped", "[scenes][errors]") {
    CHECK_THAT(error_of(with_line(9, "radius = nan")),
               StartsWith("errors.toml:9:10: layer[0].kernel.radius = ") && Contains("nan") &&
                   Contains("expected a finite number"));
    CHECK_THAT(error_of(with_line(6, "density = inf")),
               StartsWith("errors.toml:6:11: layer[0].density = inf") && Contains("expected a finite number"));
    CHECK_THAT(error_of(with_line(6, "density = 16.0\nmean = -nan")),
               Contains("layer[0].mean") && Contains("expected a finite number"));
}

TEST_CASE("unknown names list the valid choices", "[scenes][errors]") {
    CHECK_THAT(error_of(with_line(8, "type = \"gabour\"")),
               StartsWith("errors.toml:8:8: layer[0].kernel.type = \"gabour\": expected one of "
                          "cosine, gaussian, gabor"));
    CHECK_THAT(error_of(with_line(6, "density = 16.0\namplitude = \"gauss\"")),
               StartsWith("errors.toml:7:13: layer[0].amplitude = \"gauss\": expected one of normal, "
                          "uniform, sign"));
    CHECK_THAT(error_of(with_line(6, "density = 16.0\nenvelope = \"hanning\"")),
               Contains("layer[0].envelope = \"hanning\": expected one of hann, box"));
}

TEST_CASE("overrides given with --set are checked like the file and named in the message", "[scenes][errors]") {
    CHECK(error_of(kValid, {"layer.0.kernel.radius=-1"}) ==
          "--set layer.0.kernel.radius=-1: layer[0].kernel.radius = -1: expected a radius > 0 "
          "(texture units)");
    CHECK_THAT(error_of(kValid, {"layer.0.density=nan"}),
               StartsWith("--set layer.0.density=nan: layer[0].density = ") &&
                   Contains("expected a finite number"));
    CHECK_THAT(error_of(kValid, {"layer.0.kernel.radus=3"}),
               StartsWith("--set layer.0.kernel.radus=3: unknown key \"radus\" in layer[0].kernel") &&
                   Contains("did you mean \"radius\"?"));
    CHECK_THAT(error_of(kValid, {"layer.0.kernel.type=gabour"}),
               StartsWith("--set layer.0.kernel.type=gabour: layer[0].kernel.type = \"gabour\": "
                          "expected one of cosine, gaussian, gabor"));
    CHECK_THAT(error_of(kValid, {"radius"}), StartsWith("--set radius: expected key=value"));
    CHECK_THAT(error_of(kValid, {"layer.3.density=2"}),
               StartsWith("--set layer.3.density=2: layer has 1 elements, no index 3"));
    // A good override takes effect, and changes the scene hash.
    const auto base = load_scene_string(kValid, "errors.toml");
    const auto s = load_scene_string(kValid, "errors.toml", {"layer.0.kernel.radius=4", "output.size=[32,16]"});
    CHECK(s.layers[0].kernel.radius == 4.0);
    CHECK(s.output.width == 32);
    CHECK(s.output.height == 16);
    CHECK(s.hash != base.hash);
}

TEST_CASE("animation settings that cannot work are refused", "[scenes][errors]") {
    SECTION("keyframes out of order") {
        CHECK_THAT(error_of(with_line(2, "size = [64, 48]\n[camera]\nzoom = { keys = [[0.0, 1.0], [2.0, 2.0], "
                                         "[1.0, 3.0]] }")),
                   StartsWith("errors.toml:4:42: camera.zoom.keys = ") &&
                       Contains(": keyframes out of order: time 1 follows 2 (times must increase)"));
    }
    SECTION("loop shorter than the lifetime") {
        CHECK_THAT(error_of(with_line(6, "density = 16.0\nlifetime = 2.0\nloop = 1.0")),
                   StartsWith("errors.toml:8:8: layer[0].loop = 1: a loop shorter than the lifetime") &&
                       Contains("expected loop >= lifetime"));
    }
    SECTION("loop on a still layer") {
        CHECK_THAT(error_of(with_line(6, "density = 16.0\nloop = 3.0")),
                   StartsWith("errors.toml:7:8: layer[0].loop = 3: a loop needs moving particles"));
    }
    SECTION("flow on a still layer") {
        const std::string text = std::string(kValid) + "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [1.0, 0.0]\n";
        CHECK_THAT(error_of(text), StartsWith("errors.toml:10:") && Contains("layer[0].flow") &&
                                       Contains("set lifetime > 0 in this layer"));
    }
    SECTION("a start time between frames") {
        CHECK_THAT(error_of(with_line(2, "size = [64, 48]\nfps = 24\nstart = 0.01")),
                   Contains("errors.toml:4:9: output.start = 0.01: expected a whole number of frames"));
    }
}

TEST_CASE("errors in a scene file name the file", "[scenes][errors]") {
    TempFile f("bad-scene");
    f.write(with_line(9, "radius = -2.0"));
    CHECK_THROWS_AS(load_scene(f.path()), SceneError);
    CHECK_THROWS_WITH(load_scene(f.path()),
                      StartsWith(f.path() + ":9:10: layer[0].kernel.radius = -2: expected a radius > 0"));
    TempFile missing("missing-scene");
    CHECK_THROWS_AS(load_scene(missing.path()), impulse::IoError);
    CHECK_THROWS_WITH(load_scene(missing.path()), StartsWith(missing.path() + ": cannot open scene file"));
}

TEST_CASE("a density beyond the Poisson sampler is refused naming the layer (fuzzing's find)",
          "[scenes][errors]") {
    // fuzz_scene's reproducer (veins with density = 1.6e80): the seeding cell's count, drawn as
    // ceil(mean / 200) Poisson parts, overflowed an int (undefined behaviour under UBSan) while
    // the simulators were built, before the impulse budget is checked.
    const auto scene = load_scene_string(with_line(6, "density = 1.6e80"), "dense.toml");
    CHECK_THROWS_AS(impulse::scenes::Renderer(scene), BudgetError);
    CHECK_THROWS_WITH(impulse::scenes::Renderer(scene),
                      StartsWith("dense.toml: layer[0]: a seeding cell expects ") &&
                          Contains("the Poisson sampler draws (lower the density)"));
    // Under the sampler's limit the impulse budget refuses it, with its estimate.
    const auto big = load_scene_string(with_line(6, "density = 1e10"), "dense.toml");
    CHECK_THROWS_WITH(impulse::scenes::Renderer(big), Contains("limits.max_impulses"));
}

TEST_CASE("a scene over the impulse or memory budget is refused with the estimate",
          "[scenes][errors]") {
    // 1024 x 1024 at density 1e5 per kernel area of radius 8: lambda = 1e5 / (64 pi) per px^2 over
    // the birth region (1024 + 2 * 8)^2 = the estimate the message must carry.
    const std::string text = with_line(2, "size = [1024, 1024]");
    const auto scene = load_scene_string(with_line(6, "density = 1e5"), "budget.toml",
                                         {"output.size=[1024,1024]"});
    const double estimate = 1e5 / (64.0 * 3.14159265358979323846) * 1040.0 * 1040.0;
    std::ostringstream expected;
    expected << "budget.toml: the scene needs an estimated " << estimate
             << " impulses per frame, over the budget of 5e+07";
    CHECK_THROWS_AS(impulse::scenes::Renderer(scene), BudgetError);
    CHECK_THROWS_WITH(impulse::scenes::Renderer(scene),
                      StartsWith(expected.str()) && Contains("limits.max_impulses"));
    // Raising the impulse limit lets the memory estimate (~120 bytes per impulse) refuse it.
    const auto raised = load_scene_string(with_line(6, "density = 1e5"), "budget.toml",
                                          {"output.size=[1024,1024]", "limits.max_impulses=1e9"});
    CHECK_THROWS_AS(impulse::scenes::Renderer(raised), BudgetError);
    CHECK_THROWS_WITH(impulse::scenes::Renderer(raised), Contains("MiB per frame"));
    CHECK_NOTHROW(impulse::scenes::Renderer(load_scene_string(text, "budget.toml")));
    auto tight = load_scene_string(text, "budget.toml", {"limits.max_memory_mib=1"});
    CHECK_THROWS_AS(impulse::scenes::Renderer(tight), BudgetError);
    CHECK_THROWS_WITH(impulse::scenes::Renderer(tight),
                      Contains("MiB per frame, over the budget of 1 MiB (limits.max_memory_mib)"));
}

TEST_CASE("a perspective frame over the pixel-evaluation budget is refused before it is drawn",
          "[scenes][errors]") {
    // The impulse count does not bound a perspective frame's work: the near field's pixel boxes
    // are counted on every frame before any pixel is evaluated.
    const std::vector<std::string> camera = {"camera.type=\"perspective\"", "camera.height=16",
                                             "camera.pitch=20", "camera.fov=60"};
    auto with = [&](std::vector<std::string> extra) {
        extra.insert(extra.begin(), camera.begin(), camera.end());
        return load_scene_string(kValid, "pixels.toml", extra);
    };
    impulse::render::Frame f;
    impulse::scenes::Renderer ok(with({}));
    CHECK_NOTHROW(ok.render(0, f));
    impulse::scenes::Renderer tight(with({"limits.max_pixel_evaluations=1000"}));
    CHECK_THROWS_AS(tight.render(0, f), BudgetError);
    CHECK_THROWS_WITH(tight.render(0, f),
                      StartsWith("pixels.toml: layer[0] at t = 0 s needs ") &&
                          Contains("pixel evaluations, over the budget of 1000 "
                                   "(limits.max_pixel_evaluations"));
    CHECK_THAT(error_of(with_line(9, "radius = 8.0\n[limits]\nmax_pixel_evaluations = -1")),
               Contains("limits.max_pixel_evaluations = -1") && Contains("a count > 0"));
}

TEST_CASE("a flow too fast for max_travel is refused naming the scene and the layer",
          "[scenes][errors]") {
    // Found only when a view's birth region is computed (the renderer's estimate), not by the
    // loader: the message carries the scene and the layer all the same.
    const auto scene = load_scene_string(
        with_line(6, "density = 16.0\nlifetime = 1.0\n[[layer.flow]]\ntype = \"uniform\"\n"
                     "velocity = [1e5, 0.0]"),
        "fast.toml");
    CHECK_THROWS_AS(impulse::scenes::Renderer(scene), impulse::SceneError);
    CHECK_THROWS_WITH(impulse::scenes::Renderer(scene),
                      StartsWith("fast.toml: layer[0]: flow speed bound 100000 units/s") &&
                          Contains("beyond max_travel = 4096"));
}
