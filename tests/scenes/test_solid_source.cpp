// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "solid": a slice z = z0 + velocity t through solid noise as a layer
// (scenes/sources/source_solid.cpp on the layer-source seam): the slice's variance against Campbell's
// 3-D variance, moving through the noise, and bad input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
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

TEST_CASE("solid layer: a slice has Campbell's 3-D variance", "[scenes][solid][slow]") {
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
    fails_with(base + "[layer.solid]\nkernel = \"gabor\"\n", "cosine, gaussian, spectrum");
    fails_with(base + "density = 4.0\n", "a solid layer has no density");
    fails_with("[[layer]]\nsource = \"solidish\"\n", "impulses, fbm, subdivision, solid");
}

TEST_CASE("solid layer: a designed kernel's slice has the stated 2-D spectrum",
          "[scenes][solid][design][slow]") {
    // kernel = "autocorrelation", gaussian l = 3 in 3-D, band-limited to the pixel Nyquist
    // frequency (0.5 at zoom 1): the source states the slice's S_2 (projection-slice), and no
    // power aliases. Hann-windowed periodograms of 128^2 frames, 16 seeds, averaged in annuli 4
    // bins wide; an annulus of M bins holds M / 2 independent ones (S(k) = S(-k)), and the
    // Hann window correlates neighbours: variance factor (1 + 2 (2/3)^2 + 2 (1/6)^2)^2 = 3.78.
    const int n = 128, seeds = 16, width = 4;
    const int annuli = n / 2 / width;
    std::vector<double> meas(annuli, 0.0), theo(annuli, 0.0), count(annuli, 0.0);
    const std::string solid = "kernel = \"autocorrelation\"\nmodel = \"gaussian\"\nlength = 3.0\nvariance = 2.0\n";
    std::vector<double> w(n);
    for (int i = 0; i < n; ++i) w[i] = 0.5 - 0.5 * std::cos(2 * M_PI * i / n);
    double wsum = 0;
    for (double v : w) wsum += v * v;
    wsum *= wsum;  // the 2-D window's sum of squares
    std::vector<std::complex<double>> twiddle(n);
    for (int j = 0; j < n; ++j) twiddle[j] = std::polar(1.0, -2 * M_PI * j / n);
    for (int seed = 1; seed <= seeds; ++seed) {
        std::string text = solid_scene(seed, solid);
        text.erase(text.find("radius = 4.0\n"), 13);  // the design chooses its radius
        const scenes::Scene scene = scenes::load_scene_string(text, "s.toml");
        const auto& src = *scene.layers[0].source;
        const render::Frame f = render_at(text, 0);
        // Direct 2-D DFT by rows then columns (128^2: cheap enough without FFTW here).
        std::vector<std::complex<double>> a(size_t(n) * n), b(size_t(n) * n);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) a[size_t(y) * n + x] = f.at(x, y) * w[x] * w[y];
        auto dft = [&](const std::vector<std::complex<double>>& in, std::vector<std::complex<double>>& out, bool rows) {
            for (int l = 0; l < n; ++l)
                for (int k = 0; k < n; ++k) {
                    std::complex<double> s = 0;
                    for (int j = 0; j < n; ++j)
                        s += (rows ? in[size_t(l) * n + j] : in[size_t(j) * n + l]) * twiddle[(j * k) % n];
                    (rows ? out[size_t(l) * n + k] : out[size_t(k) * n + l]) = s;
                }
        };
        dft(a, b, true);
        dft(b, a, false);
        for (int ky = 0; ky < n; ++ky)
            for (int kx = 0; kx < n; ++kx) {
                const double fx = double(kx < n / 2 ? kx : kx - n) / n, fy = double(ky < n / 2 ? ky : ky - n) / n;
                const double k = std::hypot(fx, fy);
                const int ann = static_cast<int>(k * n / width);
                if (ann < 1 || ann >= annuli) continue;
                // E|DFT|^2 = S(k) sum w^2 (unit pixel spacing), for a spectrum smooth over bins.
                meas[ann] += std::norm(a[size_t(ky) * n + kx]) / wsum;
                theo[ann] += *src.power_spectrum(k);
                count[ann] += 1;
            }
    }
    double peak = 0;
    for (int i = 1; i < annuli; ++i) peak = std::max(peak, theo[i] / count[i]);
    int checked = 0;
    for (int i = 1; i < annuli; ++i) {
        if (theo[i] / count[i] < 0.01 * peak) continue;
        const double ratio = meas[i] / theo[i];
        const double se = std::sqrt(3.78 / (0.5 * count[i]));
        INFO("annulus " << i << " (k ~ " << (i + 0.5) * width / n << "): measured / stated " << ratio << " +- " << se);
        CHECK(std::abs(ratio - 1.0) <= 5.0 * se);
        ++checked;
    }
    CHECK(checked >= 4);
}

TEST_CASE("solid layer: designed kernels refused and aliasing warned at the key", "[scenes][solid][errors]") {
    const std::string base = "[[layer]]\nsource = \"solid\"\n[layer.solid]\n";
    auto fails_with = [&](const std::string& text, const std::string& what) {
        CAPTURE(text);
        REQUIRE_THROWS_WITH(scenes::load_scene_string(text, "bad.toml"), Catch::Contains(what));
    };
    fails_with(base + "kernel = \"spectrum\"\nmodel = \"bandpass\"\n", "defined in 2-D");
    fails_with(base + "kernel = \"spectrum\"\nexpression = \"exp(-k*k*100) * (1 - 40*k)\"\n", "is negative");
    fails_with(base + "kernel = \"autocorrelation\"\nexpression = \"cos(r) * exp(-r*r/400)\"\n", "-0.218 R(0)");
    fails_with(base + "dims = 4\nkernel = \"autocorrelation\"\nmodel = \"gaussian\"\n", "needs dims = 3");
    const scenes::Scene small = scenes::load_scene_string(base + "radius = 1.5\n", "s.toml");
    bool warned = false;
    for (const auto& w : small.warnings) warned |= w.find("under 2: the slice aliases") != std::string::npos;
    CHECK(warned);
    const scenes::Scene fine = scenes::load_scene_string(base + "radius = 2.5\n", "s.toml");
    for (const auto& w : fine.warnings) CHECK(w.find("aliases") == std::string::npos);
}
