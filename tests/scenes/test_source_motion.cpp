// SPDX-License-Identifier: Apache-2.0
// Source layers in time (issue 13): a [[layer.flow]] of type "uniform" carries an fbm,
// subdivision or solid layer rigidly, f(x, t) = g(x - int_0^t v), so frame t is frame 0 shifted
// by v t, exactly (same bits) for whole-pixel shifts.
#include <catch2/catch.hpp>

#include <string>

#include "scenes/scenes.h"
#include "tests/scene_render.h"

namespace {

using namespace impulse;

/// 64 x 64 pixels on one 64-sample tile (one texture unit a pixel), 8 frames a second, a layer
/// `source` with its table `table` moving at `flow` (empty: still).
std::string moving_scene(const std::string& source, const std::string& table,
                         const std::string& flow) {
    return R"(seed = 4
[output]
size = [64, 64]
fps = 8
frames = 16
[camera]
center = [32.0, 32.0]
[[layer]]
source = ")" + source + "\"\n" + table + flow;
}

const std::string kFbm = "[layer.fbm]\nmethod = \"fourier\"\nhurst = 0.6\nsamples = 64\n";
const std::string kSolid = "[layer.solid]\nradius = 6.0\n";
// 8 and -16 units a second: frame k is shifted by (k, -2k) pixels.
const std::string kFlow = "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [8.0, -16.0]\n";

float at(const render::Frame& f, int i, int j) { return f.data[size_t(j) * f.width + i]; }

}  // namespace

TEST_CASE("a periodic fbm layer in a uniform flow is frame 0 shifted by v t to the bit",
          "[scenes][source][fbm][time]") {
    const std::string text = moving_scene("fbm", kFbm, kFlow);
    const render::Frame f0 = test::render_scene_text(text, 0);
    for (int k : {3, 7}) {
        const render::Frame fk = test::render_scene_text(text, k);
        CAPTURE(k);
        int differ = 0;
        for (int j = 0; j < 64; ++j)
            for (int i = 0; i < 64; ++i)
                differ += at(fk, i, j) != at(f0, (i - k + 64) % 64, (j + 2 * k) % 64);
        CHECK(differ == 0);
        // It moves: frame k is not frame 0.
        CHECK_FALSE(test::same_bits(fk, f0));
    }
    // Without the flow the layer is still.
    const std::string still = moving_scene("fbm", kFbm, "");
    CHECK(test::same_bits(test::render_scene_text(still, 5), test::render_scene_text(still, 0)));
}

TEST_CASE("a solid layer in a uniform flow is frame 0 shifted where the two overlap",
          "[scenes][source][solid][time]") {
    const std::string text = moving_scene("solid", kSolid, kFlow);
    const render::Frame f0 = test::render_scene_text(text, 0);
    const int k = 5;
    const render::Frame fk = test::render_scene_text(text, k);
    int differ = 0, compared = 0;
    for (int j = 0; j + 2 * k < 64; ++j)
        for (int i = k; i < 64; ++i, ++compared) differ += at(fk, i, j) != at(f0, i - k, j + 2 * k);
    CHECK(compared > 2000);
    CHECK(differ == 0);
}

TEST_CASE("a keyframed drift moves a source by the integral of its velocity",
          "[scenes][source][time]") {
    // vx ramps 0 -> 16 over the first second: at t = 1 the layer has moved 8 units.
    const std::string flow =
        "[[layer.flow]]\ntype = \"uniform\"\nvx = { keys = [[0.0, 0.0], [1.0, 16.0]] }\n";
    const render::Frame f0 = test::render_scene_text(moving_scene("fbm", kFbm, flow), 0);
    const render::Frame f8 = test::render_scene_text(moving_scene("fbm", kFbm, flow), 8);
    int differ = 0;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) differ += at(f8, i, j) != at(f0, (i - 8 + 64) % 64, j);
    CHECK(differ == 0);
}

TEST_CASE("a source layer's flow is uniform or refused in one line", "[scenes][source][errors]") {
    auto fails_with = [](const std::string& text, const std::string& what) {
        CAPTURE(text);
        REQUIRE_THROWS_WITH(scenes::load_scene_string(text, "bad.toml"), Catch::Contains(what));
    };
    fails_with(moving_scene("fbm", kFbm, "[[layer.flow]]\ntype = \"vortex\"\ncore = 4.0\n"),
               "bad.toml:15:8: layer[0].flow[0].type = \"vortex\": a fbm layer is carried rigidly");
    fails_with(moving_scene("solid", kSolid, "[[layer.flow]]\nvelocity = [1.0, 2.0]\n"),
               "layer[0].flow[0].type: a solid layer is carried rigidly");
    fails_with(moving_scene("fbm", kFbm, kFlow + "[[layer.flow]]\ntype = \"uniform\"\nvx = { keys = [[0.0, "
                                               "0.0], [1.0, 2.0]] }\n"),
               "sums several uniform flows only when they are constant");
    fails_with(moving_scene("fbm", kFbm, "[[layer.flow]]\ntype = \"uniform\"\nspeed = 3.0\n"),
               "speed");
}
