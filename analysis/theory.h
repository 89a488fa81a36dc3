// SPDX-License-Identifier: Apache-2.0
#pragma once
// The closed-form theory of a scene as seen through frames of it (Campbell's theorem,
// design.md §1): expected mean, variance, periodogram and autocovariance of a sum of layers, the
// correlation of frames in time, and the sampling errors the comparison judges them with
// (design.md §5). Builds on scenes/ (layer_theory, scene_theory); scenes/ does not use analysis/,
// so the dependency runs one way.

#include <cstddef>
#include <string>
#include <vector>

#include "analysis/analyze.h"
#include "scenes/scenes.h"

namespace impulse::analysis {

inline constexpr double kFamilyAlpha = 0.01;  ///< family-wise false-alarm rate of the max|z| tests
inline constexpr double kZLimit = 4.0;        ///< |z| limit for mean, variance and the trend t

/// printf("%.*g", digits, v).
std::string format_number(double v, int digits);

/// Two-sided Bonferroni threshold for the maximum of m |z| values at family-wise level alpha.
double bonferroni_threshold(int m, double alpha);

/// Effective number of independent frames among n consecutive ones whose statistic has
/// correlation r(l) at a lag of l frames: Var(mean) = (s^2 / n) (1 + 2 sum (1 - l/n) r(l)).
double effective_frames(size_t n, const std::vector<double>& r);

/// How many independent frames the averages over frames are worth.
struct TimeCorrelation {
    std::string source = "none";  ///< "scene", "frames" or "none" (fewer than 10 frames)
    double n_eff_mean = 1, n_eff_variance = 1, n_eff_spectrum = 1;
    double n_eff_population = 1;  ///< for the impulse-count (fourth-cumulant) fluctuations
    double q_eff = 1, q_eff_population = 1;  ///< the same for each quarter of the drift test
    bool converged = true;
    /// From the scene: the correlation at lags 0..n-1 of the field squared (periodogram bins,
    /// the Gaussian part of the frame variance) and of the impulse population (fourth power of
    /// the envelope); empty otherwise.
    std::vector<double> r2, r4;
};

/// From the scene: without flow a layer's field at lags of l frames correlates as its envelope,
/// r(l) = (w * w~)(l / fps) / int w^2 (design.md §1; 1 for a still layer), layers weighted by
/// their variance. The frame mean follows r, periodogram bins and the frame variance follow r^2
/// (Gaussian approximation). Advection by a flow moves the pattern without changing the power of
/// a periodic frame and decorrelates the rest sooner, so this is exact or conservative with flows.
TimeCorrelation scene_time_correlation(const scenes::Scene& scene, size_t n, size_t quarter);

/// Closed-form statistics of the scene for the frames measured in R (its size, window, lags),
/// with the sampling errors for the correlation tc; display inputs mapped back through [lo, hi]
/// with `clipped` of their values at the ends. Adds notes to R.
TheoryComparison compare_with_theory(const scenes::Scene& scene, const std::string& path,
                                     AnalysisResult& R, const TimeCorrelation& tc, bool mapped,
                                     double lo, double hi, double clipped);

}  // namespace impulse::analysis
