// SPDX-License-Identifier: Apache-2.0
// level_drift: the trend and block tests of a correlated series against its stationary
// covariance are calibrated (z ~ N(0, 1), chi^2 ~ chi^2_{B-1}) where the independent-frames
// model is not, and they see a drift and a swing.

#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "analysis/analysis.h"

using namespace impulse::analysis;

namespace {

/// AR(1) series x_i = phi x_{i-1} + e_i, started stationary, unit marginal variance.
std::vector<double> ar1(std::mt19937_64& rng, size_t n, double phi) {
    std::normal_distribution<double> g;
    std::vector<double> x(n);
    x[0] = g(rng);
    for (size_t i = 1; i < n; ++i) x[i] = phi * x[i - 1] + std::sqrt(1 - phi * phi) * g(rng);
    return x;
}

std::vector<double> ar1_rho(size_t n, double phi) {
    std::vector<double> r(n);
    for (size_t l = 0; l < n; ++l) r[l] = std::pow(phi, double(l));
    return r;
}

}  // namespace

TEST_CASE("level_drift is calibrated on correlated stationary series", "[analysis][stats]") {
    std::mt19937_64 rng(18);
    const size_t n = 300, runs = 2000;
    const double phi = 0.9;  // integrated time 19 frames
    const auto rho = ar1_rho(n, phi);
    const std::vector<double> white = {1.0};
    double sz = 0, sz2 = 0, chi = 0;
    int reject = 0, reject_white = 0;
    for (size_t k = 0; k < runs; ++k) {
        const auto x = ar1(rng, n, phi);
        const LevelDrift L = level_drift(x, 1.0, rho, 10, INFINITY, 0.01, 0.8);
        sz += L.z_trend, sz2 += L.z_trend * L.z_trend, chi += L.chi2;
        reject += std::abs(L.z_trend) > 1.96;
        reject_white += std::abs(level_drift(x, 1.0, white, 10, INFINITY, 0.01, 0.8).z_trend) > 1.96;
    }
    // Var z = 1: the sample variance of 2000 normals has sd sqrt(2 / 2000) = 0.032; 4 sd.
    CHECK(sz2 / runs - (sz / runs) * (sz / runs) == Approx(1.0).margin(0.13));
    // E chi^2 = 9 with Var = 18: the mean of 2000 has sd 0.095; 4 sd.
    CHECK(chi / runs == Approx(9.0).margin(0.38));
    // 5 % two-sided: 100 of 2000 expected, sd 9.7.
    CHECK(std::abs(reject - 100) < 40);
    // Taking the frames as independent rejects most of the time.
    CHECK(reject_white > 1000);
}

TEST_CASE("level_drift sees a linear drift and a swing that comes and goes", "[analysis][stats]") {
    std::mt19937_64 rng(5);
    const size_t n = 300;
    const auto rho = ar1_rho(n, 0.9);
    auto x = ar1(rng, n, 0.9);
    auto y = x;
    for (size_t i = 0; i < n; ++i) {
        x[i] += 10.0 + 2.0 * double(i) / double(n);      // +20 % over the series
        y[i] += 10.0 + 1.5 * std::cos(6.283185307 * double(i) / 100.0);  // three periods
    }
    const LevelDrift a = level_drift(x, 1.0, rho, 10, INFINITY, 0.01, 0.8);
    const LevelDrift b = level_drift(y, 1.0, rho, 10, INFINITY, 0.01, 0.8);
    CHECK(a.z_trend > 3.0);
    CHECK(std::abs(b.z_trend) < 3.0);  // a swing with no net trend is the blocks' to see
    CHECK(b.z_blocks > 3.0);
    // Detectable change: (z_0.005 + z_0.8) sd_slope (n - 1).
    CHECK(a.detectable_change == Approx((2.5758 + 0.8416) * a.sd_slope * 299).epsilon(1e-3));
}
