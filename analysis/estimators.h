// SPDX-License-Identifier: Apache-2.0
#pragma once
// The estimators of impulse::analysis (analysis/analysis.h): moments, histogram, periodogram
// (2-D and radially averaged), autocorrelation, per-frame and stationarity statistics.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace impulse::analysis {

/// A single-channel float image, row-major, top row first.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> data;  ///< width * height values
    float at(int x, int y) const { return data[static_cast<size_t>(y) * width + x]; }
};

/// Sample mean and (population, divide by n) variance, accumulated in double, fixed order.
struct Moments {
    double mean = 0.0;
    double variance = 0.0;
    double skewness = 0.0;         ///< third standardized moment
    double excess_kurtosis = 0.0;  ///< fourth standardized moment minus 3
    double min = 0.0, max = 0.0;
};
Moments moments(std::span<const float> values);

/// Histogram of `values` over [lo, hi) in `bins` equal bins; values outside are counted in
/// `below` / `above`.
struct Histogram {
    double lo = 0.0, hi = 1.0;
    std::vector<uint64_t> counts;
    uint64_t below = 0, above = 0;
};
Histogram histogram(std::span<const float> values, double lo, double hi, int bins);

/// Window applied before the FFT. `None` is right for periodic (torus) frames, which have no
/// edge discontinuity; `Hann` for ordinary frames (the estimate is normalised by the window's
/// energy so a white field still gives its true spectral density).
enum class Window { None, Hann };

/// 2-D periodogram |DFT(f - mean)|^2 / (sum of squared window weights), so that its expectation
/// is the spectral density S(k) in units of value^2 per (cycle/pixel)^2 (k in cycles per pixel),
/// for a field with unit pixel spacing. Layout: `power[ky * width + kx]` with FFT ordering
/// (index i <-> frequency i/n for i < n/2, (i-n)/n otherwise). The DC term is zero (mean removed).
struct Periodogram {
    int width = 0, height = 0;
    std::vector<double> power;
    /// frequency in cycles per pixel of FFT index i along an axis of length n
    static double frequency(int i, int n) { return (i < (n + 1) / 2 ? i : i - n) / double(n); }
};
Periodogram periodogram(const Image& image, Window window = Window::None);
/// Average of several periodograms of equal size (e.g. over frames): reduces the variance by
/// the number of independent inputs.
Periodogram average(std::span<const Periodogram> periodograms);

/// Radially averaged spectrum: annulus b holds |k| in [b*dk, (b+1)*dk), dk = 1/min(width,height),
/// up to the Nyquist radius 0.5. `count` is the number of DFT bins in the annulus (both members
/// of each conjugate pair); `frequency` is the mean |k| of those bins.
struct RadialProfile {
    std::vector<double> frequency;  ///< cycles per pixel
    std::vector<double> power;      ///< mean periodogram value in the annulus
    std::vector<uint64_t> count;
};
RadialProfile radial_average(const Periodogram& p);

/// Circular autocovariance of the mean-removed image via FFT (Wiener–Khinchine), normalised by
/// the pixel count: acov[dy * width + dx] for lags dx, dy in FFT ordering; acov[0] = variance.
/// For a periodic (torus) frame this is the exact sample autocovariance.
std::vector<double> autocovariance(const Image& image);
/// Radial average of an autocovariance image out to `max_lag` pixels in unit-wide rings
/// (ring r holds lags with round(|tau|) == r).
std::vector<double> radial_autocovariance(const std::vector<double>& acov, int width, int height,
                                          int max_lag);

/// Per-frame statistics of an animation.
struct FrameStats {
    double mean = 0.0;
    double variance = 0.0;
    double diff_variance = 0.0;  ///< variance of (frame - previous frame); 0 for the first frame
};
std::vector<FrameStats> frame_stats(std::span<const Image> frames);

/// Block statistics of a time series x_0..x_{n-1}: split into `blocks` equal consecutive blocks
/// (a remainder at the end is dropped) and return the block means.
std::vector<double> block_means(std::span<const double> series, int blocks);

/// Least-squares slope of y against index 0..n-1, with its standard error computed from the
/// scatter of `blocks` block means (so serial correlation shorter than a block is accounted for).
/// `t` = slope / stderr is the trend statistic reported by `impulse analyze`.
struct Trend {
    double slope = 0.0;
    double stderr_slope = 0.0;
    double t = 0.0;
};
Trend trend(std::span<const double> series, int blocks = 10);

/// Spectral drift between two sets of frames: for each annulus of their radially averaged
/// periodograms, z = (P_a - P_b) / sqrt(var_a + var_b) with var = P^2 / (effective count),
/// effective count = (annulus bins / 2) * frames. Returns max |z| over annuli with
/// frequency in (0, 0.5) and the per-annulus z values.
struct SpectralDrift {
    double max_abs_z = 0.0;
    std::vector<double> z;
    std::vector<double> frequency;
};
/// With Window::Hann, each periodogram is windowed and the variance multiplied by
/// kHannInflation.
SpectralDrift spectral_drift(std::span<const Image> early, std::span<const Image> late,
                             Window window = Window::None);

/// Variance inflation of an average of Hann-windowed periodogram bins: the DFT-even Hann window
/// makes neighbouring bins correlate with coefficients (1, -2/3, 1/6) per axis, so a sum of bins
/// has sum rho^2 = 35/18 times the variance per axis (Percival & Walden 1993 ch. 6). Using the
/// 2-D product is conservative for one-bin-wide annuli (radial neighbours fall outside).
inline constexpr double kHannInflation = (35.0 / 18.0) * (35.0 / 18.0);

/// Drift of the level of a correlated series x_0..x_{n-1} (analysis/level_drift.cpp), tested
/// against the covariance it has when stationary, C(l) = variance rho(l) (rho(0) = 1, rho = 0
/// beyond its size): the least-squares slope with its exact standard error under that C, and
/// the means of `blocks` equal consecutive blocks (a remainder at the end dropped) against the
/// last, chi^2 = y^T Cov(y)^-1 y with blocks - 1 degrees of freedom. A linear drift shows in the
/// slope, a swing that comes and goes (a pulsing source) in the blocks. `variance_dof`: degrees
/// of freedom of `variance` when it is estimated (infinity when known), so z_trend follows
/// Student's t and chi2 an F distribution before both are mapped to standard normal deviates.
/// Throws ValueError for fewer than 4 values, blocks outside [2, n] or variance <= 0.
struct LevelDrift {
    double mean = 0.0;
    double slope = 0.0, sd_slope = 0.0;
    double z_trend = 0.0;  ///< slope / sd_slope as a standard normal deviate (two-sided test)
    int blocks = 0, dof = 0;
    double chi2 = 0.0;
    double z_blocks = 0.0;  ///< chi2 / dof as an upper standard normal deviate (one-sided test)
    double block_mean_variance = 0.0;  ///< Var of one block's mean under C
    /// The linear change over the series (slope (n - 1)) the trend test detects with the given
    /// power at two-sided level alpha.
    double detectable_change = 0.0;
};
LevelDrift level_drift(std::span<const double> x, double variance, std::span<const double> rho,
                       int blocks, double variance_dof, double alpha, double power);
/// Student's t with `dof` degrees of freedom as a standard normal deviate of the same tail
/// probability (Wallace 1959); dof = infinity: t itself.
double student_to_normal(double t, double dof);
/// F(d1, d2) as an upper standard normal deviate (Paulson 1942); d2 = infinity: chi^2_d1 / d1.
double variance_ratio_to_normal(double F, double d1, double d2);

/// Kolmogorov–Smirnov distance between the empirical CDF of `values` and a CDF given as a
/// callable through a function pointer + context (keeps this header free of <functional>).
double ks_distance(std::span<const float> values, double (*cdf)(double x, const void* ctx),
                   const void* ctx);

}  // namespace impulse::analysis
