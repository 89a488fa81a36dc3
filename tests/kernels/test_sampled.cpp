// SPDX-License-Identifier: Apache-2.0
// Sampled kernels (radial profiles and 2-D grids) against the analytic kernel they sample,
// through the exact statistics and through the renderer.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "kernels/kernels.h"
#include "render/render.h"

using namespace impulse;

namespace {

kernels::KernelParams cosine(double R) {
    kernels::KernelParams p;
    p.type = kernels::KernelType::Cosine;
    p.radius = R;
    return p;
}

kernels::KernelParams sampled_radial(const kernels::Kernel& k, int n) {
    auto s = std::make_shared<kernels::SampledKernel>();
    s->radial = true;
    s->n = n;
    for (int i = 0; i < n; ++i) s->values.push_back(k.evaluate(k.radius() * i / (n - 1), 0.0));
    kernels::KernelParams p;
    p.type = kernels::KernelType::Sampled;
    p.radius = k.radius();
    p.sampled = s;
    return p;
}

kernels::KernelParams sampled_grid(const kernels::Kernel& k, int n) {
    auto s = std::make_shared<kernels::SampledKernel>();
    s->radial = false;
    s->n = n;
    const double R = k.radius();
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            s->values.push_back(k.evaluate(-R + 2 * R * i / (n - 1), -R + 2 * R * j / (n - 1)));
    kernels::KernelParams p;
    p.type = kernels::KernelType::Sampled;
    p.radius = R;
    p.sampled = s;
    return p;
}

}  // namespace

TEST_CASE("a radial sampled kernel reproduces the analytic kernel's statistics", "[kernels]") {
    const kernels::Kernel ref(cosine(16.0));
    const kernels::Kernel k(sampled_radial(ref, 257));
    // Catmull-Rom on 257 samples of a smooth profile: O(h^3) interpolation error, h = R/256.
    CHECK(k.integral() == Approx(ref.integral()).epsilon(1e-6));
    CHECK(k.integral_sq() == Approx(ref.integral_sq()).epsilon(1e-6));
    for (double kk : {0.0, 0.01, 0.03, 0.06})
        CHECK(k.power_spectrum(kk, 0.0) == Approx(ref.power_spectrum(kk, 0.0)).epsilon(1e-4).margin(1e-9));
    for (double r : {0.0, 3.3, 9.1, 15.2})
        CHECK(k.evaluate(r, 0.0) == Approx(ref.evaluate(r, 0.0)).margin(1e-6));
}

TEST_CASE("a grid sampled kernel reproduces the analytic kernel's statistics", "[kernels]") {
    const kernels::Kernel ref(cosine(16.0));
    const kernels::Kernel k(sampled_grid(ref, 129));
    // Bilinear interpolation: error ~ h^2/8 |h''| with h = 32/128 and |h''| <= pi^2/(2 R^2):
    // about 1.5e-4 of the peak; integrals average it further.
    CHECK(k.integral() == Approx(ref.integral()).epsilon(2e-3));
    CHECK(k.integral_sq() == Approx(ref.integral_sq()).epsilon(2e-3));
    CHECK(k.power_spectrum(0.02, 0.01) == Approx(ref.power_spectrum(0.02, 0.01)).epsilon(5e-3));
    CHECK(k.evaluate(5.0, -3.0) == Approx(ref.evaluate(5.0, -3.0)).margin(2e-4));
    CHECK(k.evaluate(20.0, 0.0) == 0.0);
}

TEST_CASE("the renderer evaluates sampled kernels like the analytic one", "[kernels][render]") {
    const kernels::Kernel ref(cosine(12.0));
    sim::Impulses imp;
    for (int i = 0; i < 40; ++i) {
        imp.x.push_back(3.0 + 1.7 * i);
        imp.y.push_back(5.0 + 1.3 * i + 0.37 * (i % 7));
        imp.weight.push_back(i % 3 == 0 ? -1.0f : 0.5f + 0.01f * i);
        imp.theta.push_back(0.3f * i);
    }
    render::View view;
    view.width = 80, view.height = 70;
    render::Frame want, got_r, got_g;
    render::accumulate(ref, imp, view, want);
    // A wiggly radial profile the polynomial cannot follow takes the table path; here check
    // both sampled forms against the analytic kernel.
    render::accumulate(kernels::Kernel(sampled_radial(ref, 513)), imp, view, got_r);
    render::accumulate(kernels::Kernel(sampled_grid(ref, 193)), imp, view, got_g);
    double er = 0, eg = 0;
    for (size_t i = 0; i < want.data.size(); ++i) {
        er = std::max(er, double(std::abs(want.data[i] - got_r.data[i])));
        eg = std::max(eg, double(std::abs(want.data[i] - got_g.data[i])));
    }
    // Sums of ~5 overlapping kernels: a few times the per-kernel interpolation error.
    CHECK(er < 1e-4);
    CHECK(eg < 2e-3);
}

TEST_CASE("an oscillating sampled profile is tabulated, not fitted", "[kernels]") {
    auto s = std::make_shared<kernels::SampledKernel>();
    s->n = 400;
    for (int i = 0; i < s->n; ++i) {
        const double r = double(i) / (s->n - 1);
        s->values.push_back(std::cos(60.0 * r) * (1.0 - r) * (1.0 - r));
    }
    kernels::KernelParams p;
    p.type = kernels::KernelType::Sampled;
    p.radius = 30.0;
    p.sampled = s;
    const kernels::Kernel k(p);
    REQUIRE(!k.envelope_table().empty());
    const size_t intervals = k.envelope_table().size() - 1;
    for (double f : {0.0, 0.1, 0.37, 0.8}) {
        const size_t i = static_cast<size_t>(f * intervals);
        CHECK(k.envelope_table()[i] == Approx(k.envelope(double(i) / intervals)).margin(1e-6));
    }
}
