// SPDX-License-Identifier: Apache-2.0
// Does the level of a correlated series drift? A linear trend and a test of block means, both
// against the covariance the series has when it is stationary (analysis.h, LevelDrift).

#include <algorithm>
#include <cmath>

#include "analysis/analysis.h"
#include "numeric/errors.h"
#include "numeric/gaussian.h"

namespace impulse::analysis {
namespace {

double rho_at(std::span<const double> rho, size_t l) { return l < rho.size() ? rho[l] : 0.0; }

/// sum_{i in [0, m)} sum_{j in [0, m)} rho(|d + j - i|): the covariance (in units of the
/// series' variance, times m^2) of two means of m consecutive values d apart.
double block_pair(std::span<const double> rho, long d, long m) {
    double s = 0.0;
    for (long k = -(m - 1); k <= m - 1; ++k)
        s += double(m - std::abs(k)) * rho_at(rho, size_t(std::abs(d + k)));
    return s;
}

/// Solves A x = b for a symmetric positive definite A (n x n, row-major) by Cholesky; returns
/// b^T A^-1 b, or NaN when A is not positive definite.
double quadratic_form_inverse(std::vector<double> A, const std::vector<double>& b) {
    const size_t n = b.size();
    for (size_t j = 0; j < n; ++j) {
        double d = A[j * n + j];
        for (size_t k = 0; k < j; ++k) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 0.0)) return NAN;
        A[j * n + j] = std::sqrt(d);
        for (size_t i = j + 1; i < n; ++i) {
            double s = A[i * n + j];
            for (size_t k = 0; k < j; ++k) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s / A[j * n + j];
        }
    }
    // L y = b: then b^T A^-1 b = |y|^2.
    std::vector<double> y(n);
    double q = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double s = b[i];
        for (size_t k = 0; k < i; ++k) s -= A[i * n + k] * y[k];
        y[i] = s / A[i * n + i];
        q += y[i] * y[i];
    }
    return q;
}

}  // namespace

double student_to_normal(double t, double dof) {
    if (!std::isfinite(dof)) return t;
    // Wallace's (1959) normalising transformation of Student's t: accurate to a few 1e-3 in z
    // out to the 1e-4 tails for dof >= 3.
    const double z = std::sqrt(dof * std::log1p(t * t / dof)) * (1.0 - 1.0 / (2.0 * dof)) /
                     std::sqrt(1.0 + 1.0 / (2.0 * dof));
    return std::copysign(z, t);
}

double variance_ratio_to_normal(double F, double d1, double d2) {
    // Paulson's (1942) Wilson–Hilferty approximation for F(d1, d2); d2 infinite: chi^2_d1 / d1.
    const double a = 2.0 / (9.0 * d1);
    const double b = std::isfinite(d2) ? 2.0 / (9.0 * d2) : 0.0;
    const double c = std::cbrt(std::max(F, 0.0));
    return ((1.0 - b) * c - (1.0 - a)) / std::sqrt(a + b * c * c);
}

LevelDrift level_drift(std::span<const double> x, double variance, std::span<const double> rho,
                       int blocks, double variance_dof, double alpha, double power) {
    const size_t n = x.size();
    if (n < 4 || blocks < 2 || size_t(blocks) > n || !(variance > 0.0))
        throw ValueError("level_drift: needs >= 4 values, 2 <= blocks <= values and a variance > 0");
    LevelDrift L;
    for (double v : x) L.mean += v;
    L.mean /= double(n);
    // Least-squares slope b = sum w_i x_i, w_i = (i - ibar) / Sxx; Var b = sum w_i w_j C(i - j).
    const double ibar = 0.5 * double(n - 1);
    double sxx = 0.0;
    for (size_t i = 0; i < n; ++i) sxx += (double(i) - ibar) * (double(i) - ibar);
    for (size_t i = 0; i < n; ++i) L.slope += (double(i) - ibar) / sxx * x[i];
    // sum_i sum_j w_i w_j rho(|i - j|) by lags: sum_l rho(l) sum_i w_i w_{i+l}.
    double vb = 0.0;
    for (size_t l = 0; l < n && l < rho.size(); ++l) {
        double s = 0.0;
        for (size_t i = 0; i + l < n; ++i) s += (double(i) - ibar) * (double(i + l) - ibar);
        vb += (l == 0 ? 1.0 : 2.0) * rho[l] * s;
    }
    L.sd_slope = std::sqrt(std::max(vb, 0.0) * variance) / sxx;
    L.z_trend = student_to_normal(L.slope / L.sd_slope, variance_dof);
    // Block means m_b against the last one, y_b = m_b - m_B: chi^2 = y^T Cov(y)^-1 y has B - 1
    // degrees of freedom for a stationary Gaussian series, whatever its correlation (rho).
    const long m = long(n) / blocks;
    L.blocks = blocks;
    std::vector<double> means(size_t(blocks), 0.0);
    for (int b = 0; b < blocks; ++b) {
        for (long i = 0; i < m; ++i) means[size_t(b)] += x[size_t(b * m + i)];
        means[size_t(b)] /= double(m);
    }
    std::vector<double> pair(static_cast<size_t>(blocks));
    for (int d = 0; d < blocks; ++d) pair[size_t(d)] = block_pair(rho, long(d) * m, m);
    L.block_mean_variance = pair[0] * variance / double(m * m);
    const size_t k = size_t(blocks - 1);
    const auto cov = [&](size_t a, size_t b) { return pair[a > b ? a - b : b - a]; };
    std::vector<double> A(k * k), y(k);
    for (size_t a = 0; a < k; ++a) {
        y[a] = means[a] - means[k];
        for (size_t b = 0; b < k; ++b)
            A[a * k + b] = (cov(a, b) - cov(a, k) - cov(k, b) + cov(k, k)) * variance /
                           double(m * m);
    }
    L.chi2 = quadratic_form_inverse(std::move(A), y);
    L.dof = int(k);
    L.z_blocks = variance_ratio_to_normal(L.chi2 / double(k), double(k), variance_dof);
    // Smallest linear change of the level over the series that the trend test sees with the
    // given power at two-sided level alpha (normal approximation).
    const double za = -numeric::normal_quantile_lower(0.5 * alpha);
    const double zp = -numeric::normal_quantile_lower(1.0 - power);
    L.detectable_change = (za + zp) * L.sd_slope * double(n - 1);
    return L;
}

}  // namespace impulse::analysis
