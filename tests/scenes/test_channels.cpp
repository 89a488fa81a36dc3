// SPDX-License-Identifier: Apache-2.0
// Renderer::render_channels (docs/channels.md): the composite derivatives against central
// differences of the value channel, normals against the height field's, motion vectors
// against each impulse's measured displacement between frames, and what is refused.
// Checked by hand once: with the layers' opacity left out of the composite, the rotation back
// from the kernel's frame turned the wrong way (render/gradient.cpp) and the camera's next view
// taken at the frame's own time (scenes/frame/channels.cpp), the first two cases fail (779 pixels
// over the difference bound, 636 normals, every composite pixel; every matched impulse's
// vector and the pan).

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "numeric/errors.h"
#include "scenes/scenes.h"

namespace {

using Catch::Matchers::Contains;
using impulse::scenes::ChannelSet;
using impulse::scenes::FrameChannels;
using impulse::scenes::Renderer;

constexpr double kPi = std::numbers::pi;

/// Two cosine layers (R = 6 and 9 texture units), the second at opacity 0.6 and turned at
/// random, seen at zoom 8 (h = 0.125 units per pixel), without anti-aliasing.
const char* kTwoLayers = R"(
[output]
size = [96, 80]
[camera]
zoom = 8.0
center = [20.0, 30.0]
[[layer]]
seed = 3
density = 6.0
amplitude = "uniform"
[layer.kernel]
type = "cosine"
radius = 6.0
[[layer]]
seed = 4
density = 4.0
opacity = 0.6
orientation = "random"
[layer.kernel]
type = "cosine"
radius = 9.0
aspect = 1.5
)";

/// The sum of |w| of layer i's impulses within its radius R of texture point (x, y).
double local_weight(const Renderer& r, size_t i, double R, double x, double y) {
    const auto& imp = r.impulses(i);
    double s = 0.0;
    for (size_t k = 0; k < imp.size(); ++k)
        if (std::hypot(imp.x[k] - x, imp.y[k] - y) < R + 1.0) s += std::abs(imp.weight[k]);
    return s;
}

}  // namespace

TEST_CASE("composite derivative channels match central differences of the value channel",
          "[scenes][channels]") {
    Renderer r(impulse::scenes::load_scene_string(kTwoLayers, "two.toml"));
    ChannelSet set;
    set.value = set.dx = set.dy = set.normal = true;
    FrameChannels ch;
    r.render_channels(0, set, ch);
    REQUIRE(ch.layers.size() == 2);
    REQUIRE(ch.layer_names[1] == "layer1");
    const auto view = r.scene().camera.view(96, 80, 0.0);
    const double h = view.scale;
    // Per impulse of radius R (tests/render/test_gradient.cpp): the central difference errs by
    // max(h^2 / 6 * 4 (pi / R)^3 a^3, J h / 4) per texture unit, J = pi^2 a^2 / (2 R^2) the jump
    // of h'' at the edge, a the aspect (lengths across shrink by it); plus 2e-6 of the value's
    // rounding and polynomial; times |w| of the impulses reaching the pixel, opacity, and h.
    auto per_weight = [&](double R, double a) {
        return std::max(h * h / 6.0 * 4.0 * std::pow(kPi * a / R, 3), kPi * kPi * a * a / (2 * R * R) * h / 4.0) * h + 2e-6;
    };
    const double c0 = per_weight(6.0, 1.0), c1 = 0.6 * per_weight(9.0, 1.5);
    int checked = 0;
    double worst_ratio = 0.0, worst_normal = 0.0;
    const double relief = impulse::scenes::normal_relief(r.scene(), 0.0);
    std::vector<float> n;
    impulse::scenes::normal_map(ch.dx, ch.dy, relief, n);
    for (int y = 1; y + 1 < 80; y += 3)
        for (int x = 1; x + 1 < 96; x += 3) {
            const double tx = view.x0 + (x + 0.5) * h, ty = view.y0 + (y + 0.5) * h;
            const double bound = c0 * local_weight(r, 0, 6.0, tx, ty) + c1 * local_weight(r, 1, 9.0, tx, ty);
            const double cx = (ch.value.at(x + 1, y) - ch.value.at(x - 1, y)) / 2.0;
            const double cy = (ch.value.at(x, y + 1) - ch.value.at(x, y - 1)) / 2.0;
            const double err = std::max(std::abs(cx - ch.dx.at(x, y)), std::abs(cy - ch.dy.at(x, y)));
            CHECK(err <= bound);
            worst_ratio = std::max(worst_ratio, err / bound);
            // The normal of the height field relief * f from its own differences: v -> v / |v|
            // moves by at most 2 |dv| for |v| >= 1, |dv| <= sqrt(2) relief err.
            const size_t i = size_t(y) * 96 + x;
            const double gx = -relief * cx, gy = relief * cy, inv = 1.0 / std::sqrt(gx * gx + gy * gy + 1.0);
            const double dn = std::hypot(n[3 * i] - gx * inv, n[3 * i + 1] - gy * inv, n[3 * i + 2] - inv);
            CHECK(dn <= 2.0 * std::sqrt(2.0) * relief * bound + 1e-6);
            CHECK(std::abs(std::hypot(n[3 * i], n[3 * i + 1], n[3 * i + 2]) - 1.0) <= 1e-6);
            worst_normal = std::max(worst_normal, dn);
            ++checked;
        }
    INFO("worst error / bound " << worst_ratio << ", normal difference " << worst_normal);
    CHECK(checked > 500);
    // Without the second layer's opacity (or with a layer left out) the composite is off by far
    // more than the bound: the test sees the composition.
    for (size_t p = 0; p < ch.dx.data.size(); ++p)
        CHECK(std::abs(ch.dx.data[p] - (ch.layer_dx[0].data[p] + 0.6f * ch.layer_dx[1].data[p])) <=
              1e-6f * (1.0f + std::abs(ch.dx.data[p])));
}

TEST_CASE("motion vectors follow each impulse's displacement between frames",
          "[scenes][channels]") {
    // Sparse impulses in a uniform wind plus a Lamb-Oseen vortex, filmed by a panning camera.
    // The vortex (circulation G = 2 pi 200, core c = 20) turns at most at Omega = G / (2 pi c^2)
    // = 0.5 /s: |grad v| <= |dv/dr| + |v / r| <= 2 Omega, |v| <= 0.6382 G / (2 pi c) (the peak of
    // (1 - e^{-x^2}) / x). Over a frame dt an impulse moves by v dt up to dt^2 / 2 |Dv/Dt| <=
    // dt^2 / 2 |v| 2 Omega (Dv/Dt = (v . grad) v); the vector is the flow at the pixel centre, up
    // to 0.71 px from the impulse: 2 Omega 0.71 px dt more. Float storage and Heun's step add
    // under 1e-4 px.
    const char* text = R"(
[output]
size = [128, 96]
fps = 30
frames = 20
[camera]
center_x = { keys = [[0.0, 64.0], [10.0, 164.0]] }
center_y = 48.0
[[layer]]
seed = 9
density = 0.4
lifetime = 10.0
[layer.kernel]
type = "cosine"
radius = 4.0
[[layer.flow]]
type = "uniform"
velocity = [6.0, -3.0]
[[layer.flow]]
type = "vortex"
center = [64.0, 48.0]
circulation = 1256.6370614359173
core = 20.0
)";
    Renderer r(impulse::scenes::load_scene_string(text, "motion.toml"));
    const auto& sc = r.scene();
    ChannelSet set;
    set.motion = true;
    FrameChannels ch;
    r.render_channels(5, set, ch);
    const auto before = r.impulses(0);
    impulse::render::Frame f6;
    r.render(6, f6);
    const auto after = r.impulses(0);
    const auto v5 = sc.camera.view(128, 96, sc.frame_time(5));
    const auto v6 = sc.camera.view(128, 96, sc.frame_time(6));
    const double dt = 1.0 / 30.0, omega = 0.5, vmax = 0.6382 * 200.0 / 20.0 + std::hypot(6.0, 3.0);
    const double tol = (dt * dt / 2.0 * vmax * 2.0 * omega + 2.0 * omega * 0.71 * v5.scale * dt) / v5.scale + 1e-4;
    int matched = 0;
    double worst = 0.0;
    for (size_t k = 0; k < before.size(); ++k) {
        const double px = (before.x[k] - v5.x0) / v5.scale - 0.5, py = (before.y[k] - v5.y0) / v5.scale - 0.5;
        const int ix = int(std::lround(px)), iy = int(std::lround(py));
        if (ix < 0 || iy < 0 || ix >= 128 || iy >= 96) continue;
        // The same impulse one frame later: the nearest to where the vector says it goes
        // (impulses are ~11 units apart; they move about 0.25 units a frame).
        const size_t i = size_t(iy) * 128 + ix;
        const double ex = v6.x0 + (px + ch.motion[0].data[i] + 0.5) * v6.scale;
        const double ey = v6.y0 + (py - ch.motion[1].data[i] + 0.5) * v6.scale;
        size_t best = 0;
        double dist = 1e300;
        for (size_t m = 0; m < after.size(); ++m)
            if (const double d = std::hypot(after.x[m] - ex, after.y[m] - ey); d < dist) dist = d, best = m;
        REQUIRE(dist < 1.0);
        const double mx = (after.x[best] - v6.x0) / v6.scale - 0.5 - px;
        const double my = -((after.y[best] - v6.y0) / v6.scale - 0.5 - py);  // v up
        CHECK(std::abs(ch.motion[0].data[i] - mx) <= tol);
        CHECK(std::abs(ch.motion[1].data[i] - my) <= tol);
        worst = std::max({worst, std::abs(ch.motion[0].data[i] - mx), std::abs(ch.motion[1].data[i] - my)});
        // A steady flow and a linear pan: backward is forward reversed.
        CHECK(std::abs(ch.motion[2].data[i] + ch.motion[0].data[i]) <= 1e-5);
        CHECK(std::abs(ch.motion[3].data[i] + ch.motion[1].data[i]) <= 1e-5);
        ++matched;
    }
    INFO("worst " << worst << " px, tolerance " << tol);
    CHECK(matched >= 10);
    // The pan (10 units/s, 1/3 px a frame) is in the vectors: at the vortex's centre the wind
    // alone would move content 0.2 px right; the camera following faster moves it left.
    CHECK(std::abs(ch.motion[0].at(64, 48) - (6.0 - 10.0) * dt) <= 2.0 * omega * 1.0 * dt);
}

TEST_CASE("channels a scene cannot give are refused with the flag and the reason",
          "[scenes][channels][errors]") {
    ChannelSet grad;
    grad.dx = true;
    FrameChannels ch;
    SECTION("a shaped layer") {
        Renderer r(impulse::scenes::load_scene_string(
            "[output]\nsize = [16, 16]\n[[layer]]\n[layer.marginal]\ntype = \"uniform\"\n",
            "shaped.toml"));
        REQUIRE_THROWS_WITH(r.render_channels(0, grad, ch, {}, "--channels dx"),
                            Contains("shaped.toml: --channels dx: layer[0] is shaped"));
    }
    SECTION("a perspective camera") {
        Renderer r(impulse::scenes::load_scene_string(
            "[output]\nsize = [16, 16]\n[camera]\ntype = \"perspective\"\n[[layer]]\n",
            "persp.toml"));
        REQUIRE_THROWS_WITH(r.render_channels(0, grad, ch, {}, "--channels dx"),
                            Contains("orthographic cameras only"));
    }
    SECTION("an unknown name, with the nearest") {
        REQUIRE_THROWS_WITH(impulse::scenes::parse_channels("value,dxx", "--channels"),
                            "--channels value,dxx: unknown channel \"dxx\" (did you mean \"dx\"?): "
                            "expected one of value, dx, dy, normal, motion");
    }
}
