// SPDX-License-Identifier: Apache-2.0
// Kernel properties against closed forms and independent quadrature: integrals (the inputs of
// Campbell's theorem), power spectra, autocorrelation, the float envelope the renderer uses
// (polynomial or table), grid kernels' support, and parameter validation.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "kernels/kernels.h"
#include "numeric/errors.h"

namespace {

using Catch::Matchers::Contains;
using impulse::ValueError;
using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelType;

constexpr double kPi = std::numbers::pi;

double rel_diff(double a, double b) { return std::abs(a - b) / std::abs(b); }

KernelParams cosine(double radius) {
    KernelParams p;
    p.type = KernelType::Cosine;
    p.radius = radius;
    return p;
}

KernelParams gaussian(double radius, double sigma) {
    KernelParams p;
    p.type = KernelType::Gaussian;
    p.radius = radius;
    p.sigma = sigma;
    return p;
}

KernelParams gabor(double radius, double frequency, double phase = 0.0) {
    KernelParams p;
    p.type = KernelType::Gabor;
    p.radius = radius;
    p.frequency = frequency;
    p.phase = phase;
    return p;
}

/// int h^p over the plane by brute force from Kernel::evaluate, in polar coordinates about the
/// kernel centre: composite Simpson in r on [0, rmax] (n_r intervals, even) and the periodic
/// trapezoid rule in angle (spectrally accurate for a smooth periodic integrand). Independent of
/// the library's Gauss–Legendre/Hankel machinery. Exact up to O(dr^4) where h^p is smooth in r
/// along each ray, i.e. for an isotropic kernel whose only jump is at r = R = rmax.
double polar_integral(const Kernel& k, int power, double rmax, int n_r, int n_angle) {
    const double dr = rmax / n_r;
    double sum = 0.0;
    for (int i = 0; i <= n_r; ++i) {
        const double r = i * dr;
        const double w = (i == 0 || i == n_r) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        // Stay a hair inside the support at r = R so the endpoint sees the limit from inside.
        const double rr = i == n_r ? r * (1.0 - 1e-13) : r;
        double ring = 0.0;
        for (int j = 0; j < n_angle; ++j) {
            const double a = 2.0 * kPi * j / n_angle;
            ring += std::pow(k.evaluate(rr * std::cos(a), rr * std::sin(a)), power);
        }
        sum += w * r * ring * (2.0 * kPi / n_angle);
    }
    return sum * dr / 3.0;
}

}  // namespace

TEST_CASE("cosine kernel integrals match their closed forms", "[kernels]") {
    // h(r) = 1/2 + 1/2 cos(pi r / R) = cos^2(pi s / 2), s = r / R. With 2 theta = pi s and
    // int_0^1 s cos(m pi s) ds = ((-1)^m - 1) / (m pi)^2 (= -2/pi^2 for m = 1, 0 for m = 2):
    //   int h   = 2 pi R^2 int_0^1 s (1/2 + 1/2 cos pi s) ds = 2 pi R^2 (1/4 - 1/pi^2)
    //           = pi R^2 (1/2 - 2/pi^2)
    //   h^2 = cos^4 theta = (3 + 4 cos 2theta + cos 4theta) / 8
    //   int h^2 = 2 pi R^2 (3/16 - 1/pi^2) = pi R^2 (3/8 - 2/pi^2)
    //   h^4 = cos^8 theta = (35 + 56 cos 2th + 28 cos 4th + 8 cos 6th + cos 8th) / 128
    //   int h^4 = 2 pi R^2 (35/2 - 112/pi^2 - 16/(9 pi^2)) / 128
    const double pi2 = kPi * kPi;
    for (double R : {16.0, 3.7, 250.0}) {
        CAPTURE(R);
        const Kernel k(cosine(R));
        CHECK(rel_diff(k.integral(), kPi * R * R * (0.5 - 2.0 / pi2)) < 1e-9);
        CHECK(rel_diff(k.integral_sq(), kPi * R * R * (0.375 - 2.0 / pi2)) < 1e-9);
        CHECK(rel_diff(k.integral_4(),
                       2.0 * kPi * R * R * (17.5 - 112.0 / pi2 - 16.0 / (9.0 * pi2)) / 128.0) < 1e-9);
        CHECK(rel_diff(k.support_area(), kPi * R * R) < 1e-15);
    }
}

TEST_CASE("truncated Gaussian kernel integrals match their closed forms", "[kernels]") {
    // h = exp(-r^2 / (2 s^2)) on r < R:
    //   int h   = 2 pi int_0^R e^{-r^2/2s^2} r dr = 2 pi s^2 (1 - e^{-R^2/(2 s^2)})
    //   int h^2 : the same with s -> s/sqrt(2):  pi s^2 (1 - e^{-R^2/s^2})
    //   int h^4 : s -> s/2:                      (pi s^2 / 2) (1 - e^{-2 R^2/s^2})
    struct Case {
        double R, s;
    };
    for (const Case c : {Case{20.0, 7.0}, Case{56.0, 20.0}, Case{5.0, 5.0}}) {
        CAPTURE(c.R, c.s);
        const Kernel k(gaussian(c.R, c.s));
        const double s2 = c.s * c.s, R2 = c.R * c.R;
        CHECK(rel_diff(k.integral(), 2.0 * kPi * s2 * (1.0 - std::exp(-R2 / (2.0 * s2)))) < 1e-9);
        CHECK(rel_diff(k.integral_sq(), kPi * s2 * (1.0 - std::exp(-R2 / s2))) < 1e-9);
        CHECK(rel_diff(k.integral_4(), 0.5 * kPi * s2 * (1.0 - std::exp(-2.0 * R2 / s2))) < 1e-9);
    }
}

TEST_CASE("Gabor kernel integrals match brute-force quadrature of evaluate()", "[kernels]") {
    // The library derives them from Hankel transforms of the envelope at the carrier harmonics;
    // here they come from sampling h itself. Simpson in r with 800 intervals: error
    // ~ R^5 max|d^4 h/dr^4| dr^4 / 180, about 1e-10 relative for f R <= 2; the trapezoid rule in
    // angle with 720 points is exact to rounding for these band-limited rays.
    struct Case {
        double R, f, phase;
    };
    for (const Case c : {Case{16.0, 0.0625, 0.0}, Case{16.0, 0.125, 0.0}, Case{10.0, 0.05, 1.1}}) {
        CAPTURE(c.R, c.f, c.phase);
        const Kernel k(gabor(c.R, c.f, c.phase));
        REQUIRE(k.gabor_a() == Approx(1.2107 / c.R).epsilon(1e-4));
        CHECK(rel_diff(k.integral_sq(), polar_integral(k, 2, c.R, 800, 720)) < 1e-8);
        CHECK(rel_diff(k.integral_4(), polar_integral(k, 4, c.R, 800, 720)) < 1e-8);
        // int h = cos(phase) E(f) nearly cancels for f R ~ 1: compare absolutely, on the scale
        // of int |h| <= support area.
        CHECK(std::abs(k.integral() - polar_integral(k, 1, c.R, 800, 720)) <
              1e-9 * k.support_area());
    }
}

TEST_CASE("an elliptical kernel's integrals scale by 1/aspect", "[kernels]") {
    // Squeezing v by `aspect` divides every integral of a power of h by it. Checked both
    // against the isotropic kernel's statistics and by a brute-force Cartesian midpoint sum
    // over the rotated ellipse (cosine: h and h' vanish at the boundary, so the midpoint rule
    // keeps its O(d^2) accuracy; d = 0.02 R gives ~1e-5).
    for (double aspect : {1.0, 1.6, 2.5, 4.0}) {
        CAPTURE(aspect);
        KernelParams p = cosine(8.0);
        p.aspect = aspect;
        p.orientation = 0.7;
        const Kernel k(p), iso(cosine(8.0));
        CHECK(rel_diff(k.integral(), iso.integral() / aspect) < 1e-12);
        CHECK(rel_diff(k.integral_sq(), iso.integral_sq() / aspect) < 1e-12);
        CHECK(rel_diff(k.integral_4(), iso.integral_4() / aspect) < 1e-12);
        CHECK(rel_diff(k.support_area(), iso.support_area() / aspect) < 1e-12);

        const double d = 0.02 * 8.0;
        double s1 = 0.0, s2 = 0.0;
        for (double y = -8.0 + 0.5 * d; y < 8.0; y += d)
            for (double x = -8.0 + 0.5 * d; x < 8.0; x += d) {
                const double h = k.evaluate(x, y);
                s1 += h, s2 += h * h;
            }
        CHECK(rel_diff(s1 * d * d, k.integral()) < 1e-4);
        CHECK(rel_diff(s2 * d * d, k.integral_sq()) < 1e-4);
    }
    KernelParams g = gabor(16.0, 0.0625);
    g.aspect = 2.0;
    const Kernel ga(g), gi(gabor(16.0, 0.0625));
    CHECK(rel_diff(ga.integral_sq(), gi.integral_sq() / 2.0) < 1e-12);
}

TEST_CASE("power spectrum at k = 0 is (int h)^2", "[kernels]") {
    // H(0) = int h, so |H(0)|^2 = integral()^2 for every kernel family and shape.
    KernelParams ell = cosine(12.0);
    ell.aspect = 3.0;
    ell.orientation = 0.4;
    KernelParams gab = gabor(16.0, 0.03, 0.5);
    gab.aspect = 1.5;
    gab.orientation = -0.3;
    for (const KernelParams& p : {cosine(16.0), gaussian(20.0, 7.0), ell, gab,
                                  gabor(16.0, 0.0625)}) {
        const Kernel k(p);
        CAPTURE(std::string(impulse::kernels::to_string(p.type)), p.aspect);
        const double i2 = k.integral() * k.integral();
        CHECK(std::abs(k.power_spectrum(0.0, 0.0) - i2) <= 1e-9 * k.integral_sq() * k.support_area());
    }
}

TEST_CASE("power spectrum of a wide-support Gaussian is the Gaussian transform", "[kernels]") {
    // For R = 10 s the truncation changes H by at most 2 pi s^2 e^{-50} ~ 1e-20 relative, so
    // |H(k)|^2 = (2 pi s^2)^2 exp(-4 pi^2 s^2 k^2) up to the Hankel quadrature's error.
    // Compared where the spectrum is above 1e-8 of its peak (k s < 0.68), relative 1e-7.
    const double s = 4.0;
    const Kernel k(gaussian(10.0 * s, s));
    const double peak = std::pow(2.0 * kPi * s * s, 2);
    for (int i = 0; i < 68; ++i) {
        const double kk = 0.01 * i / s;
        const double expected = peak * std::exp(-4.0 * kPi * kPi * s * s * kk * kk);
        CAPTURE(kk);
        CHECK(rel_diff(k.power_spectrum(kk, 0.0), expected) < 1e-7);
        CHECK(rel_diff(k.power_spectrum(0.6 * kk, -0.8 * kk), expected) < 1e-7);  // isotropic
        CHECK(rel_diff(k.radial_power_spectrum(kk), expected) < 1e-7);
    }
}

TEST_CASE("Parseval: the integral of the power spectrum is int h^2", "[kernels]") {
    // A coarse check (1e-3) that power_spectrum is normalised like integral_sq: any factor
    // error (2 pi, aspect, the carrier's 1/4) would show as O(1).
    SECTION("isotropic cosine, radial integral") {
        // int |H|^2 d^2k = 2 pi int_0^K P(k) k dk, midpoint rule with 500 steps. The cosine bump
        // is C^1 with a jump in h'' at R, so |H|^2 ~ k^-7: beyond K R = 4 the tail is < 1e-5.
        const double R = 8.0;
        const Kernel k(cosine(R));
        const double K = 0.5, dk = K / 500.0;
        double sum = 0.0;
        for (int i = 0; i < 500; ++i) {
            const double kk = (i + 0.5) * dk;
            sum += k.power_spectrum(kk, 0.0) * kk;
        }
        CHECK(rel_diff(2.0 * kPi * sum * dk, k.integral_sq()) < 1e-3);
    }
    SECTION("Gabor with aspect 2, 2-D midpoint sum") {
        // Envelope exp(-pi a^2 r^2), a = 0.076, truncated at 1 %: two Gaussian lobes of |H|^2 at
        // +-f with sd a / sqrt(4 pi) = 0.021 along u and twice that across; [-0.3, 0.3]^2 holds
        // them to > 7 sd, and the truncation ripple (a 1e-4 jump in h^2) puts ~1e-4 outside.
        KernelParams p = gabor(16.0, 0.0625);
        p.aspect = 2.0;
        p.orientation = 0.5;
        const Kernel k(p);
        const int n = 30;
        const double K = 0.3, d = 2.0 * K / n;
        double sum = 0.0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                sum += k.power_spectrum(-K + (i + 0.5) * d, -K + (j + 0.5) * d);
        CHECK(rel_diff(sum * d * d, k.integral_sq()) < 1e-3);
    }
}

TEST_CASE("autocorrelation at lag 0 is int h^2", "[kernels]") {
    // Documented accuracy: far below 1e-4 for the cosine kernel, ~1e-4 for kernels with a jump.
    CHECK(rel_diff(Kernel(cosine(16.0)).autocorrelation(0.0, 0.0), Kernel(cosine(16.0)).integral_sq()) <
          1e-6);
    KernelParams ell = cosine(12.0);
    ell.aspect = 2.5;
    ell.orientation = 1.0;
    CHECK(rel_diff(Kernel(ell).autocorrelation(0.0, 0.0), Kernel(ell).integral_sq()) < 1e-6);
    for (const KernelParams& p : {gaussian(20.0, 7.0), gabor(16.0, 0.0625)}) {
        const Kernel k(p);
        CHECK(rel_diff(k.autocorrelation(0.0, 0.0), k.integral_sq()) < 3e-4);
    }
    // Symmetric in the lag, zero beyond the sum of the supports.
    const Kernel c(cosine(6.0));
    CHECK(c.autocorrelation(3.0, 1.0) == Approx(c.autocorrelation(-3.0, -1.0)).epsilon(1e-6));
    CHECK(c.autocorrelation(12.5, 0.0) == 0.0);
}

namespace {

/// The envelope as the renderer evaluates it in float: the Chebyshev polynomial, or, when the
/// kernel carries a table, linear interpolation in q over it (render/eval_loops.inc
/// TableEnvelope).
double renderer_envelope(const Kernel& k, double q) {
    const auto& t = k.envelope_table();
    if (t.empty()) return k.polynomial().evaluate(static_cast<float>(q));
    const float x = std::min(static_cast<float>(q), 1.0f) * static_cast<float>(t.size() - 1);
    const int i = std::min(static_cast<int>(x), static_cast<int>(t.size()) - 2);
    const float f = x - static_cast<float>(i);
    return t[i] + f * (t[i + 1] - t[i]);
}

double worst_envelope_error(const Kernel& k) {
    double worst = 0.0;
    for (int i = 0; i < 10000; ++i) {
        const double q = i / 10000.0;
        worst = std::max(worst, std::abs(renderer_envelope(k, q) - k.envelope(q)));
    }
    return worst;
}

}  // namespace

TEST_CASE("the renderer's envelope matches the exact envelope to 1e-6", "[kernels]") {
    // kernels.h: the polynomial's degree is chosen so its error is below 1e-6 of e(0); when it
    // cannot be, a table is used instead. Either way the float envelope must be within 1e-6.
    KernelParams gb = gabor(16.0, 0.0625);
    gb.bandwidth = 0.02;
    for (const KernelParams& p : {cosine(16.0), cosine(1.0), gaussian(20.0, 7.0), gaussian(56.0, 20.0),
                                  gaussian(16.0, 5.0), gaussian(20.0, 5.0), gabor(16.0, 0.0625), gb}) {
        const Kernel k(p);
        CAPTURE(std::string(impulse::kernels::to_string(p.type)), p.radius, p.sigma,
                k.envelope_table().size());
        const auto& poly = k.polynomial();
        CHECK(poly.coefficients.size() % 2 == 1);
        if (k.envelope_table().empty()) CHECK(poly.max_error < 1e-6 * k.envelope(0.0));
        CHECK(worst_envelope_error(k) < 1e-6);
    }
}

TEST_CASE("the renderer's envelope of a narrow Gaussian meets the 1e-6 bound", "[kernels]") {
    // A Gaussian truncated at R = 12 sigma (e(q) = exp(-72 q)) or 53 sigma (sigma = 0.3 px at
    // R = 16) defeats the degree-40 polynomial, so the kernel falls back to its 4097-entry
    // table, linear in q: error ~ h^2 / 8 * e'' = (1/4096)^2 / 8 * 72^2 = 3.9e-5 at 12 sigma and
    // ~1.5e-2 at 53 sigma (e'' = 1422^2). Isotropic Gaussians take the separable exp path in the
    // renderer, but elliptical ones (aspect != 1) use this envelope.
    for (double ratio : {12.0, 16.0 / 0.3}) {
        KernelParams p = gaussian(16.0, 16.0 / ratio);
        p.aspect = 1.5;
        const Kernel k(p);
        CAPTURE(ratio, k.polynomial().max_error, k.envelope_table().size());
        CHECK(worst_envelope_error(k) < 1e-6);
    }
    // A sigma so small that sigma^2 underflows would give e(0) = exp(-0 * inf) = NaN: it must
    // be refused (radius / sigma is bounded), not turned into a kernel of NaNs.
    CHECK_THROWS_WITH(Kernel(gaussian(16.0, 1e-200)), Catch::Contains("sigma") && Catch::Contains("radius / sigma"));
    // The exponent uses (R / sigma)^2, so the largest accepted ratio still evaluates finitely.
    const Kernel narrow(gaussian(16.0, 16.0 / 1000.0));
    CHECK(std::isfinite(narrow.envelope(0.0)));
    CHECK(narrow.envelope(0.0) == 1.0);
}

TEST_CASE("a grid kernel is zero beyond its radius", "[kernels]") {
    // kernels.h, SampledKernel: "both zero beyond the radius R". A grid of ones over [-R, R]^2 is
    // then the disk indicator: h = 0 at (0.8 R, 0.8 R) (outside the disk, inside the square) and
    // int h = int h^2 = pi R^2 up to the bilinear ramp of one grid cell at the rim
    // (|error| <= perimeter * spacing = 2 pi R * 2R/(n-1), 5 % for n = 129).
    auto sk = std::make_shared<impulse::kernels::SampledKernel>();
    sk->radial = false;
    sk->n = 129;
    sk->values.assign(size_t(sk->n) * sk->n, 1.0);
    KernelParams p;
    p.type = KernelType::Sampled;
    p.radius = 10.0;
    p.sampled = sk;
    const Kernel k(p);
    CHECK(k.evaluate(0.0, 0.0) == Approx(1.0));
    CHECK(k.evaluate(8.0, 8.0) == 0.0);
    CHECK(k.integral() == Approx(kPi * 100.0).epsilon(0.05));
    CHECK(k.integral_sq() == Approx(kPi * 100.0).epsilon(0.05));
}

TEST_CASE("validate rejects invalid parameters naming the key", "[kernels][errors]") {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    KernelParams p;
    p.radius = 0.0;
    CHECK_THROWS_MATCHES(Kernel(p), ValueError, Catch::Matchers::Message(
                                                    "radius = 0: must be a finite number > 0"));
    p.radius = -3.0;
    CHECK_THROWS_WITH(impulse::kernels::validate(p), Contains("radius = -3"));
    p.radius = nan;
    CHECK_THROWS_AS(Kernel(p), ValueError);
    CHECK_THROWS_WITH(Kernel(p), Contains("radius = ") && Contains("nan"));
    p.radius = inf;
    CHECK_THROWS_WITH(Kernel(p), Contains("radius = inf"));
    p = KernelParams{};
    p.aspect = 0.5;
    CHECK_THROWS_AS(Kernel(p), ValueError);
    CHECK_THROWS_WITH(Kernel(p), Contains("aspect = 0.5") && Contains(">= 1"));
    p.aspect = nan;
    CHECK_THROWS_WITH(Kernel(p), Contains("aspect"));
    p = KernelParams{};
    p.orientation = nan;
    CHECK_THROWS_WITH(Kernel(p), Contains("orientation"));
    p = gaussian(10.0, 0.0);
    CHECK_THROWS_WITH(Kernel(p), Contains("sigma = 0"));
    p = gaussian(10.0, nan);
    CHECK_THROWS_WITH(Kernel(p), Contains("sigma"));
    p = gabor(16.0, -0.1);
    CHECK_THROWS_WITH(Kernel(p), Contains("frequency = -0.1"));
    p = gabor(16.0, 0.1);
    p.bandwidth = -1.0;
    CHECK_THROWS_WITH(Kernel(p), Contains("bandwidth = -1"));
    p = gabor(16.0, 0.1, nan);
    CHECK_THROWS_WITH(Kernel(p), Contains("phase"));
    // Valid extremes pass.
    CHECK_NOTHROW(Kernel(gabor(16.0, 0.0)));
    KernelParams ok = cosine(1e-3);
    ok.aspect = 1.0;
    CHECK_NOTHROW(Kernel(ok));
}
