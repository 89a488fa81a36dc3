// SPDX-License-Identifier: Apache-2.0
#pragma once
// Structure function and generalised Hurst exponent (analysis/structure.cpp): how a surface's
// increments grow with the lag, the test of self-similarity (Kaplan & Kuo 1996 §V). For fBm,
// E[(B(p + d) - B(p))^2] = sigma^2 |d|^{2H} (their eqs. 2-3). Part of impulse::analysis.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "analysis/estimators.h"

namespace impulse::analysis {

/// Sample structure function at the given lags (pixels): the mean of (B(p + d u) - B(p))^2 over
/// every pixel pair inside the image, along u = x (1, 0), y (0, 1) and the diagonal (1, 1) (a
/// diagonal lag d spans d sqrt(2) pixels). `f` is the mean of the x and y values.
struct StructureFunction {
    std::vector<int> lags;
    std::vector<double> fx, fy, diagonal, f;
};
StructureFunction structure_function(const Image& image, std::span<const int> lags);

/// 1, 2, 4, ... up to the largest power of two <= max_lag.
std::vector<int> dyadic_lags(int max_lag);

/// Generalised Hurst exponent (Kaplan & Kuo eq. 21) from f at the dyadic lags 2^0, 2^1, ...:
/// H(s) = 1/2 log2(f(2^{s+1}) / f(2^s)), s = 0 .. size - 2. NaN where f is not positive.
std::vector<double> generalized_hurst(std::span<const double> f_dyadic);

/// Structure function and H(s) pooled over realizations (or frames): f averaged over them, H(s)
/// from the pooled f, and its sampling band: stderr(s) = sd of the per-realization H(s) / sqrt(n)
/// (0 for one realization). Add images of equal size one at a time (fixed order: deterministic).
struct StructureSummary {
    std::vector<int> lags;  ///< dyadic, 1 .. 2^{smax+1}
    std::vector<double> fx, fy, diagonal, f;
    std::vector<double> hurst;         ///< H(s) of the pooled f, s = 0 .. lags.size() - 2
    std::vector<double> hurst_x, hurst_y, hurst_diagonal;
    std::vector<double> hurst_stderr;  ///< of `hurst`, over realizations
    int realizations = 0;
};
class StructureAccumulator {
public:
    /// Lags 2^0 .. 2^{max_s + 1} (clipped to the image).
    explicit StructureAccumulator(int max_s) : m_max_s(max_s) {}
    void add(const Image& image);
    StructureSummary summary() const;

private:
    int m_max_s;
    std::vector<int> m_lags;
    std::vector<StructureFunction> m_each;
};

/// Per-pixel variance over realizations (Kaplan & Kuo Figs. 1-2): the sample variance (divide
/// by n - 1) of each pixel across the images added.
class PixelVariance {
public:
    void add(const Image& image);
    /// The variance map (n >= 2 images added).
    Image variance() const;
    int count() const { return m_n; }

private:
    int m_n = 0, m_w = 0, m_h = 0;
    std::vector<double> m_sum, m_sum2;
};

/// 1-D profile: row `index` (along x) or column `index` (along y) of the image.
std::vector<double> profile(const Image& image, bool along_x, int index);

}  // namespace impulse::analysis
