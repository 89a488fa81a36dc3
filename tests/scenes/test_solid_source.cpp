// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "solid": a slice z = z0 + velocity t through solid noise as a layer
// (scenes/source_solid.cpp on the layer-source seam): the slice's variance against Campbell's
// 3-D variance, moving through the noise, and bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "scenes/scenes.h"
#include "tests/scene_render.h"

namespace {

using namespace impulse;

std::string solid_scene(int seed, const std::string& solid) {
    return "seed = " + std::to_string(seed) + R"(
[output]
size = [128, 128]
fps = 1
frames = 2
[[layer]]
source = "solid"
[layer.solid]
radius = 4.0
)" + solid;
}

render::Frame render_at(const std::string& text, double t) {
    scenes::Scene scene = scenes::load_scene_string(text, "s.toml");
    scenes::Renderer r(std::move(scene));
    render::Frame f;
    r.render(static_cast<int>(t), f);
    return f;
}

}  // namespace

TEST_CASE("solid layer: a slice has Campbell's 3-D variance", "[scenes][solid]") {
    // Pixels 9 apart (> 2R) are independent samples of the slice.
    double s = 0, s2 = 0, s4 = 0, theory = 0;
    int n = 0;
    for (int seed = 1; seed <= 40; ++seed) {
        const std::string text = solid_scene(seed, "z0 = 0.5\n");
        theory = scenes::layer_theory(scenes::load_scene_string(text, "s.toml").layers[0]).variance;
        const render::Frame f = render_at(text, 0);
        for (int y = 4; y < 128; y += 9)
            for (int x = 4; x < 128; x += 9) {
                const double v = f.at(x, y);
                s += v, s2 += v * v, s4 += v * v * v * v, ++n;
            }
    }
    const double m2 = s2 / n, se = std::sqrt((s4 / n - m2 * m2) / n);
    INFO("slice E f^2 = " << m2 << " +- " << se << ", Campbell " << theory);
    CHECK(std::abs(m2 - theory) <= 5.0 * se);
    CHECK(std::abs(m2 - 0.9 * theory) > 5.0 * se);  // the band would see a 10 % error
}

TEST_CASE("solid layer: velocity moves the slice through the noise", "[scenes][solid]") {
    // At frame 1 (t = 1 / fps s) with velocity v the slice is z0 + v t: the frame at t = 0 of
    // the slice z0 = v t, bit for bit.
    const std::string moving = solid_scene(3, "velocity = 2.5\n");
    const std::string placed = solid_scene(3, "z0 = 2.5\n");
    scenes::Scene a = scenes::load_scene_string(moving, "s.toml");
    scenes::Scene b = scenes::load_scene_string(placed, "s.toml");
    scenes::Renderer ra(std::move(a)), rb(std::move(b));
    render::Frame fa, fb, f0;
    ra.render(1, fa);
    rb.render(0, fb);
    ra.render(0, f0);
    REQUIRE(fa.data.size() == fb.data.size());
    CHECK(std::memcmp(fa.data.data(), fb.data.data(), fa.data.size() * 4) == 0);
    CHECK(std::memcmp(fa.data.data(), f0.data.data(), fa.data.size() * 4) != 0);
}

TEST_CASE("solid layer: bad input is refused at the key", "[scenes][solid][errors]") {
    const std::string base = "[[layer]]\nsource = \"solid\"\n";
    auto fails_with = [&](const std::string& text, const std::string& what) {
        CAPTURE(text);
        REQUIRE_THROWS_WITH(scenes::load_scene_string(text, "bad.toml"), Catch::Contains(what));
    };
    fails_with(base + "[layer.solid]\nradius = -1\n", "layer[0].solid.radius = -1");
    fails_with(base + "[layer.solid]\ndensity = 0\n", "impulses per kernel volume");
    fails_with(base + "[layer.solid]\nrate = 1\n", "set dims = 4");
    fails_with(base + "[layer.solid]\nkernel = \"gabor\"\n", "cosine, gaussian");
    fails_with(base + "density = 4.0\n", "a solid layer has no density");
    fails_with("[[layer]]\nsource = \"solidish\"\n", "impulses, fbm, subdivision, solid");
}
