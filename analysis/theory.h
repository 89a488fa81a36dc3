// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the analysis needs from a closed-form theory (Campbell's theorem, design.md §1) and the
// sampling-error helpers it judges measurements with (design.md §5). The theory of a scene is
// stated by scenes/ (scenes/closed_form.h), which sits above analysis/ (design.md §2):
// it is passed in as a ClosedForm, so the dependency runs one way.

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "analysis/analyze.h"

namespace impulse::analysis {

inline constexpr double kFamilyAlpha = 0.01;  ///< family-wise false-alarm rate of the max|z| tests
inline constexpr double kZLimit = 4.0;        ///< |z| limit for mean, variance and the trend t

/// printf("%.*g", digits, v).
std::string format_number(double v, int digits);

/// Two-sided Bonferroni threshold for the maximum of m |z| values at family-wise level alpha.
double bonferroni_threshold(int m, double alpha);

/// Wilson–Hilferty normal deviate of r = X / E[X] for X ~ Gamma(shape): nearly exact for the
/// mean of `shape` independent exponentials, which is what an annulus mean of periodogram bins is
/// (Wilson & Hilferty 1931; for large shape it is (r - 1) sqrt(shape)).
double wilson_hilferty_z(double ratio, double shape);

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

/// The closed-form statistics of what made the frames (a scene: scenes::closed_form), as the
/// analysis asks for them.
class ClosedForm {
public:
    virtual ~ClosedForm() = default;
    /// Notes for the result (the scene's own warnings).
    virtual std::vector<std::string> warnings() const = 0;
    /// The field values that display values 0 and 1 stand for (8/16-bit inputs are mapped back).
    virtual std::pair<double, double> display_range() const = 0;
    /// The closed forms are those of a sum of layers: false for a scene composed otherwise.
    virtual bool sum_of_layers() const = 0;
    /// Why sum_of_layers() is false, for the result's notes.
    virtual std::string not_covered() const = 0;
    /// Some parameter varies in time: the statistics are not stationary by design.
    virtual bool keyframed() const = 0;
    /// The correlation of n frames in time (and of each quarter of them).
    virtual TimeCorrelation time_correlation(size_t n, size_t quarter) const = 0;
    /// The theory for the frames measured in R (size, window, lags) with the sampling errors for
    /// the correlation tc; display inputs mapped back through [lo, hi] with `clipped` of their
    /// values at the ends. Adds notes to R.
    virtual TheoryComparison compare(AnalysisResult& R, const TimeCorrelation& tc, bool mapped,
                                     double lo, double hi, double clipped) const = 0;
};

}  // namespace impulse::analysis
