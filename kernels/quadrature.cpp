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

}  // namespace impulse::kernels::detail
