// SPDX-License-Identifier: Apache-2.0
#include "kernels/quadrature.h"

#include <array>
#include <cmath>
#include <numbers>

namespace impulse::kernels::detail {
namespace {

struct Rule {
    std::array<double, kGlPoints> x{}, w{};
    Rule() {
        // Newton iteration on the Legendre polynomial P_n from the Chebyshev initial guess.
        const int n = kGlPoints;
        for (int i = 0; i < n; ++i) {
            double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
            double dp = 0.0;
            for (int it = 0; it < 100; ++it) {
                double p0 = 1.0, p1 = z;
                for (int k = 2; k <= n; ++k) {
                    double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n * (z * p1 - p0) / (z * z - 1.0);
                double dz = p1 / dp;
                z -= dz;
                if (std::abs(dz) < 1e-16) break;
            }
            x[i] = z;
            w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
        }
    }
};

const Rule& rule() {
    static const Rule r;
    return r;
}

}  // namespace

const double* gl_nodes() { return rule().x.data(); }
const double* gl_weights() { return rule().w.data(); }

double integrate(const std::function<double(double)>& f, double a, double b, int panels) {
    const Rule& r = rule();
    const double h = (b - a) / panels;
    double sum = 0.0;
    for (int p = 0; p < panels; ++p) {
        const double mid = a + (p + 0.5) * h;
        double s = 0.0;
        for (int i = 0; i < kGlPoints; ++i) s += r.w[i] * f(mid + 0.5 * h * r.x[i]);
        sum += 0.5 * h * s;
    }
    return sum;
}

namespace {

struct J0Tables {
    double inv_m2[80];  // 1 / m^2 for the power series
    double growth[64];  // (2j - 1)^2 / (8 j): ratio of successive asymptotic coefficients
    J0Tables() {
        for (int m = 1; m < 80; ++m) inv_m2[m] = 1.0 / (double(m) * m);
        for (int j = 1; j < 64; ++j) growth[j] = (2.0 * j - 1.0) * (2.0 * j - 1.0) / (8.0 * j);
    }
};
const J0Tables kJ0;

}  // namespace

double bessel_j0(double x) {
    x = std::abs(x);
    if (x <= 12.0) {
        // sum_m (-1)^m (x^2/4)^m / (m!)^2: the largest term is ~4e3 at x = 12, so rounding
        // costs ~4 digits (error < 1e-12).
        const double y = -0.25 * x * x;
        double term = 1.0, sum = 1.0;
        for (int m = 1; m < 80; ++m) {
            term *= y * kJ0.inv_m2[m];
            sum += term;
            if (std::abs(term) < 1e-16) break;
        }
        return sum;
    }
    // J0(x) = sqrt(2 / (pi x)) (P cos chi - Q sin chi), chi = x - pi/4, with
    // P = sum_m (-1)^m c_2m / x^2m, Q = -sum_m (-1)^m c_2m+1 / x^(2m+1),
    // c_j = prod_{i<=j} (2i - 1)^2 / (j! 8^j) (Abramowitz & Stegun 9.2.5, 9.2.9-10). The terms
    // shrink until j ~ 2x; stopping there leaves an error ~e^{-2x} < 1e-10 for x > 12.
    const double inv = 1.0 / x;
    double p = 1.0, q = 0.0, t = 1.0;
    for (int j = 1; j < 64; ++j) {
        const double nt = t * kJ0.growth[j] * inv;
        if (nt > t || nt < 1e-16) break;  // converged, or the asymptotic series turns
        t = nt;
        switch (j & 3) {  // signs: P gets +c0 -c2 +c4 ..., Q gets -c1 +c3 -c5 ...
            case 0: p += t; break;
            case 1: q -= t; break;
            case 2: p -= t; break;
            case 3: q += t; break;
        }
    }
    const double chi = x - 0.25 * std::numbers::pi;
    return std::sqrt(2.0 / (std::numbers::pi * x)) * (p * std::cos(chi) - q * std::sin(chi));
}

}  // namespace impulse::kernels::detail
