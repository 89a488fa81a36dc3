// SPDX-License-Identifier: Apache-2.0
// [camera.sea] (docs/perspective.md §9): the mirror camera sees the deck where the reflected ray
// meets it (closed-form geometry), a flat sea is the mirror image weighted by Schlick's Fresnel
// reflectance, the sky above the horizon is untouched, and bad seas are refused.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/detail/camera.h"
#include "scenes/scenes.h"

namespace S = impulse::scenes;
using impulse::render::Frame;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string sea_scene(const std::string& sea) {
    return R"(
[output]
size = [160, 90]
fps = 10
frames = 3
[camera]
type = "perspective"
plane = "sky"
position = [5.0, -7.0]
height = 100.0
pitch = 14.0
heading = 30.0
fov = 55.0
)" + sea + R"(
[[layer]]
density = 5.0
lifetime = 2.0
[layer.kernel]
type = "gaussian"
radius = 60.0
sigma = 20.0
)";
}

/// The main camera's ray through pixel centre (i + 0.5, j + 0.5) in its own frame: horizontal
/// distance and height per unit length (pinhole, principal point at the centre).
void ray(const S::CameraConfig& c, int w, int h, int i, int j, double& horiz, double& dz) {
    const double p = c.pitch.value(0) * kDeg, f = 0.5 * h / std::tan(0.5 * c.fov.value(0) * kDeg);
    const double a = i + 0.5 - 0.5 * w, b = 0.5 * h - (j + 0.5);
    const double dF = f * std::cos(p) - b * std::sin(p), z = f * std::sin(p) + b * std::cos(p);
    const double len = std::sqrt(dF * dF + a * a + z * z);
    horiz = std::sqrt(dF * dF + a * a) / len, dz = z / len;
}

}  // namespace

TEST_CASE("the mirror camera sees the deck where the reflected ray meets it", "[scenes][sea]") {
    const S::Scene scene =
        S::load_scene_string(sea_scene("[camera.sea]\ndepth = 3.0\n"), "sea.toml");
    const S::CameraConfig& c = scene.camera;
    const S::CameraConfig m = S::detail::mirror_camera(c);
    const int w = 160, h = 90;
    const impulse::render::PerspectiveView mv(m.perspective(w, h, 0.0));
    // A ray of depression delta from the eye meets the sea depth / tan(delta) away and, reflected,
    // rises height + depth to the deck: (height + 2 depth) / tan(delta) from the foot in all.
    int checked = 0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; i += 7) {
            double horiz, dz;
            ray(c, w, h, i, j, horiz, dz);
            if (!(dz < -1e-3)) continue;  // above the horizon (or grazing it)
            const double expected = (100.0 + 2.0 * 3.0) * horiz / -dz;
            double x, y;
            REQUIRE(mv.texture_point(i + 0.5, h - (j + 0.5), x, y));
            const double got = std::hypot(x - 5.0, y + 7.0);
            CAPTURE(i, j, expected, got);
            CHECK(got == Approx(expected).epsilon(1e-9));
            ++checked;
        }
    CHECK(checked > 200);
}

TEST_CASE("a flat sea is the mirror image weighted by Schlick's reflectance", "[scenes][sea]") {
    const S::Scene scene =
        S::load_scene_string(sea_scene("[camera.sea]\ndepth = 3.0\nroughness = 0.0\n"), "sea.toml");
    const int w = 160, h = 90;
    // A mirror picture with a distinct value per pixel, a field of zeros, mean 0.5.
    Frame mirror, field;
    mirror.resize(w, h), field.resize(w, h);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) mirror.data[size_t(j) * w + i] = float(0.01 * i + 0.37 * j);
    const double mean = 0.5;
    S::detail::apply_sea(scene.camera.perspective(w, h, 0.0), scene.camera.sea, 0.5, 0.0, mean,
                         mirror, field);
    int sea = 0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            double horiz, dz;
            ray(scene.camera, w, h, i, j, horiz, dz);
            CAPTURE(i, j, dz);
            if (dz >= 0.0) {  // the sky is left alone
                CHECK(field.at(i, j) == 0.0f);
                continue;
            }
            // Schlick: F = F0 + (1 - F0) (1 - cos theta)^5, cos theta = sin(depression), F0 = 0.02.
            const double F = 0.02 + 0.98 * std::pow(1.0 + dz, 5);
            const double expected = mean + F * (mirror.at(i, h - 1 - j) - mean);
            CHECK(field.at(i, j) == Approx(expected).epsilon(1e-5));
            ++sea;
        }
    CHECK(sea > 20 * w);  // the horizon is a quarter up the frame
}

TEST_CASE("the sea leaves the sky's pixels as they were", "[scenes][sea][slow]") {
    const S::Scene with = S::load_scene_string(sea_scene("[camera.sea]\ndepth = 3.0\n"), "a.toml");
    const S::Scene without = S::load_scene_string(sea_scene(""), "b.toml");
    S::Renderer ra(with), rb(without);
    Frame a, b;
    ra.render(2, a), rb.render(2, b);
    int differ_below = 0;
    for (int j = 0; j < a.height; ++j)
        for (int i = 0; i < a.width; ++i) {
            double horiz, dz;
            ray(with.camera, a.width, a.height, i, j, horiz, dz);
            if (dz >= 0.0)
                CHECK(a.at(i, j) == b.at(i, j));
            else
                differ_below += a.at(i, j) != b.at(i, j);
        }
    CHECK(differ_below > 1000);
    // The background below the horizon is the sea's, above it the sky gradient's.
    const auto bg = with.shading_at(0.2).background;
    REQUIRE(bg.size() == 3 * 2048);
    CHECK(bg[0] == Approx(with.shading.top[0]));
    CHECK(bg.back() != Approx(with.shading.bottom[2]));
    CHECK(without.shading_at(0.2).background.empty());
}

TEST_CASE("the mirror picture is the frame's view at its resolution", "[scenes][sea]") {
    S::SeaConfig sea;
    CHECK(S::detail::mirror_size(sea, 1920, 1080) == std::array<int, 2>{960, 540});  // default half
    CHECK(S::detail::mirror_size(sea, 3840, 2160) == std::array<int, 2>{1920, 1080});
    CHECK(S::detail::mirror_size(sea, 1280, 720) ==
          std::array<int, 2>{960, 540});  // 540 rows at least
    CHECK(S::detail::mirror_size(sea, 640, 360) ==
          std::array<int, 2>{640, 360});  // never above the frame
    sea.mirror_min_height = 1;  // odd sizes round up and keep the frame's view at the edges
    CHECK(S::detail::mirror_size(sea, 321, 181) == std::array<int, 2>{162, 91});
    sea.mirror_resolution = 0.125;
    CHECK(S::detail::mirror_size(sea, 5, 3) == std::array<int, 2>{2, 1});
    sea.mirror_resolution = 1.0;
    CHECK(S::detail::mirror_size(sea, 1920, 1080) == std::array<int, 2>{1920, 1080});
}

/// Sums over one band of sea rows of two renders a (the cheap mirror) and b (the full one).
struct SeaBand {
    double n = 0, sum_a = 0, sum_b = 0, sq_a = 0, sq_b = 0, diff2 = 0;
    void add(double a, double b) {
        n += 1, sum_a += a, sum_b += b, sq_a += a * a, sq_b += b * b, diff2 += (a - b) * (a - b);
    }
    double mean(double sum) const { return sum / n; }
    double sd(double sum, double sq) const {
        return std::sqrt(std::max(0.0, sq / n - mean(sum) * mean(sum)));
    }
};

/// The sea's rows of `a` and `b` in `count` bands from the horizon down; the sky's pixels must
/// be the same bits in both.
std::vector<SeaBand> sea_bands(const S::CameraConfig& c, const Frame& a, const Frame& b,
                               int count) {
    int first = a.height;
    for (int j = a.height - 1; j >= 0; --j) {
        double horiz, dz;
        ray(c, a.width, a.height, 0, j, horiz, dz);
        if (dz >= 0.0) break;
        first = j;
    }
    std::vector<SeaBand> bands(static_cast<size_t>(count));
    for (int j = 0; j < a.height; ++j)
        for (int i = 0; i < a.width; ++i) {
            if (j < first) {
                CHECK(a.at(i, j) == b.at(i, j));  // the sky does not see the mirror
                continue;
            }
            bands[size_t((j - first) * count / (a.height - first))].add(a.at(i, j), b.at(i, j));
        }
    return bands;
}

TEST_CASE("a half-size mirror stays within its tolerance of the full one", "[scenes][sea][slow]") {
    // clouds' sea (depth 3, rms slope 0.025, longest wave 10) at 1080p, the default mirror (half
    // size, 960 x 540) against the full one.
    const std::string keys = "[camera.sea]\ndepth = 3.0\nroughness = 0.025\nwavelength = 10.0\n";
    const S::OutputSize size{1920, 1080};
    const S::Scene cheap = S::load_scene_string(sea_scene(keys), "cheap.toml", {}, size);
    const S::Scene full =
        S::load_scene_string(sea_scene(keys + "mirror_resolution = 1.0\n"), "full.toml", {}, size);
    REQUIRE(S::detail::mirror_size(cheap.camera.sea, 1920, 1080) == std::array<int, 2>{960, 540});
    REQUIRE(S::detail::mirror_size(full.camera.sea, 1920, 1080) == std::array<int, 2>{1920, 1080});
    S::Renderer rc(cheap), rf(full);
    Frame a, b;
    rc.render(2, a), rf.render(2, b);
    const double sd = std::sqrt(S::scene_theory(cheap, 0.2).variance);
    const auto bands = sea_bands(cheap.camera, a, b, 4);
    // Tolerances (the difference is one frame pixel more blur of the reflected picture, no
    // sampling noise: the renders are deterministic). Measured per band from the horizon down:
    // rms 0.19, 0.14, 0.056, 0.016 of the texture's sd; mean within 0.002 sd (a blur keeps it);
    // sd 0.79, 0.90, 0.96, 0.99 of the full mirror's (the finest streaks at the horizon soften).
    // Allowed: rms 0.25 sd, mean 0.01 sd, sd at least 0.75 of the full one's and not above it.
    for (size_t k = 0; k < bands.size(); ++k) {
        const SeaBand& s = bands[k];
        const double rms = std::sqrt(s.diff2 / s.n), sd_a = s.sd(s.sum_a, s.sq_a),
                     sd_b = s.sd(s.sum_b, s.sq_b);
        CAPTURE(k, rms / sd, (s.mean(s.sum_a) - s.mean(s.sum_b)) / sd, sd_a / sd, sd_b / sd);
        CHECK(s.n > 10000);
        CHECK(sd_b > 0.3 * sd);  // the full mirror shows the deck's reflection
        CHECK(rms < 0.25 * sd);
        CHECK(std::abs(s.mean(s.sum_a) - s.mean(s.sum_b)) < 0.01 * sd);
        CHECK(sd_a > 0.75 * sd_b);
        CHECK(sd_a < 1.01 * sd_b);
    }
}

TEST_CASE("bad seas are refused with one line", "[scenes][sea][errors]") {
    CHECK_THROWS_WITH(
        S::load_scene_string(sea_scene("[camera.sea]\ndepth = -1.0\n"), "d.toml"),
        Catch::Contains("d.toml:15:9: camera.sea.depth = -1: expected a distance in (0, 1e6]"));
    CHECK_THROWS_WITH(S::load_scene_string(sea_scene("[camera.sea]\nroughness = 0.9\n"), "r.toml"),
                      Catch::Contains("camera.sea.roughness = 0.9") && Catch::Contains("[0, 0.5]"));
    CHECK_THROWS_WITH(
        S::load_scene_string(sea_scene("[camera.sea]\nmirror_resolution = 2.0\n"), "m.toml"),
        Catch::Contains("camera.sea.mirror_resolution = 2") && Catch::Contains("[0.125, 1]"));
    std::string high = sea_scene("[camera.sea]\ndepth = 3.0\n");
    high.replace(high.find("pitch = 14.0"), 12, "pitch = 40.0");
    CHECK_THROWS_WITH(
        S::load_scene_string(high, "p.toml"),
        Catch::Contains("p.toml") && Catch::Contains("the horizon is above the frame"));
    const std::string ground = R"(
[camera]
type = "perspective"
pitch = 30.0
[camera.sea]
depth = 2.0
[[layer]]
)";
    CHECK_THROWS_WITH(S::load_scene_string(ground, "g.toml"),
                      Catch::Contains("g.toml") && Catch::Contains("plane = \"sky\""));
}
