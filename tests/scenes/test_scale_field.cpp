// SPDX-License-Identifier: Apache-2.0
// [layer.scale]: the local statistics follow the kernel scale field (docs/scenes.md "Kernel scale
// fields"). A field s = 1 on the left half of the frame and s = 2 on the right: an impulse of
// scale s draws g_s(x) = h(x / s) / s, so with lambda impulses per unit area and E[a^2] = 1
//     variance          lambda int g_s^2            = lambda int h^2          (any s)
//     structure fn.     D_s(tau) = E (f(x + tau) - f(x))^2
//                                = 2 lambda [(h * h~)(0) - (h * h~)(tau / s)]
// (Campbell's theorem; (g_s * g_s~)(tau) = (h * h~)(tau / s) by x = s y). D is the lag-domain
// form of the spectrum, D(tau) = 2 int (1 - cos 2 pi k.tau) S(k) dk, so matching it at every lag
// in each half says S_s(k) = s^2 S(s k) there: the local spectrum moves down an octave on the
// right. The periodogram test checks the same in the frequency domain against a layer whose kernel
// is itself twice as large. Bands: 4 standard errors of the mean over 64 x 64 blocks (their
// scatter, measured in the run), plus the quadrature error of (h * h~) (1e-4 relative, Kernel).

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"

namespace {

namespace test = impulse::test;
using impulse::render::Frame;

constexpr int kBlock = 64;

/// Mean and standard error (scatter / sqrt(n)) of per-block values.
struct BlockMean {
    double mean = 0.0, se = 0.0;
};
BlockMean block_mean(const std::vector<double>& v) {
    double s = 0.0, s2 = 0.0;
    for (double x : v) s += x;
    const double m = s / v.size();
    for (double x : v) s2 += (x - m) * (x - m);
    return {m, std::sqrt(s2 / (v.size() - 1) / v.size())};
}

/// Per 64 x 64 block of columns [x0, x1): the mean of (f(x + lag, y) - f(x, y))^2 over pairs
/// inside the block, or of f^2 (the mean is 0) for lag = 0.
std::vector<double> block_values(const Frame& f, int x0, int x1, int lag) {
    std::vector<double> out;
    for (int by = 0; by + kBlock <= f.height; by += kBlock)
        for (int bx = x0; bx + kBlock <= x1; bx += kBlock) {
            double s = 0.0;
            int n = 0;
            for (int y = by; y < by + kBlock; ++y)
                for (int x = bx; x + lag < bx + kBlock; ++x, ++n) {
                    const double a = f.data[size_t(y) * f.width + x];
                    const double d = lag ? f.data[size_t(y) * f.width + x + lag] - a : a;
                    s += d * d;
                }
            out.push_back(s / n);
        }
    return out;
}

struct Rendered {
    impulse::scenes::Scene scene;
    Frame frame;
};
Rendered render(const std::string& text) {
    Rendered r{impulse::scenes::load_scene_string(text, "scale.toml"), {}};
    impulse::scenes::Renderer(r.scene).render(0, r.frame);
    return r;
}

const char* const kHalves = R"(
[output]
size = [1024, 512]
[[layer]]
seed = 7
density = 16.0
scale = { type = "linear", from = [511.0, 0.0], to = [513.0, 0.0], values = [1.0, 2.0] }
[layer.kernel]
type = "cosine"
radius = 8.0
)";

/// Columns of each half, a kernel radius (at its scale) and more away from the step.
constexpr int kLeft0 = 0, kLeft1 = 448, kRight0 = 576, kRight1 = 1024;

}  // namespace

TEST_CASE("the structure function of each half follows the scale field", "[scenes][stats][scale]") {
    const Rendered r = render(kHalves);
    const auto& layer = r.scene.layers[0];
    const impulse::kernels::Kernel h(layer.kernel);
    const double lambda = layer.process.intensity;
    const double c0 = h.autocorrelation(0.0, 0.0);
    for (const auto& [x0, x1, s] : {std::tuple{kLeft0, kLeft1, 1.0}, {kRight0, kRight1, 2.0}}) {
        const double scale = s;
        const BlockMean v = block_mean(block_values(r.frame, x0, x1, 0));
        INFO("s = " << scale << ": variance " << v.mean << " +- " << v.se << ", closed form "
                    << lambda * h.integral_sq());
        CHECK(std::abs(v.mean - lambda * h.integral_sq()) <= 4.0 * v.se);
        for (int lag : {1, 2, 4, 8, 12}) {
            const BlockMean d = block_mean(block_values(r.frame, x0, x1, lag));
            const double expected = 2.0 * lambda * (c0 - h.autocorrelation(lag / scale, 0.0));
            INFO("s = " << scale << ", lag " << lag << ": D = " << d.mean << " +- " << d.se
                        << ", closed form " << expected);
            CHECK(std::abs(d.mean - expected) <= 4.0 * d.se + 1e-4 * 2.0 * lambda * c0);
        }
    }
}

TEST_CASE("an impulse between two scale classes keeps its int h^2", "[scenes][stats][scale]") {
    // s = 1.5 lies between the classes 2^(4/8) and 2^(5/8) (f = 0.67): the split keeps
    // lambda int h^2 exactly, where amplitudes of 1 instead of 1/s would give 2.25 times it.
    std::string text = kHalves;
    text.replace(text.find("scale = {"), text.find('\n', text.find("scale = {")) - text.find("scale = {"),
                 "scale = 1.5");
    const Rendered r = render(text);
    const auto& layer = r.scene.layers[0];
    const double expected = layer.process.intensity * impulse::kernels::Kernel(layer.kernel).integral_sq();
    const BlockMean v = block_mean(block_values(r.frame, 0, 1024, 0));
    INFO("variance " << v.mean << " +- " << v.se << ", closed form " << expected);
    CHECK(std::abs(v.mean - expected) <= 4.0 * v.se);
}

TEST_CASE("the right half has the spectrum of a kernel twice as large", "[scenes][stats][scale]") {
    // Periodograms (Hann window) of the 64 x 64 blocks, radially averaged: the spectral centroid
    // sum k P(k) / sum P(k) of the right half against that of a layer whose kernel has radius 16
    // (the same spectrum S(k) = lambda_8 / 4 |H_16(k)|^2 = lambda_16 |H_16(k)|^2, the same
    // window), and of the left half against the radius-8 kernel itself.
    auto centroids = [](const Frame& f, int x0, int x1) {
        std::vector<double> out;
        for (int by = 0; by + kBlock <= f.height; by += kBlock)
            for (int bx = x0; bx + kBlock <= x1; bx += kBlock) {
                impulse::analysis::Image im{kBlock, kBlock, {}};
                for (int y = by; y < by + kBlock; ++y)
                    for (int x = bx; x < bx + kBlock; ++x)
                        im.data.push_back(f.data[size_t(y) * f.width + x]);
                const auto p = impulse::analysis::radial_average(
                    impulse::analysis::periodogram(im, impulse::analysis::Window::Hann));
                double num = 0.0, den = 0.0;
                for (size_t b = 1; b < p.power.size(); ++b)
                    num += p.frequency[b] * p.power[b] * p.count[b], den += p.power[b] * p.count[b];
                out.push_back(num / den);
            }
        return block_mean(out);
    };
    const Rendered r = render(kHalves);
    std::string plain = kHalves;
    plain.erase(plain.find("scale = {"), plain.find('\n', plain.find("scale = {")) - plain.find("scale = {"));
    plain.replace(plain.find("seed = 7"), 8, "seed = 8");  // other impulses: independent
    std::string large = plain;
    large.replace(large.find("radius = 8.0"), 12, "radius = 16.0");
    const Frame f8 = render(plain).frame, f16 = render(large).frame;
    const BlockMean left = centroids(r.frame, kLeft0, kLeft1), right = centroids(r.frame, kRight0, kRight1);
    const BlockMean ref8 = centroids(f8, kLeft0, kLeft1), ref16 = centroids(f16, kRight0, kRight1);
    INFO("centroids (cycles/px): left " << left.mean << " +- " << left.se << " (radius 8: "
                                        << ref8.mean << " +- " << ref8.se << "), right "
                                        << right.mean << " +- " << right.se << " (radius 16: "
                                        << ref16.mean << " +- " << ref16.se << ")");
    CHECK(std::abs(left.mean - ref8.mean) <= 4.0 * std::hypot(left.se, ref8.se));
    CHECK(std::abs(right.mean - ref16.mean) <= 4.0 * std::hypot(right.se, ref16.se));
    // The centroid moves down by about an octave (not exactly 2: the window's leakage and the
    // pixel grid do not scale with the kernel).
    CHECK(left.mean / right.mean > 1.5);
}

namespace {

const char* const kCameras[] = {
    "",  // orthographic, the evaluator's own loops
    "[camera]\nantialias = \"blend\"\n",  // orthographic through the pyramid
    "[camera]\ntype = \"perspective\"\nposition = [256.0, 128.0]\nheight = 40.0\npitch = 20.0\n"
    "fov = 60.0\n",
};

std::string camera_scene(const char* camera, const std::string& scale) {
    return std::string("[output]\nsize = [256, 144]\n") + camera +
           "[[layer]]\ndensity = 16.0\n" + scale +
           "[layer.kernel]\ntype = \"gabor\"\nradius = 8.0\nfrequency = 0.15\n";
}

}  // namespace

TEST_CASE("scale = 1 draws the bits of the layer without a scale in every camera",
          "[scenes][scale][slow]") {
    // One class (s_0 = 1), weights w c(0) / 1 = w and the kernel (or pyramid) of h(x / 1): the
    // class path repeats the unscaled arithmetic exactly, through each evaluator.
    for (const char* camera : kCameras) {
        INFO(camera);
        const Frame plain = render(camera_scene(camera, "")).frame;
        const Frame one = render(camera_scene(camera, "scale = 1.0\n")).frame;
        CHECK(test::same_bits(plain, one));
        const Frame two = render(camera_scene(camera, "scale = 2.0\n")).frame;
        CHECK_FALSE(test::same_bits(plain, two));
    }
}

TEST_CASE("a scale field draws the same bits for any thread count and tiling", "[scenes][scale][determinism]") {
    const std::string text = camera_scene(
        "", "scale = { type = \"radial\", center = [128.0, 72.0], radius = 100.0, values = [0.7, 2.5] }\n");
    impulse::scenes::Renderer r(impulse::scenes::load_scene_string(text, "scale.toml"));
    Frame a, b, c;
    r.render(0, a);
    impulse::render::EvalOptions serial;
    serial.parallel = false;
    serial.tile_size = 24;
    r.render(0, b, serial);
    impulse::render::EvalOptions baseline;
    baseline.use_avx2 = false;
    r.render(0, c, baseline);
    CHECK(test::same_bits(a, b));
    CHECK(test::same_bits(a, c));
}

TEST_CASE("a scale image that cannot be read is refused with one line", "[scenes][scale][errors]") {
    const std::string text = "[[layer]]\nscale = { type = \"image\", path = \"no_such_scale.exr\" }\n";
    REQUIRE_THROWS_WITH(impulse::scenes::load_scene_string(text, "s.toml"),
                        Catch::Contains("s.toml:2:34: layer[0].scale.path = \"no_such_scale.exr\": "
                                        "cannot read"));
}
