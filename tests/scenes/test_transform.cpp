// SPDX-License-Identifier: Apache-2.0
// Field transforms (Lewis 1989 §5.1): marble and wood. Without turbulence the output is the
// analytic stripes and rings at every pixel's texture point (camera zoom and pan included);
// with turbulence the marble's mean against its closed form E[sin(theta + k Z)] =
// sin(theta) Re phi_Z(k), phi_Z the characteristic function of the normalised shot noise;
// wood's random ring widths stay within their bounds; the display range follows the transform.

#include <tbb/global_control.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace {

using impulse::render::Frame;
using impulse::scenes::load_scene_string;
constexpr double kPi = std::numbers::pi;

Frame render(const impulse::scenes::Scene& s) {
    impulse::scenes::Renderer r(s);
    Frame f;
    r.render(0, f);
    return f;
}

/// The wood ring profile written out independently: 1 - s^a (1 - s) / max, max at a / (a + 1).
double xtab(double s, double a) {
    const double peak = a / (a + 1);
    return 1 - std::pow(s, a) * (1 - s) / (std::pow(peak, a) * (1 - peak));
}

const char* kNoise = R"([output]
size = [1024, 1024]
[[layer]]
seed = 9
density = 16.0
[layer.kernel]
type = "cosine"
radius = 8.0
)";

}  // namespace

TEST_CASE("marble and wood without turbulence are the analytic stripes and rings",
          "[scenes][transform]") {
    // Float output of a double computation: agreement to 1e-6 (the float rounding of values in
    // [-1, 1] is below 6e-8).
    SECTION("marble, camera zoomed and panned") {
        const std::string text = std::string(kNoise) + R"([camera]
center = [300.0, -120.0]
zoom = 2.5
[shading.transform]
type = "marble"
angle = 0.7
frequency = 0.013
phase = 0.4
turbulence = 0.0
)";
        const auto scene = load_scene_string(text, "marble.toml");
        const Frame f = render(scene);
        const auto v = scene.camera.view(1024, 1024, 0.0);
        CHECK(v.scale == Approx(0.4));
        double worst = 0;
        for (int j = 0; j < f.height; j += 3)
            for (int i = 0; i < f.width; i += 3) {
                const double x = v.x0 + (i + 0.5) * v.scale, y = v.y0 + (j + 0.5) * v.scale;
                const double e = std::sin(2 * kPi * 0.013 * (x * std::cos(0.7) + y * std::sin(0.7)) + 0.4);
                worst = std::max(worst, std::abs(f.at(i, j) - e));
            }
        CHECK(worst < 1e-6);
        // The same bits on one thread (per-pixel work, no order dependence).
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        const Frame g = render(scene);
        CHECK(std::memcmp(f.data.data(), g.data.data(), f.data.size() * sizeof(float)) == 0);
    }
    SECTION("wood, periodic rings round the centre") {
        const std::string text = std::string(kNoise) + R"([shading.transform]
type = "wood"
center = [200.0, 700.0]
ring_width = 23.0
sharpness = 4.0
turbulence = 0.0
)";
        const Frame f = render(load_scene_string(text, "wood.toml"));
        double worst = 0, lo = 1, hi = 0;
        for (int j = 0; j < f.height; j += 3)
            for (int i = 0; i < f.width; i += 3) {
                const double r = std::hypot(i + 0.5 - 200, j + 0.5 - 700) / 23.0;
                worst = std::max(worst, std::abs(f.at(i, j) - xtab(r - std::floor(r), 4.0)));
                lo = std::min<double>(lo, f.at(i, j)), hi = std::max<double>(hi, f.at(i, j));
            }
        CHECK(worst < 1e-6);
        CHECK(lo >= 0.0);
        CHECK(lo < 0.01);
        CHECK(hi <= 1.0);
        CHECK(hi > 0.99);
    }
    SECTION("wood with growth: ring widths vary within ring_width (1 +- growth)") {
        // Along the row through the centre, the latewood minima of xtab sit at
        // R_k + c w_k (c = a / (a + 1)), so consecutive minima are (1 - c) w_k + c w_(k+1)
        // apart: within [w (1 - g), w (1 + g)] and, with random widths, not all equal.
        const std::string text = std::string(kNoise) + R"([shading.transform]
type = "wood"
center = [0.0, 512.0]
ring_width = 20.0
growth = 0.5
turbulence = 0.0
)";
        const Frame f = render(load_scene_string(text, "wood.toml"));
        std::vector<double> minima;
        for (int i = 1; i + 1 < f.width; ++i) {
            const float a = f.at(i - 1, 511), b = f.at(i, 511), c = f.at(i + 1, 511);
            if (b < a && b <= c && b < 0.2f) minima.push_back(i);
        }
        REQUIRE(minima.size() > 30);
        double min_gap = 1e9, max_gap = 0;
        for (size_t k = 1; k < minima.size(); ++k) {
            min_gap = std::min(min_gap, minima[k] - minima[k - 1]);
            max_gap = std::max(max_gap, minima[k] - minima[k - 1]);
        }
        CAPTURE(min_gap, max_gap, minima.size());
        CHECK(min_gap >= 10 - 1);  // one pixel of quantisation
        CHECK(max_gap <= 30 + 1);
        CHECK(max_gap - min_gap > 5);
    }
}

TEST_CASE("marble with turbulence: the mean follows sin(theta) Re phi_Z(k)",
          "[scenes][transform][stats]") {
    // v = sin(theta + k Z), theta = 2 pi x / 32 (angle 0, 32 px period, 32 whole periods per
    // row), Z = f / sigma the field in standard deviations. Normal amplitudes make Z symmetric,
    // so E[v] = sin(theta) E[cos kZ] = sin(theta) Re phi_Z(k), and E[v^2] = 1/2 - 1/2 cos(2 theta)
    // Re phi_Z(2k). For shot noise with normal amplitudes (Campbell's theorem for the
    // characteristic function) phi_X(t) = exp(lambda int (exp(-t^2 h(x)^2 / 2) - 1) d^2x), and
    // phi_Z(k) = phi_X(k / sigma): exact, not the Gaussian limit exp(-k^2 / 2).
    // Estimators: A = (2/N) sum v_p sin(theta_p), E[A] = Re phi(k) (2/N) sum sin^2 theta_p;
    // B = -(4/N) sum v_p^2 cos(2 theta_p), E[B] = Re phi(2k) (2/N) sum cos^2 (2 theta_p);
    // C = (2/N) sum v_p cos(theta_p), E[C] = 0.
    // Bands: the frame is cut into 64 blocks of 128 x 128 (4 periods each); values further
    // apart than the kernel's diameter (16 px) are independent, so block estimates are nearly
    // independent and the standard error of their mean is sd(blocks) / 8; band 5 standard
    // errors (Student t with 63 degrees of freedom: a 5-sd excursion has probability < 1e-5).
    const auto base = load_scene_string(kNoise, "marble.toml");
    const impulse::kernels::Kernel kern(base.layers[0].kernel);
    const double lambda = base.layers[0].process.intensity;
    const double sigma = std::sqrt(impulse::scenes::scene_theory(base).variance);
    auto phi = [&](double k) {
        const double t = k / sigma, R = kern.radius();
        double s = 0;
        const int n = 4000;
        for (int i = 0; i < n; ++i) {
            const double r = (i + 0.5) * R / n, h = kern.evaluate(r, 0);
            s += 2 * kPi * r * (std::exp(-0.5 * t * t * h * h) - 1) * R / n;
        }
        return std::exp(lambda * s);
    };
    for (double k : {0.5, 1.0, 2.0}) {
        const std::string text = std::string(kNoise) +
                                 "[shading.transform]\ntype = \"marble\"\nangle = 0.0\n"
                                 "frequency = 0.03125\nturbulence = " + std::to_string(k) + "\n";
        const Frame f = render(load_scene_string(text, "marble.toml"));
        std::vector<double> a_blocks, b_blocks, c_blocks;
        double a_norm = 0, b_norm = 0;
        for (int by = 0; by < 8; ++by)
            for (int bx = 0; bx < 8; ++bx) {
                double a = 0, b = 0, c = 0, sa = 0, sb = 0;
                for (int j = by * 128; j < by * 128 + 128; ++j)
                    for (int i = bx * 128; i < bx * 128 + 128; ++i) {
                        const double th = 2 * kPi * (i + 0.5) / 32, v = f.at(i, j);
                        a += v * std::sin(th), sa += std::sin(th) * std::sin(th);
                        b -= v * v * std::cos(2 * th), sb += std::cos(2 * th) * std::cos(2 * th);
                        c += v * std::cos(th);
                    }
                const double n = 128.0 * 128.0;
                a_blocks.push_back(2 * a / n), b_blocks.push_back(4 * b / n), c_blocks.push_back(2 * c / n);
                a_norm += 2 * sa / n / 64, b_norm += 2 * sb / n / 64;
            }
        auto mean_se = [](const std::vector<double>& x) {
            double m = 0, s = 0;
            for (double v : x) m += v;
            m /= x.size();
            for (double v : x) s += (v - m) * (v - m);
            return std::pair{m, std::sqrt(s / (x.size() - 1) / x.size())};
        };
        const auto [a, a_se] = mean_se(a_blocks);
        const auto [b, b_se] = mean_se(b_blocks);
        const auto [c, c_se] = mean_se(c_blocks);
        const double ea = phi(k) * a_norm, eb = phi(2 * k) * b_norm;
        const double gauss = std::exp(-0.5 * k * k) * a_norm;
        CAPTURE(k, a, ea, a_se, gauss, b, eb, b_se, c, c_se);
        CHECK(std::abs(a - ea) < 5 * a_se);
        CHECK(std::abs(b - eb) < 5 * b_se);
        CHECK(std::abs(c) < 5 * c_se);
        // Teeth: without the turbulence the projection is 1, far outside the band.
        CHECK(std::abs(a_norm - ea) > 20 * a_se);
        // At k = 2 the Gaussian limit exp(-k^2/2) is rejected: density 16 is not Gaussian
        // enough for the phase's fourth cumulant (the exact phi is 40 % larger).
        if (k == 2.0) CHECK(std::abs(a - gauss) > 5 * a_se);
    }
}

TEST_CASE("the display range follows the transform", "[scenes][transform]") {
    const std::string layer = "[output]\nsize = [64, 64]\n[[layer]]\n";
    auto map_of = [](const std::string& text) {
        impulse::scenes::Renderer r(load_scene_string(text, "m.toml"));
        return r.mapping();
    };
    const auto m = map_of(layer + "[shading.transform]\ntype = \"marble\"\n");
    CHECK(m.lo == -1.0);
    CHECK(m.hi == 1.0);
    const auto w = map_of(layer + "[shading.transform]\ntype = \"wood\"\n");
    CHECK(w.lo == 0.0);
    CHECK(w.hi == 1.0);
    const auto o = map_of("[output]\nsize = [64, 64]\nrange = [-0.5, 0.5]\n[[layer]]\n"
                          "[shading.transform]\ntype = \"marble\"\n");
    CHECK(o.lo == -0.5);
    CHECK(o.hi == 0.5);
    const auto none = map_of(layer);
    CHECK(none.hi == Approx(-none.lo));
    CHECK(none.hi > 3.0);  // mean +- 3 sd of the untransformed field
}

TEST_CASE("wood rings too many for the view are refused, not tabulated for minutes",
          "[scenes][transform][errors]") {
    // 64 x 64 view centred on the trunk: the far corner is 45 units out. Rings of width 1e-6 with
    // growth (their boundaries tabulated) would number 4.5e7, over the limit of 1e7; a
    // ring_width of 1e-6 had run for minutes. Growth near 1 makes some rings thin, not many.
    const std::string head = "[output]\nsize = [64, 64]\n[[layer]]\n[shading.transform]\n"
                             "type = \"wood\"\n";
    Frame f;
    impulse::scenes::Renderer many(
        load_scene_string(head + "ring_width = 1e-6\ngrowth = 0.5\n", "w.toml"));
    CHECK_THROWS_AS(many.render(0, f), impulse::SceneError);
    CHECK_THROWS_WITH(many.render(0, f),
                      Catch::StartsWith("w.toml: shading.transform: wood: rings of width 1e-06") &&
                          Catch::Contains("over the limit of 1e+07"));
    impulse::scenes::Renderer thin(
        load_scene_string(head + "ring_width = 8.0\ngrowth = 0.99999999\n", "w.toml"));
    CHECK_NOTHROW(thin.render(0, f));
    impulse::scenes::Renderer periodic(load_scene_string(head + "ring_width = 1e-6\n", "w.toml"));
    CHECK_NOTHROW(periodic.render(0, f));  // no table without growth
}
