// SPDX-License-Identifier: Apache-2.0
// Kernel gradients (kernels/gradient.cpp) against their closed forms for the analytic kernels,
// and against differences of the interpolants for sampled ones (docs/channels.md
// "Derivatives").

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <numbers>

#include "kernels/kernels.h"

namespace {

using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelType;
using impulse::kernels::SampledKernel;

constexpr double kPi = std::numbers::pi;
// Double rounding of a handful of operations on values of order 1 / length: 1e-12 of the
// gradient's scale leaves a factor 1000 over the ~1e-15 they accumulate.
constexpr double kRounding = 1e-12;

/// Points spread over the support (and a few outside), in units of the radius.
template <class F>
void for_points(double R, F f) {
    for (int j = -6; j <= 6; ++j)
        for (int i = -6; i <= 6; ++i) f(R * (i + 0.37) / 5.5, R * (j - 0.21) / 5.5);
}

}  // namespace

TEST_CASE("analytic kernel gradients equal their closed forms", "[kernels][gradient]") {
    const double R = 12.0;
    SECTION("cosine: grad h = -(pi / 2R) sin(pi r / R) x / r") {
        KernelParams p;
        p.type = KernelType::Cosine, p.radius = R;
        const Kernel k(p);
        for_points(R, [&](double x, double y) {
            const double r = std::hypot(x, y);
            const double g = r < R ? -(kPi / (2 * R)) * std::sin(kPi * r / R) / r : 0.0;
            const auto v = k.value_gradient(x, y);
            CHECK(std::abs(v[0] - k.evaluate(x, y)) <= kRounding);
            CHECK(std::abs(v[1] - g * x) <= kRounding / R);
            CHECK(std::abs(v[2] - g * y) <= kRounding / R);
        });
    }
    SECTION("elliptical Gaussian turned by theta: grad of exp(-(u^2 + a^2 v^2) / 2 sigma^2)") {
        KernelParams p;
        p.type = KernelType::Gaussian, p.radius = R, p.sigma = 4.0, p.aspect = 2.5;
        p.orientation = 0.4;
        const Kernel k(p);
        const double theta = 0.9, o = p.orientation + theta, c = std::cos(o), s = std::sin(o);
        for_points(R, [&](double x, double y) {
            const double u = c * x + s * y, v = -s * x + c * y, a2 = p.aspect * p.aspect;
            const bool inside = u * u + a2 * v * v < R * R;
            const double h = inside ? std::exp(-(u * u + a2 * v * v) / (2 * p.sigma * p.sigma)) : 0.0;
            const double hu = -u / (p.sigma * p.sigma) * h, hv = -a2 * v / (p.sigma * p.sigma) * h;
            const auto g = k.value_gradient(x, y, theta);
            CHECK(std::abs(g[1] - (hu * c - hv * s)) <= kRounding / p.sigma);
            CHECK(std::abs(g[2] - (hu * s + hv * c)) <= kRounding / p.sigma);
        });
    }
    SECTION("Gabor: the product rule on exp(-pi a^2 r^2) cos(2 pi f u + phi)") {
        KernelParams p;
        p.type = KernelType::Gabor, p.radius = R, p.frequency = 0.15, p.phase = 0.3;
        const Kernel k(p);
        const double a = k.gabor_a(), f = p.frequency;
        for_points(R, [&](double x, double y) {
            const double r2 = x * x + y * y;
            const double e = r2 < R * R ? std::exp(-kPi * a * a * r2) : 0.0;
            const double ph = 2 * kPi * f * x + p.phase;
            const double gx = -2 * kPi * a * a * x * e * std::cos(ph) - e * 2 * kPi * f * std::sin(ph);
            const double gy = -2 * kPi * a * a * y * e * std::cos(ph);
            const auto g = k.value_gradient(x, y);
            CHECK(std::abs(g[1] - gx) <= kRounding);
            CHECK(std::abs(g[2] - gy) <= kRounding);
        });
    }
}

TEST_CASE("sampled kernel gradients are those of their interpolants", "[kernels][gradient]") {
    const double R = 10.0;
    const int n = 33;
    auto table = std::make_shared<SampledKernel>();
    table->radial = true, table->n = n;
    for (int i = 0; i < n; ++i) table->values.push_back(std::pow(std::cos(0.5 * kPi * i / (n - 1)), 3));
    KernelParams p;
    p.type = KernelType::Sampled, p.radius = R, p.sampled = table;
    const Kernel k(p);
    // Along +x the gradient is de/dr. The Catmull–Rom cubic has e''' = 3 C ((n - 1) / R)^3 with
    // |C| = |3 (p1 - p2) + p3 - p0| <= 8 max|p| = 8: a central difference of step d errs by at
    // most d^2 / 6 * 24 ((n - 1) / R)^3, plus 2 * 1e-16 / (2 d) of rounding.
    const double d = 1e-4 * R / (n - 1), bound = d * d / 6 * 24 * std::pow((n - 1) / R, 3) + 1e-16 / d;
    for (int i = 1; i < 60; ++i) {
        const double r = R * (i + 0.31) / 61.0;
        const double central = (k.evaluate(r + d, 0) - k.evaluate(r - d, 0)) / (2 * d);
        const auto g = k.value_gradient(r, 0);
        CHECK(std::abs(g[1] - central) <= bound);
        CHECK(std::abs(g[2]) <= kRounding);
        // A radial kernel's gradient is radial with the same length at any angle.
        const double t = 0.3 + i;
        const auto h = k.value_gradient(r * std::cos(t), r * std::sin(t));
        CHECK(std::abs(h[1] - g[1] * std::cos(t)) <= kRounding + 1e-9 * std::abs(g[1]));
        CHECK(std::abs(h[2] - g[1] * std::sin(t)) <= kRounding + 1e-9 * std::abs(g[1]));
    }
    SECTION("a grid kernel: bilinear, so a difference inside one cell is exact") {
        auto grid = std::make_shared<SampledKernel>();
        grid->radial = false, grid->n = 17;
        for (int j = 0; j < 17; ++j)
            for (int i = 0; i < 17; ++i) grid->values.push_back(std::sin(0.7 * i) * std::cos(0.4 * j + 0.2 * i));
        KernelParams q;
        q.type = KernelType::Sampled, q.radius = R, q.sampled = grid, q.aspect = 1.5;
        const Kernel g(q);
        const double cell = 2 * R / 16;
        for (int j = 3; j < 13; ++j)
            for (int i = 3; i < 13; ++i) {
                // The middle of cell (i, j) in u; v chosen so a v is the middle of row j.
                const double u = -R + (i + 0.5) * cell, v = (-R + (j + 0.5) * cell) / q.aspect;
                if (u * u + q.aspect * q.aspect * v * v >= 0.8 * R * R) continue;
                const double e = 0.1 * cell;
                const auto gg = g.value_gradient(u, v);
                CHECK(std::abs(gg[1] - (g.evaluate(u + e, v) - g.evaluate(u - e, v)) / (2 * e)) <= 1e-9);
                CHECK(std::abs(gg[2] - (g.evaluate(u, v + e / q.aspect) - g.evaluate(u, v - e / q.aspect)) /
                                           (2 * e / q.aspect)) <= 1e-9);
            }
    }
}
