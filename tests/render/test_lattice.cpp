// SPDX-License-Identifier: Apache-2.0
// Multi-rate evaluation (docs/multirate.md): the error of a lattice and its cubic B-spline
// reconstruction, measured against direct evaluation, stays within the prediction, and the
// prediction is not loose; tolerance 0 is direct evaluation bit for bit; the lattice path is
// deterministic for any thread count and tile size.

#include <tbb/task_arena.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "kernels/kernels.h"
#include "render/render.h"

using namespace impulse;

namespace {

/// A Poisson impulse set over `box` at `per_area` impulses per kernel area, amplitudes +-1,
/// angles uniform in [0, 2 pi) when `turned` (else 0): a still layer of the point process
/// (Lewis 1986 §3) without the simulator, so the test sees the evaluator alone.
sim::Impulses poisson(const kernels::Kernel& k, const numeric::Box& box, double per_area,
                      bool turned, uint64_t seed, double* lambda) {
    *lambda = per_area / k.support_area();
    const double R = k.radius();
    const double x0 = box.x0 - R, y0 = box.y0 - R, x1 = box.x1 + R, y1 = box.y1 + R;
    std::mt19937_64 rng(seed);
    std::poisson_distribution<long> count(*lambda * (x1 - x0) * (y1 - y0));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const long n = count(rng);
    sim::Impulses imp;
    for (long i = 0; i < n; ++i) {
        imp.x.push_back(x0 + u(rng) * (x1 - x0));
        imp.y.push_back(y0 + u(rng) * (y1 - y0));
        imp.weight.push_back(u(rng) < 0.5 ? -1.0f : 1.0f);
        imp.theta.push_back(turned ? static_cast<float>(2.0 * std::numbers::pi * u(rng)) : 0.0f);
    }
    return imp;
}

struct Case {
    const char* name;
    kernels::KernelParams params;
    bool turned;
    int min_spacing;  ///< the rule must find at least this (band-limited kernels pay off)
};

kernels::KernelParams cosine(double r) {
    kernels::KernelParams p;
    p.type = kernels::KernelType::Cosine, p.radius = r;
    return p;
}
kernels::KernelParams gaussian(double sigma) {
    kernels::KernelParams p;
    // The radius where the Gaussian's step is 1e-3 of its peak: sqrt(2 ln 1000) sigma.
    p.type = kernels::KernelType::Gaussian, p.sigma = sigma, p.radius = 3.7169 * sigma;
    return p;
}
kernels::KernelParams gabor(double r, double f) {
    kernels::KernelParams p;
    p.type = kernels::KernelType::Gabor, p.radius = r, p.frequency = f;
    return p;
}

struct Measured {
    double rms = 0.0, border_rms = 0.0;
    int pixels = 0, border_pixels = 0;
};

/// rms of (lattice - direct) over the view and over its outer band of 2h pixels, / sd.
Measured measure(const render::Frame& direct, const render::Frame& approx, int band, double sd) {
    Measured m;
    double all = 0.0, border = 0.0;
    for (int y = 0; y < direct.height; ++y)
        for (int x = 0; x < direct.width; ++x) {
            const double d = double(approx.at(x, y)) - direct.at(x, y);
            all += d * d, ++m.pixels;
            if (x < band || y < band || x >= direct.width - band || y >= direct.height - band)
                border += d * d, ++m.border_pixels;
        }
    m.rms = std::sqrt(all / m.pixels) / sd;
    m.border_rms = std::sqrt(border / m.border_pixels) / sd;
    return m;
}

}  // namespace

TEST_CASE("a lattice's measured error is within its predicted error, and the prediction is tight",
          "[render][lattice]") {
    // The rms rule alone (keep_spectrum = false): its coarser spacings measure the prediction
    // where the error is largest; the renderer's rule (below) is finer still.
    const double tolerance = render::kRecommendedLatticeTolerance;
    kernels::KernelParams aniso = cosine(24.0);
    aniso.aspect = 2.5;
    const std::vector<Case> cases = {
        {"cosine r16", cosine(16.0), false, 2},
        {"cosine r40", cosine(40.0), false, 4},
        {"gaussian sigma 6 (radius at 1e-3)", gaussian(6.0), false, 3},
        {"gaussian sigma 20", gaussian(20.0), false, 8},
        {"gabor f 1/40 (low)", gabor(48.0, 1.0 / 40.0), true, 2},
        {"gabor f 1/5 (high)", gabor(24.0, 0.2), true, 1},
        {"anisotropic cosine", aniso, true, 2},
    };
    render::View view;
    view.width = 480, view.height = 240;  // whole multiples of every spacing up to 16 but 7..
    for (const Case& c : cases) {
        const kernels::Kernel k(c.params);
        const render::LatticeRule rule = render::choose_lattice(k, view.scale, tolerance, false);
        const render::LatticeError e = render::lattice_error(k, view.scale, rule.spacing, rule.margin);
        INFO(c.name << ": h = " << rule.spacing << ", predicted " << rule.predicted_error
                    << " (interpolation " << e.interpolation << ", beyond " << e.beyond
                    << ", boundary " << e.boundary << "), next " << rule.next_error);
        CHECK(rule.spacing >= c.min_spacing);
        CHECK(rule.predicted_error <= tolerance);
        if (rule.spacing == 1) continue;
        CHECK(rule.next_error > tolerance);
        double lambda = 0.0;
        const auto imp = poisson(k, render::lattice_view(view, rule).box(), 16.0, c.turned,
                                 7 + rule.spacing, &lambda);
        const double sd = std::sqrt(lambda * k.integral_sq());  // Campbell, E[a^2] = 1
        render::Frame direct, approx;
        direct.resize(view.width, view.height), approx.resize(view.width, view.height);
        render::accumulate(k, imp, view, direct);
        render::accumulate_lattice(k, imp, view, rule, approx);
        const Measured m = measure(direct, approx, 2 * rule.spacing, sd);
        // The squared error averaged over the pixels scatters with the field: about one
        // independent value per kernel area (the error is the field's band near the lattice's
        // Nyquist frequency, modulated by the impulses), so its relative sd is sqrt(2 / N_eff)
        // with N_eff = pixels / kernel area in pixels; 3 sd either way.
        const double n_eff = m.pixels / k.support_area();
        const double band = 3.0 * std::sqrt(2.0 / n_eff);
        INFO("measured rms " << m.rms << ", border " << m.border_rms << ", band +-" << band
                             << " in the mean square");
        CHECK(m.rms <= rule.predicted_error * std::sqrt(1.0 + band));
        // Not loose: the quadrature part is the error's expectation, not only a bound.
        CHECK(m.rms >= e.interpolation * std::sqrt(std::max(0.0, 1.0 - band)));
        // The margin keeps the border as good as the middle (the prefilter's start).
        const double n_border = m.border_pixels / k.support_area() + 1.0;
        CHECK(m.border_rms <= rule.predicted_error * std::sqrt(1.0 + 3.0 * std::sqrt(2.0 / n_border)));
    }
}

TEST_CASE("a truncated Gaussian is not band-limited: the rule keeps it direct", "[render][lattice]") {
    // sigma 8 cut at the default radius 16 (2 sigma): a 13.5 % step, ~1 % of the power above
    // 0.1 cycles per pixel. The rms error alone already keeps it direct.
    kernels::KernelParams p;
    p.type = kernels::KernelType::Gaussian, p.sigma = 8.0, p.radius = 16.0;
    CHECK(render::choose_lattice(kernels::Kernel(p), 1.0, 0.005).spacing == 1);
    const render::LatticeRule rms = render::choose_lattice(kernels::Kernel(p), 1.0, 0.005, false);
    CHECK(rms.spacing == 1);
    CHECK(rms.next_error > 0.005);
}

TEST_CASE("the renderer's rule keeps the spectrum: every frequency within 1e-3 of its power or "
          "under the 8-bit noise",
          "[render][lattice]") {
    // docs/multirate.md §5. With the rms rule alone at 0.005, the periodogram test of a periodic
    // cosine r16 frame (tests/render/test_stats.cpp) had 28 of 162 annuli out of their 5-sd band
    // (worst z = 14, near the lattice's Nyquist frequency, h = 3); with the spectral bound the
    // rule takes h = 2 and that test passes at the default tolerance.
    struct Expect {
        const char* name;
        kernels::KernelParams params;
        int spacing, rms_spacing;  // with the spectrum kept, and with the rms rule alone
    };
    const std::vector<Expect> cases = {
        {"cosine r16", cosine(16.0), 2, 3},       {"cosine r32", cosine(32.0), 3, 6},
        {"gaussian sigma 8", gaussian(8.0), 4, 6}, {"gaussian sigma 16", gaussian(16.0), 8, 12},
        {"gaussian sigma 40", gaussian(40.0), 12, 24},
    };
    for (const Expect& c : cases) {
        const kernels::Kernel k(c.params);
        const render::LatticeRule rule = render::choose_lattice(k, 1.0, 0.005);
        const render::LatticeRule rms = render::choose_lattice(k, 1.0, 0.005, false);
        INFO(c.name << ": h " << rule.spacing << " (spectral " << rule.spectral_error << ", next "
                    << rule.next_spectral << ", next rms " << rule.next_error << "), rms alone h "
                    << rms.spacing);
        CHECK(rule.spacing == c.spacing);
        CHECK(rms.spacing == c.rms_spacing);
        CHECK(rule.spectral_error <= render::kSpectralFidelity);
        CHECK(rule.predicted_error <= 0.005);
        // The next spacing misses one of the two: the rule takes the coarsest that keeps both.
        CHECK((rule.next_spectral > render::kSpectralFidelity || rule.next_error > 0.005));
        // The spectral bound is what the rms rule's spacing breaks.
        CHECK(render::lattice_error(k, 1.0, rms.spacing, rms.margin).spectral > render::kSpectralFidelity);
    }
}

TEST_CASE("tolerance 0 is direct evaluation, bit for bit", "[render][lattice][determinism]") {
    const kernels::Kernel k(cosine(16.0));
    render::View view;
    view.width = 200, view.height = 120;
    double lambda = 0.0;
    const auto imp = poisson(k, view.box(), 16.0, false, 3, &lambda);
    const render::LatticeRule rule = render::choose_lattice(k, 1.0, 0.0);
    CHECK(rule.spacing == 1);
    render::Frame a, b;
    a.resize(view.width, view.height), b.resize(view.width, view.height);
    render::accumulate(k, imp, view, a);
    render::accumulate_lattice(k, imp, view, rule, b);
    CHECK(a.data == b.data);
}

TEST_CASE("the lattice path gives the same bits for any thread count and tile size",
          "[render][lattice][determinism]") {
    const kernels::Kernel k(gaussian(8.0));
    render::View view;
    view.width = 333, view.height = 177;  // not multiples of the spacing
    view.x0 = -17.25, view.y0 = 40.5, view.scale = 0.75;
    const render::LatticeRule rule = render::choose_lattice(k, view.scale, 0.005);
    REQUIRE(rule.spacing > 1);
    double lambda = 0.0;
    const auto imp = poisson(k, render::lattice_view(view, rule).box(), 10.0, false, 5, &lambda);
    auto run = [&](int threads, int tile) {
        render::Frame f;
        f.resize(view.width, view.height);
        render::EvalOptions o;
        o.tile_size = tile;
        tbb::task_arena arena(threads);
        arena.execute([&] { render::accumulate_lattice(k, imp, view, rule, f, o); });
        return f.data;
    };
    const auto one = run(1, 128);
    CHECK(run(2, 128) == one);
    CHECK(run(2, 16) == one);
    CHECK(run(1, 40) == one);
}

TEST_CASE("render.tolerance is checked", "[render][lattice]") {
    const kernels::Kernel k(cosine(16.0));
    for (double bad : {-0.001, 0.2, std::nan("")})
        CHECK_THROWS_WITH(render::choose_lattice(k, 1.0, bad), Catch::Contains("tolerance ="));
}
