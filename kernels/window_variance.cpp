// SPDX-License-Identifier: Apache-2.0
// int A(u)^2 du of kernels/window_variance.h by FFT correlations of the window's indicator.

#include "kernels/window_variance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <optional>
#include <vector>

#include "kernels/kernel.h"
#include "numeric/fft.h"

namespace impulse::kernels {
namespace {

/// Total transform points (phases x padded window) above which the phases are thinned.
constexpr double kPointBudget = 67108864.0;  // 2^26

/// The padded transform and the window's indicator spectrum, shared by every phase.
struct Grid {
    int width, height;  ///< the window
    int reach;          ///< taps in [-reach, reach] pixels hold the kernel
    int rows, cols;     ///< transform size: the linear correlation fits without wrapping
    std::vector<std::complex<double>> indicator;  ///< spectrum of the window's indicator
};

Grid make_grid(int width, int height, int reach) {
    Grid g{width, height, reach, numeric::fast_fft_size(height + 2 * reach),
           numeric::fast_fft_size(width + 2 * reach), {}};
    numeric::RealFft2d fft(g.rows, g.cols, numeric::FftPlans::Forward);
    for (int y = 0; y < height; ++y)
        std::fill_n(fft.real() + size_t(y) * g.cols, width, 1.0);
    fft.forward();
    g.indicator.assign(fft.spectrum(), fft.spectrum() + size_t(g.rows) * fft.half_cols());
    return g;
}

/// Correlation of the window's indicator with the taps in `fft` (laid out as
/// taps[b][a] = g(reach - a, reach - b)): real()[m + reach] = sum_i g(x_i - m).
void correlate(numeric::RealFft2d& fft, const Grid& g) {
    fft.forward();
    const size_t n = size_t(g.rows) * fft.half_cols();
    const double scale = 1.0 / (double(g.rows) * g.cols);
    for (size_t i = 0; i < n; ++i) fft.spectrum()[i] *= g.indicator[i] * scale;
    fft.inverse();
}

/// A(u) on the u grid (rows x cols, row-major; zero beyond the window plus the reach) for
/// impulses at sub-pixel offset (dx, dy) and angle theta.
std::vector<double> phase_window_A(const Kernel& k, double zoom, double theta, double dx, double dy,
                                   const Grid& g) {
    numeric::RealFft2d h1(g.rows, g.cols, numeric::FftPlans::Both);
    numeric::RealFft2d h2(g.rows, g.cols, numeric::FftPlans::Both);
    const int taps = 2 * g.reach + 1;
    for (int b = 0; b < taps; ++b)
        for (int a = 0; a < taps; ++a) {
            const double x = (g.reach - a - dx) / zoom, y = (g.reach - b - dy) / zoom;
            const double v = k.evaluate(x, y, theta);
            h1.real()[size_t(b) * g.cols + a] = v;
            h2.real()[size_t(b) * g.cols + a] = v * v;
        }
    correlate(h1, g);
    correlate(h2, g);
    const double N = double(g.width) * g.height;
    std::vector<double> A(size_t(g.rows) * g.cols);
    for (size_t i = 0; i < A.size(); ++i) {
        const double hbar = h1.real()[i] / N;
        A[i] = h2.real()[i] / N - hbar * hbar;
    }
    return A;
}

/// sum over the u grid of A(u)^2 for impulses at sub-pixel offset (dx, dy) and angle theta.
double phase_sum(const Kernel& k, double zoom, double theta, double dx, double dy, const Grid& g) {
    double sum = 0.0;
    for (double a : phase_window_A(k, zoom, theta, dx, dy, g)) sum += a * a;
    return sum;
}

/// sum_u A(u) A(u + n) at integer shifts n, |n| up to `max_shift` per axis, from A's power
/// spectrum on a grid padded so that those shifts do not wrap; bilinear between them.
class Autocorrelation {
public:
    Autocorrelation(const std::vector<double>& A, const Grid& g, int max_shift)
        : m_extent_x(g.width + 2 * g.reach), m_extent_y(g.height + 2 * g.reach),
          m_cols(numeric::fast_fft_size(m_extent_x + std::min(max_shift, m_extent_x))),
          m_rows(numeric::fast_fft_size(m_extent_y + std::min(max_shift, m_extent_y))) {
        numeric::RealFft2d fft(m_rows, m_cols, numeric::FftPlans::Both);
        for (int y = 0; y < m_extent_y; ++y)
            std::copy_n(A.data() + size_t(y) * g.cols, m_extent_x, fft.real() + size_t(y) * m_cols);
        fft.forward();
        const size_t n = size_t(m_rows) * fft.half_cols();
        const double scale = 1.0 / (double(m_rows) * m_cols);
        for (size_t i = 0; i < n; ++i) fft.spectrum()[i] = std::norm(fft.spectrum()[i]) * scale;
        fft.inverse();
        m_values.assign(fft.real(), fft.real() + size_t(m_rows) * m_cols);
    }
    /// At an integer shift: 0 where the shifted A no longer overlaps A.
    double at(int nx, int ny) const {
        if (std::abs(nx) >= m_extent_x || std::abs(ny) >= m_extent_y) return 0.0;
        return m_values[size_t((ny + m_rows) % m_rows) * m_cols + (nx + m_cols) % m_cols];
    }
    double bilinear(double sx, double sy) const {
        const double fx = std::floor(sx), fy = std::floor(sy);
        const int x0 = int(fx), y0 = int(fy);
        const double tx = sx - fx, ty = sy - fy;
        return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
               ty * ((1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1));
    }

private:
    int m_extent_x, m_extent_y, m_cols, m_rows;
    std::vector<double> m_values;
};

/// The largest |component| of the shifts, rounded up, plus one for the bilinear neighbour.
int max_integer_shift(std::span<const std::array<double, 2>> shifts) {
    double m = 0.0;
    for (const auto& s : shifts) m = std::max({m, std::abs(s[0]), std::abs(s[1])});
    return int(std::ceil(std::min(m, 1e7))) + 1;
}

}  // namespace

int window_population_phases(double radius_px, int width, int height) {
    const int reach = int(std::ceil(radius_px)) + 1;
    // Gaussian-like kernels: a lattice sum of h^2 varies with the impulse's sub-pixel position
    // by about exp(-2 pi^2 (sigma / s)^2); R / s >= 6 makes that negligible.
    int s = std::clamp(int(std::ceil(6.0 / std::max(radius_px, 1e-3))), 1, 8);
    const double points = double(numeric::fast_fft_size(width + 2 * reach)) *
                          numeric::fast_fft_size(height + 2 * reach);
    while (s > 1 && double(s) * s * points > kPointBudget) --s;
    return s;
}

double window_population_integral(const Kernel& kernel, double zoom, int width, int height,
                                  int orientations) {
    const double radius_px = kernel.radius() * zoom;
    const Grid g = make_grid(width, height, int(std::ceil(radius_px)) + 1);
    const int s = window_population_phases(radius_px, width, height);
    const int n_theta = std::max(orientations, 1);
    const size_t tasks = size_t(n_theta) * s * s;
    std::vector<double> sums(tasks);
    tbb::parallel_for(size_t(0), tasks, [&](size_t t) {
        const int o = int(t / (size_t(s) * s)), p = int(t % s), q = int(t / s % s);
        const double theta = n_theta == 1 ? 0.0 : std::numbers::pi * o / n_theta;
        sums[t] = phase_sum(kernel, zoom, theta, double(p) / s, double(q) / s, g);
    });
    double total = 0.0;  // in task order: the same bits for any thread count
    for (double v : sums) total += v;
    return total / (double(s) * s * n_theta);
}

std::vector<double> window_population_correlation(const Kernel& kernel, double zoom, int width,
                                                  int height, int orientations,
                                                  std::span<const std::array<double, 2>> shifts) {
    const double radius_px = kernel.radius() * zoom;
    const Grid g = make_grid(width, height, int(std::ceil(radius_px)) + 1);
    const int s = window_population_phases(radius_px, width, height);
    const int n_theta = std::max(orientations, 1);
    const int max_shift = max_integer_shift(shifts);
    const size_t tasks = size_t(n_theta) * s * s;
    std::vector<std::vector<double>> per_task(tasks);
    tbb::parallel_for(size_t(0), tasks, [&](size_t t) {
        const int o = int(t / (size_t(s) * s)), p = int(t % s), q = int(t / s % s);
        const double theta = n_theta == 1 ? 0.0 : std::numbers::pi * o / n_theta;
        const Autocorrelation ac(
            phase_window_A(kernel, zoom, theta, double(p) / s, double(q) / s, g), g, max_shift);
        per_task[t].resize(shifts.size());
        for (size_t i = 0; i < shifts.size(); ++i)
            per_task[t][i] = ac.bilinear(shifts[i][0], shifts[i][1]);
    });
    std::vector<double> total(shifts.size(), 0.0);
    for (const auto& v : per_task)  // in task order: the same bits for any thread count
        for (size_t i = 0; i < v.size(); ++i) total[i] += v[i];
    for (double& v : total) v /= double(s) * s * n_theta;
    return total;
}

WindowCovariance::WindowCovariance(int width, int height, int rows, int cols)
    : m_width(width), m_height(height), m_rows(rows), m_cols(cols) {
    numeric::RealFft2d ind(rows, cols, numeric::FftPlans::Forward);
    for (int y = 0; y < height; ++y) std::fill_n(ind.real() + size_t(y) * cols, width, 1.0);
    ind.forward();
    m_indicator.assign(ind.spectrum(), ind.spectrum() + size_t(rows) * ind.half_cols());
}

void WindowCovariance::add(const std::vector<double>& spectrum) {
    const double norm = 1.0 / (double(m_rows) * m_cols);
    numeric::RealFft2d cov(m_rows, m_cols, numeric::FftPlans::Inverse);
    numeric::RealFft2d sums(m_rows, m_cols, numeric::FftPlans::Inverse);
    const int hc = cov.half_cols();
    for (int ky = 0; ky < m_rows; ++ky)
        for (int kx = 0; kx < hc; ++kx) {
            const size_t i = size_t(ky) * hc + kx;
            const double s = spectrum[size_t(ky) * m_cols + kx] * norm;
            cov.spectrum()[i] = s;
            sums.spectrum()[i] = m_indicator[i] * s;
        }
    cov.inverse();
    sums.inverse();
    m_cov.emplace_back(cov.real(), cov.real() + size_t(m_rows) * m_cols);
    m_rows_sum.emplace_back(sums.real(), sums.real() + size_t(m_rows) * m_cols);
}

double WindowCovariance::frame_mean_variance(std::span<const double> weight) const {
    // sum_ij C_ij = sum_c sum_{i in window} R_c(x_i), R_c(y) = sum_{j in window} K_c(x_j - y).
    double sum = 0.0;
    for (size_t c = 0; c < m_rows_sum.size(); ++c) {
        const double wc = weight.empty() ? 1.0 : weight[c];
        if (wc == 0.0) continue;
        for (int y = 0; y < m_height; ++y)
            for (int x = 0; x < m_width; ++x) sum += wc * m_rows_sum[c][size_t(y) * m_cols + x];
    }
    const double N = double(m_width) * m_height;
    return sum / (N * N);
}

double WindowCovariance::pixel_variance() const {
    double sum = 0.0;
    for (const auto& K : m_cov) sum += K[0];
    return sum;
}

namespace {

/// t mod n for |t| < 2n.
int wrap(int t, int n) { return t < 0 ? t + n : (t >= n ? t - n : t); }

/// The fraction of a pixel that every moving component's shift shares, if they share one.
std::optional<std::array<double, 2>> common_fraction(std::span<const double> weight,
                                                     std::span<const std::array<double, 2>> s) {
    std::optional<std::array<double, 2>> t;
    for (size_t c = 0; c < s.size(); ++c) {
        if (weight[c] == 0.0 || (s[c][0] == 0.0 && s[c][1] == 0.0)) continue;
        const std::array<double, 2> f{s[c][0] - std::floor(s[c][0]), s[c][1] - std::floor(s[c][1])};
        if (!t) t = f;
        if (std::abs(f[0] - (*t)[0]) > 1e-9 || std::abs(f[1] - (*t)[1]) > 1e-9) return std::nullopt;
    }
    return t ? t : std::array<double, 2>{0.0, 0.0};
}

}  // namespace

double WindowCovariance::gaussian_term(std::span<const double> weight,
                                       std::span<const std::array<int, 2>> shift) const {
    const int w = m_width, h = m_height, rows = m_rows, cols = m_cols;
    const size_t lag_cols = size_t(2 * w - 1);
    // C at lags (dx, dy) in [1 - w, w - 1] x [1 - h, h - 1], components added row by row.
    std::vector<double> c(lag_cols * size_t(2 * h - 1), 0.0);
    for (size_t k = 0; k < m_cov.size(); ++k) {
        if (weight[k] == 0.0) continue;
        for (int dy = 1 - h; dy < h; ++dy) {
            const double* src = m_cov[k].data() + size_t(wrap(dy - shift[k][1], rows)) * cols;
            double* dst = c.data() + size_t(dy + h - 1) * lag_cols;
            for (int dx = 1 - w; dx < w; ++dx)
                dst[dx + w - 1] += weight[k] * src[wrap(dx - shift[k][0], cols)];
        }
    }
    // sum_ij C_ij^2 by lags: (w - |dx|)(h - |dy|) pixel pairs are dx, dy apart.
    double sum_sq = 0.0;
    for (int dy = 1 - h; dy < h; ++dy)
        for (int dx = 1 - w; dx < w; ++dx) {
            const double v = c[size_t(dy + h - 1) * lag_cols + size_t(dx + w - 1)];
            sum_sq += double(w - std::abs(dx)) * (h - std::abs(dy)) * v * v;
        }
    // Row sums r_i = sum_k w_k R_k(x_i + s_k), column sums c_j = sum_k w_k R_k(x_j - s_k).
    std::vector<double> r(size_t(w) * h, 0.0), col(size_t(w) * h, 0.0);
    for (size_t k = 0; k < m_cov.size(); ++k) {
        if (weight[k] == 0.0) continue;
        const int sx = shift[k][0], sy = shift[k][1];
        for (int y = 0; y < h; ++y) {
            const double* plus = m_rows_sum[k].data() + size_t(wrap(y + sy, rows)) * cols;
            const double* minus = m_rows_sum[k].data() + size_t(wrap(y - sy, rows)) * cols;
            for (int x = 0; x < w; ++x) {
                r[size_t(y) * w + x] += weight[k] * plus[wrap(x + sx, cols)];
                col[size_t(y) * w + x] += weight[k] * minus[wrap(x - sx, cols)];
            }
        }
    }
    const double N = double(w) * h;
    double sum_r = 0.0, sum_r2 = 0.0, sum_c2 = 0.0;
    for (size_t i = 0; i < r.size(); ++i) {
        sum_r += r[i];
        sum_r2 += r[i] * r[i];
        sum_c2 += col[i] * col[i];
    }
    // ||P C P||_F^2 = sum C_ij^2 - (sum_i r_i^2 + sum_j c_j^2) / N + (sum C)^2 / N^2.
    return 2.0 * (sum_sq - (sum_r2 + sum_c2) / N + sum_r * sum_r / (N * N)) / (N * N);
}

double WindowCovariance::gaussian_term(std::span<const double> weight,
                                       std::span<const std::array<double, 2>> shift) const {
    const auto frac = common_fraction(weight, shift);
    const std::array<double, 2> t = frac ? *frac : std::array<double, 2>{0.0, 0.0};
    double sum = 0.0;
    std::vector<std::array<int, 2>> n(shift.size());
    for (int cy = 0; cy < 2; ++cy)
        for (int cx = 0; cx < 2; ++cx) {
            const double bw = (cx ? t[0] : 1.0 - t[0]) * (cy ? t[1] : 1.0 - t[1]);
            if (bw == 0.0) continue;
            for (size_t c = 0; c < shift.size(); ++c) {
                const auto& s = shift[c];
                const bool moves = s[0] != 0.0 || s[1] != 0.0;
                if (!moves)
                    n[c] = {0, 0};
                else if (frac)
                    n[c] = {int(std::floor(s[0])) + cx, int(std::floor(s[1])) + cy};
                else
                    n[c] = {int(std::lround(s[0])), int(std::lround(s[1]))};
            }
            sum += bw * gaussian_term(weight, std::span<const std::array<int, 2>>(n));
        }
    return sum;
}

}  // namespace impulse::kernels
