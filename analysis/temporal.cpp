// SPDX-License-Identifier: Apache-2.0
// Statistics over time: per-frame moments, block means, the trend test and spectral drift
// between two sets of frames. Sums are in double in a fixed order: results are deterministic.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "numeric/errors.h"

namespace impulse::analysis {
namespace {

std::string size_text(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

// Every frame non-empty, consistent, and the same size as the first.
void check_frames(std::span<const Image> frames, const char* what) {
    if (frames.empty()) throw ValueError(std::string(what) + ": no frames");
    const Image& first = frames.front();
    for (size_t j = 0; j < frames.size(); ++j) {
        const Image& f = frames[j];
        if (f.width <= 0 || f.height <= 0) {
            throw ValueError(std::string(what) + ": frame " + std::to_string(j) + " is " +
                             size_text(f) + ": must be non-empty");
        }
        if (f.data.size() != static_cast<size_t>(f.width) * f.height) {
            throw ValueError(std::string(what) + ": frame " + std::to_string(j) + " has " +
                             std::to_string(f.data.size()) + " values for " + size_text(f));
        }
        if (f.width != first.width || f.height != first.height) {
            throw ValueError(std::string(what) + ": frame " + std::to_string(j) + " is " +
                             size_text(f) + ", frame 0 is " + size_text(first));
        }
    }
}

struct MeanVar {
    double mean = 0.0;
    double variance = 0.0;
};

// Two-pass population mean and variance of value(i), i = 0..n-1.
template <class F>
MeanVar mean_variance(size_t n, F value) {
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) sum += value(i);
    MeanVar r;
    r.mean = sum / static_cast<double>(n);
    double s2 = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double d = value(i) - r.mean;
        s2 += d * d;
    }
    r.variance = s2 / static_cast<double>(n);
    return r;
}

// Ordinary least-squares slope of y_i against x_i (centred sums, fixed order).
struct LineFit {
    double slope = 0.0;
    double intercept = 0.0;
    double sxx = 0.0;  ///< sum (x - xbar)^2
};
template <class X, class Y>
LineFit fit_line(size_t n, X x, Y y) {
    double sx = 0.0, sy = 0.0;
    for (size_t i = 0; i < n; ++i) {
        sx += x(i);
        sy += y(i);
    }
    const double xbar = sx / static_cast<double>(n), ybar = sy / static_cast<double>(n);
    double sxx = 0.0, sxy = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double dx = x(i) - xbar;
        sxx += dx * dx;
        sxy += dx * (y(i) - ybar);
    }
    LineFit f;
    f.sxx = sxx;
    f.slope = sxy / sxx;
    f.intercept = ybar - f.slope * xbar;
    return f;
}

// Mean of the periodograms of `frames` (Window::None), accumulated frame by frame in order so
// memory stays at one periodogram; equals average() of the same list bit for bit.
Periodogram mean_periodogram(std::span<const Image> frames, Window window) {
    Periodogram sum = periodogram(frames.front(), window);
    for (size_t j = 1; j < frames.size(); ++j) {
        const Periodogram p = periodogram(frames[j], window);
        for (size_t i = 0; i < p.power.size(); ++i) sum.power[i] += p.power[i];
    }
    const double inv = 1.0 / static_cast<double>(frames.size());
    for (double& v : sum.power) v *= inv;
    return sum;
}

}  // namespace

/// Mean, population variance and variance of the difference to the previous frame, per frame.
/// Deterministic; throws ValueError for no frames or frames of different or empty sizes.
std::vector<FrameStats> frame_stats(std::span<const Image> frames) {
    check_frames(frames, "frame_stats");
    std::vector<FrameStats> stats(frames.size());
    for (size_t j = 0; j < frames.size(); ++j) {
        const std::vector<float>& cur = frames[j].data;
        const MeanVar mv = mean_variance(cur.size(), [&](size_t i) { return double(cur[i]); });
        stats[j].mean = mv.mean;
        stats[j].variance = mv.variance;
        if (j > 0) {
            const std::vector<float>& prev = frames[j - 1].data;
            const auto diff = [&](size_t i) { return double(cur[i]) - prev[i]; };
            stats[j].diff_variance = mean_variance(cur.size(), diff).variance;
        }
    }
    return stats;
}

/// Means of `blocks` consecutive blocks of floor(n / blocks) values each. Throws ValueError for
/// blocks < 1 or fewer values than blocks.
std::vector<double> block_means(std::span<const double> series, int blocks) {
    if (blocks < 1) {
        throw ValueError("block_means: blocks = " + std::to_string(blocks) + ": must be >= 1");
    }
    if (series.size() < static_cast<size_t>(blocks)) {
        throw ValueError("block_means: " + std::to_string(series.size()) + " values for " +
                         std::to_string(blocks) + " blocks");
    }
    const size_t len = series.size() / static_cast<size_t>(blocks);
    std::vector<double> means(static_cast<size_t>(blocks));
    for (size_t b = 0; b < means.size(); ++b) {
        double sum = 0.0;
        for (size_t i = b * len; i < (b + 1) * len; ++i) sum += series[i];
        means[b] = sum / static_cast<double>(len);
    }
    return means;
}

/// OLS trend of the whole series with a block-means standard error. If the standard error is
/// 0 (block means exactly on a line), t is 0 for a zero slope and +-infinity otherwise.
/// Deterministic; throws ValueError for blocks < 3 or fewer values than blocks.
Trend trend(std::span<const double> series, int blocks) {
    if (blocks < 3) {
        throw ValueError("trend: blocks = " + std::to_string(blocks) +
                         ": must be >= 3 (the block fit has blocks - 2 degrees of freedom)");
    }
    if (series.size() < static_cast<size_t>(blocks)) {
        throw ValueError("trend: " + std::to_string(series.size()) + " values for " +
                         std::to_string(blocks) + " blocks");
    }
    Trend tr;
    const auto index = [](size_t i) { return static_cast<double>(i); };
    const auto value = [&](size_t i) { return series[i]; };
    tr.slope = fit_line(series.size(), index, value).slope;

    // Standard error from the block means m_j, j = 0..B-1, of blocks of L = floor(n/B) values,
    // placed at their centre index c_j = j L + (L - 1)/2. Fit m_j = a + b c_j by OLS; then
    //     s^2 = sum_j (m_j - a - b c_j)^2 / (B - 2),    stderr = sqrt(s^2 / sum_j (c_j - cbar)^2)
    // (the textbook OLS slope error, e.g. Draper & Smith 1998 ch. 1, applied to the block means).
    // c_j is in index units, so b and its error are already per index, like the full slope.
    // Why it is the error of the full-series slope: block means of a series whose correlation
    // is shorter than L are nearly independent, with variance sigma_B^2 = (long-run variance)/L,
    // which s^2 estimates whether or not a trend is present. For white noise of variance s2,
    // Var(b) = 12 s2 / (n (n^2 - L^2)) against 12 s2 / (n (n^2 - 1)) for the full slope: a ratio
    // of about B^2 / (B^2 - 1), so the error is slightly conservative; for correlated noise both
    // scale with the long-run variance in place of s2, which the per-point OLS error misses.
    const std::vector<double> means = block_means(series, blocks);
    const double len = static_cast<double>(series.size() / static_cast<size_t>(blocks));
    const auto centre = [&](size_t j) { return static_cast<double>(j) * len + 0.5 * (len - 1.0); };
    const LineFit fit = fit_line(means.size(), centre, [&](size_t j) { return means[j]; });
    double ss = 0.0;
    for (size_t j = 0; j < means.size(); ++j) {
        const double e = means[j] - (fit.intercept + fit.slope * centre(j));
        ss += e * e;
    }
    const double s2 = ss / static_cast<double>(blocks - 2);
    tr.stderr_slope = std::sqrt(s2 / fit.sxx);

    if (tr.stderr_slope > 0.0) {
        tr.t = tr.slope / tr.stderr_slope;
    } else if (tr.slope != 0.0) {
        tr.t = std::copysign(std::numeric_limits<double>::infinity(), tr.slope);
    }
    return tr;
}

/// Spectral drift between two frame sets of one size; see analysis.h. Periodograms use
/// Window::None. The returned z and frequency list only the annuli compared (non-empty, with
/// mean |k| in (0, 0.5)), in increasing frequency. z is 0 where both powers are 0.
/// Deterministic; throws ValueError for an empty set or frames of different sizes.
SpectralDrift spectral_drift(std::span<const Image> early, std::span<const Image> late,
                             Window window) {
    check_frames(early, "spectral_drift (early)");
    check_frames(late, "spectral_drift (late)");
    if (early.front().width != late.front().width || early.front().height != late.front().height) {
        throw ValueError("spectral_drift: early frames are " + size_text(early.front()) +
                         ", late frames are " + size_text(late.front()));
    }
    // No window: the variance model below assumes that the two members of each conjugate pair
    // carry one independent exponential value (Var P(k) = S(k)^2), true of unwindowed bins of a
    // torus frame; a window correlates neighbouring bins and would inflate |z|. For frames with
    // edges, the leakage that a missing window lets through is the same in both sets, so it
    // biases both P_a and P_b alike and cancels in the difference.
    // Frames with edges: the leakage of an unwindowed periodogram is driven by the few values
    // at the edges, so at high frequencies, where the field's own power is small, every annulus
    // rises and falls with it together: the callers' Hann window (Window::Hann) takes it out, at
    // the cost of bins correlated by (1, -2/3, 1/6) per axis (kHannInflation).
    const RadialProfile a = radial_average(mean_periodogram(early, window));
    const RadialProfile b = radial_average(mean_periodogram(late, window));
    const double inflation = window == Window::Hann ? kHannInflation : 1.0;
    const double frames_a = static_cast<double>(early.size());
    const double frames_b = static_cast<double>(late.size());

    SpectralDrift drift;
    for (size_t i = 0; i < a.power.size(); ++i) {
        if (a.count[i] == 0 || !(a.frequency[i] > 0.0 && a.frequency[i] < 0.5)) continue;
        // An annulus of `count` bins (excluding Nyquist and DC, every bin has a distinct
        // conjugate partner) holds count/2 independent exponential values per frame, so the
        // mean P has Var = P^2 / ((count/2) frames). z is then ~N(0,1) when nothing changed.
        const double pairs = 0.5 * static_cast<double>(a.count[i]);
        const double var = inflation * (a.power[i] * a.power[i] / (pairs * frames_a) +
                                        b.power[i] * b.power[i] / (pairs * frames_b));
        const double z = var > 0.0 ? (a.power[i] - b.power[i]) / std::sqrt(var) : 0.0;
        drift.z.push_back(z);
        drift.frequency.push_back(a.frequency[i]);
        drift.max_abs_z = std::max(drift.max_abs_z, std::abs(z));
    }
    return drift;
}

}  // namespace impulse::analysis
