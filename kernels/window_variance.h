// SPDX-License-Identifier: Apache-2.0
#pragma once
// The impulse population's share of the scatter of a frame's sample variance, exact for any
// kernel against the analysed window (part of impulse::kernels; included by kernels/kernels.h).
//
// A frame of N pixels x_i measures V = (1/N) sum_i (f(x_i) - fbar)^2. For shot noise
// f(x) = sum_j m_j h(x - p_j) (Poisson points p_j of intensity lambda, marks m_j = a_j w_j) V is
// a quadratic form in the random measure M = sum_j m_j delta_{p_j}:
//     V = int int Q(u, v) dM(u) dM(v),
//     Q(u, v) = (1/N) sum_i (h(x_i - u) - hbar(u)) (h(x_i - v) - hbar(v)),
//     hbar(u) = (1/N) sum_i h(x_i - u).
// The cumulant measures of M are kappa_n = lambda E[m^n] on the diagonal (Campbell's theorem).
// Var V sums the connected partitions of the four factors: those holding a kappa_1 vanish
// (int Q(u, v) dv = 0: the frame mean takes away a constant), the two pairings give the
// Gaussian part 2 (lambda E[m^2])^2 int int Q^2, and the one block of four gives
//     Var_population V = lambda E[m^4] int A(u)^2 du,   A(u) = Q(u, u)
//                      = (1/N) sum_i h(x_i - u)^2 - hbar(u)^2.
// For kernels small against the window A = int h^2 / N over the window's area N and zero
// outside, so this is lambda E[m^4] (int h^2)^2 / N; wider kernels put most of an impulse into
// hbar, which the frame mean removes, and the term is far smaller.
//
// Two frames d apart under a uniform flow (docs/stationarity.md): frame d is frame 0's process
// aged by d and moved by s_d pixels, so the same cumulants give
//     Cov_population(V_0, V_d) = beta E[a^4] int w^2(b) w^2(b + d) db  int A(u) A(u + s_d) du,
//     Cov_Gaussian(V_0, V_d)   = 2 ||P C_d P||_F^2 / N^2,  C_d(i, j) = Cov(f_0(x_i), f_d(x_j)).

#include <array>
#include <complex>
#include <span>
#include <vector>

namespace impulse::kernels {

class Kernel;

/// int A(u)^2 du (the factor of lambda E[m^4] above) for a width x height window of pixels at
/// unit spacing, the kernel h(x / zoom) in pixel units (zoom pixels per texture unit) averaged
/// over `orientations` angles in [0, pi) (1: the kernel's own). The u integral is a Riemann sum
/// over a grid of s x s sub-pixel phases (s from the kernel's size in pixels: a lattice sum of a
/// kernel only a pixel wide depends on where the impulse sits between pixels), each phase a
/// linear correlation of the window's indicator with h and h^2 by FFT (numeric/fft.h).
double window_population_integral(const Kernel& kernel, double zoom, int width, int height,
                                  int orientations = 1);

/// The sub-pixel phases per axis window_population_integral uses for a kernel of radius
/// `radius_px` pixels in a width x height window (at most 8; fewer when the transforms would
/// exceed about 2^26 points, where the window is then large against the kernel).
int window_population_phases(double radius_px, int width, int height);

/// int A(u) A(u + s) du for each shift s = (sx, sy) in pixels (frame d's content moved by s
/// against frame 0's), the same phases and orientations as window_population_integral, whose
/// value it is at s = 0 up to rounding. Integer shifts come from the autocorrelation of A by FFT;
/// fractional ones are interpolated bilinearly between them (the autocorrelation varies on the
/// scale of the kernel and the window, not of a pixel: docs/stationarity.md). Deterministic.
std::vector<double> window_population_correlation(const Kernel& kernel, double zoom, int width,
                                                  int height, int orientations,
                                                  std::span<const std::array<double, 2>> shifts);

/// The Gaussian part of the covariance of two frames' sample variances over a width x height
/// window, 2 ||P C P||_F^2 / N^2 (P the centring projector), for a pixel covariance
/// C(x_i, x_j) = sum_c weight_c K_c(x_j - x_i - shift_c): components K_c (layers), each scaled
/// by its time correlation and moved by its integer displacement. Each K_c is the inverse DFT of
/// an aliased spectrum on a periodic rows x cols grid; the grid must hold every lag up to the
/// window plus the largest shift plus K's reach without wrapping.
class WindowCovariance {
public:
    WindowCovariance(int width, int height, int rows, int cols);
    /// Adds a component from its spectrum on the rows x cols DFT grid (row-major, value^2 px^2).
    void add(const std::vector<double>& spectrum);
    size_t components() const { return m_cov.size(); }
    /// Var of a frame's mean over the window, (1/N^2) sum_ij C_ij at no shift, C = sum_c
    /// weight[c] K_c (all components when `weight` is empty): the exact value for a field that
    /// does not wrap around the window (S(0) / N holds only for frames that are periodic over
    /// the window; for kernels wide against the window it is far too large).
    double frame_mean_variance(std::span<const double> weight = {}) const;
    /// sum_c K_c(0): a pixel's variance.
    double pixel_variance() const;
    /// 2 ||P C P||_F^2 / N^2 with weight[c] and shift[c] (pixels, integer) per component.
    double gaussian_term(std::span<const double> weight,
                         std::span<const std::array<int, 2>> shift) const;
    /// The same at any shifts (pixels): components that move (shift != 0) by the same fraction
    /// of a pixel are interpolated bilinearly between the four integer shifts around theirs (the
    /// term varies on the scale of the kernels and the window, not of a pixel:
    /// docs/stationarity.md); components moving by different fractions are rounded to whole
    /// pixels.
    double gaussian_term(std::span<const double> weight,
                         std::span<const std::array<double, 2>> shift) const;

private:
    int m_width, m_height, m_rows, m_cols;
    std::vector<std::complex<double>> m_indicator;  ///< spectrum of the window's indicator
    std::vector<std::vector<double>> m_cov;   ///< K_c at lags (dy mod rows, dx mod cols)
    std::vector<std::vector<double>> m_rows_sum;  ///< R_c(y) = sum_{j in window} K_c(x_j - y)
};

}  // namespace impulse::kernels
