// SPDX-License-Identifier: Apache-2.0
// One-point statistics: moments, histogram, Kolmogorov–Smirnov distance. All sums are in
// double, in index order, so results are bit-identical from run to run.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "numeric/errors.h"

namespace impulse::analysis {

/// Two-pass moments (mean first, then central sums), population normalisation. Skewness and
/// excess kurtosis are reported as 0 when the variance is 0 (they are undefined there).
Moments moments(std::span<const float> values) {
    if (values.empty()) throw ValueError("moments: no values");
    const double n = static_cast<double>(values.size());

    Moments m;
    double sum = 0.0;
    m.min = values[0];
    m.max = values[0];
    for (float v : values) {
        sum += v;
        m.min = std::min(m.min, static_cast<double>(v));
        m.max = std::max(m.max, static_cast<double>(v));
    }
    m.mean = sum / n;

    // Central sums around the computed mean: the two-pass form avoids the cancellation of
    // E[x^2] - E[x]^2 for fields with a large mean.
    double s2 = 0.0, s3 = 0.0, s4 = 0.0;
    for (float v : values) {
        const double d = v - m.mean;
        const double d2 = d * d;
        s2 += d2;
        s3 += d2 * d;
        s4 += d2 * d2;
    }
    m.variance = s2 / n;
    if (m.variance > 0.0) {
        m.skewness = (s3 / n) / (m.variance * std::sqrt(m.variance));
        m.excess_kurtosis = (s4 / n) / (m.variance * m.variance) - 3.0;
    }
    return m;
}

/// Bin b holds [lo + b*(hi-lo)/bins, lo + (b+1)*(hi-lo)/bins); a value equal to `hi` is
/// `above`. Throws ValueError for bins <= 0, a non-finite or empty range, or a NaN value.
Histogram histogram(std::span<const float> values, double lo, double hi, int bins) {
    if (bins <= 0) throw ValueError("histogram: bins = " + std::to_string(bins) + ": must be > 0");
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi)) {
        throw ValueError("histogram: range [" + std::to_string(lo) + ", " + std::to_string(hi) +
                         "): must be finite with lo < hi");
    }
    Histogram h;
    h.lo = lo;
    h.hi = hi;
    h.counts.assign(static_cast<size_t>(bins), 0);
    const double scale = bins / (hi - lo);
    for (float v : values) {
        if (std::isnan(v)) throw ValueError("histogram: value is NaN");
        if (v < lo) {
            ++h.below;
        } else if (v >= hi) {
            ++h.above;
        } else {
            // Rounding can push a value just below `hi` to index `bins`: it belongs in the last.
            const int b = std::min(static_cast<int>((v - lo) * scale), bins - 1);
            ++h.counts[static_cast<size_t>(b)];
        }
    }
    return h;
}

/// D = sup_x |F_n(x) - F(x)|. Deterministic; throws ValueError for no values, a null `cdf`
/// or a NaN value.
double ks_distance(std::span<const float> values, double (*cdf)(double x, const void* ctx),
                   const void* ctx) {
    if (values.empty()) throw ValueError("ks_distance: no values");
    if (cdf == nullptr) throw ValueError("ks_distance: cdf is null");
    std::vector<double> sorted(values.begin(), values.end());
    for (double v : sorted) {
        if (std::isnan(v)) throw ValueError("ks_distance: value is NaN");
    }
    std::sort(sorted.begin(), sorted.end());

    // The empirical CDF steps from i/n to (i+1)/n at the i-th order statistic, so the sup is
    // attained at a step, on one side or the other. Ties need no special case: the largest
    // gap of a run of equal values is covered by its first left limit and its last right value.
    const double n = static_cast<double>(sorted.size());
    double d = 0.0;
    for (size_t i = 0; i < sorted.size(); ++i) {
        const double f = cdf(sorted[i], ctx);
        d = std::max(d, static_cast<double>(i + 1) / n - f);
        d = std::max(d, f - static_cast<double>(i) / n);
    }
    return d;
}

}  // namespace impulse::analysis
