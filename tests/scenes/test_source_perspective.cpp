// SPDX-License-Identifier: Apache-2.0
// Source layers under a perspective camera (issue 13): an fbm layer seen straight down is its
// orthographic render; in a grazing view the near pixels are the tile sampled at their plane
// points, the far ones fade to the mean, and nothing is NaN (scenes/source_grid.cpp).
#include <catch2/catch.hpp>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"

namespace {

using namespace impulse;

const std::string kLayer = R"(
[[layer]]
source = "fbm"
seed = 9
[layer.fbm]
method = "fourier"
hurst = 0.6
samples = 64
)";

std::string num(double v) {
    std::ostringstream s;
    s << std::setprecision(17) << v;
    return s.str();
}

std::string perspective(double height, double pitch, int w, int h, const std::string& size) {
    return "[output]\nsize = [" + std::to_string(w) + ", " + std::to_string(h) +
           "]\n[camera]\ntype = \"perspective\"\nposition = [32.0, 32.0]\nheight = " + num(height) +
           "\npitch = " + num(pitch) + "\nfov = 60.0\n" + kLayer + "size = " + size + "\n";
}

double rms(const render::Frame& f) {
    double q = 0;
    for (float v : f.data) q += double(v) * v;
    return std::sqrt(q / double(f.data.size()));
}

}  // namespace

TEST_CASE("an fbm layer seen straight down through a perspective camera is its orthographic render",
          "[scenes][source][fbm][perspective]") {
    // 64 pixels, fov 60: focal 32 / tan 30 pixels; 4 pixels a texture unit, 2 a sample (size 32):
    // the footprint (sd 0.125 units, a quarter sample) is below the bilinear read's own blur.
    const double focal = 32.0 / std::tan(M_PI / 6.0), zoom = 4.0;
    const render::Frame p = test::render_scene_text(perspective(focal / zoom, 90.0, 64, 64, "32.0"));
    const render::Frame o = test::render_scene_text(
        "[output]\nsize = [64, 64]\n[camera]\ncenter = [32.0, 32.0]\nzoom = " + num(zoom) + "\n" +
        kLayer + "size = 32.0\n");
    const double sd = rms(o);
    REQUIRE(sd > 0.1);
    double worst = 0;
    for (size_t k = 0; k < p.data.size(); ++k) worst = std::max(worst, double(std::abs(p.data[k] - o.data[k])));
    CAPTURE(sd, worst);
    CHECK(worst < 1e-4 * sd);  // the same bilinear reads; the plane points differ by rounding
}

TEST_CASE("an fbm layer in a grazing perspective view is sampled near and fades to the mean far",
          "[scenes][source][fbm][perspective]") {
    const int w = 160, h = 120;
    const std::string text = perspective(6.0, 12.0, w, h, "64.0");  // one texture unit a sample
    scenes::Scene scene = scenes::load_scene_string(text, "p.toml");
    const render::PerspectiveView view(scene.camera.perspective(w, h, 0.0));
    const render::Frame f = test::render_scene_text(text);
    // The tile itself: an orthographic frame whose pixel (i, j) is sample (i + 1, j + 1) mod 64.
    const render::Frame tile = test::render_scene_text(
        "[output]\nsize = [64, 64]\n[camera]\ncenter = [32.5, 32.5]\n" + kLayer + "size = 64.0\n");
    const double sd = rms(tile);
    auto sample = [&](int i, int j) {
        return double(tile.data[size_t(((j - 1) % 64 + 64) % 64) * 64 + ((i - 1) % 64 + 64) % 64]);
    };
    int near = 0, far = 0, nan = 0, near_bad = 0, far_bad = 0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double v = f.data[size_t(j) * w + i];
            if (!std::isfinite(v)) ++nan;
            double x = 0, y = 0;
            if (!view.texture_point(i + 0.5, j + 0.5, x, y)) {
                far_bad += v != 0.0;  // above the horizon: the mean
                continue;
            }
            const auto fp = view.footprint(x, y);
            const double major = 0.5 * fp.s_major;  // the pixel filter's sd along, texture units
            if (major * major < 1.0 / 6.0 - 1e-3) {
                // Below the bilinear read's own blur: the tile read at the plane point.
                const double fx = std::floor(x), fy = std::floor(y), a = x - fx, b = y - fy;
                const int ix = int(fx), iy = int(fy);
                const double ref = (1 - b) * ((1 - a) * sample(ix, iy) + a * sample(ix + 1, iy)) +
                                   b * ((1 - a) * sample(ix, iy + 1) + a * sample(ix + 1, iy + 1));
                ++near;
                near_bad += std::abs(v - ref) > 1e-3 * sd;
            } else if (major > 128.0) {  // two tiles: nothing of the field is left
                ++far;
                far_bad += std::abs(v) > 0.02 * sd;
            }
        }
    CAPTURE(near, far, sd);
    CHECK(nan == 0);
    CHECK(near > 500);
    CHECK(far > 100);
    CHECK(near_bad == 0);
    CHECK(far_bad == 0);
}

TEST_CASE("a solid layer is still refused under a perspective camera", "[scenes][source][errors]") {
    REQUIRE_THROWS_WITH(
        scenes::Renderer(scenes::load_scene_string(
            "[camera]\ntype = \"perspective\"\n[[layer]]\nsource = \"solid\"\n", "p.toml")),
        Catch::Contains("a solid layer is seen through an orthographic camera only"));
}
