// SPDX-License-Identifier: Apache-2.0
// int A(u)^2 du of kernels/window_variance.h by FFT correlations of the window's indicator.

#include "kernels/window_variance.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
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

/// sum over the u grid of A(u)^2 for impulses at sub-pixel offset (dx, dy) and angle theta.
double phase_sum(const Kernel& k, double zoom, double theta, double dx, double dy, const Grid& g) {
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
    double sum = 0.0;
    for (size_t i = 0; i < size_t(g.rows) * g.cols; ++i) {
        const double hbar = h1.real()[i] / N;
        const double A = h2.real()[i] / N - hbar * hbar;
        sum += A * A;
    }
    return sum;
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

}  // namespace impulse::kernels
