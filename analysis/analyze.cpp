// SPDX-License-Identifier: Apache-2.0
// The analysis of frames behind `impulse analyze`: measure them with the estimators and compare
// the measurements with the closed-form theory of a scene (Campbell's theorem, design.md §1;
// stated by scenes/theory/closed_form.cpp, passed in as an analysis::ClosedForm) with tolerances
// derived from each estimator's sampling error (design.md §5).

#include "analysis/analysis.h"
#include "analysis/analyze.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <span>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "analysis/theory.h"
#include "numeric/errors.h"
#include "numeric/gaussian.h"

namespace impulse::analysis {
namespace {

constexpr int kHistogramBins = 64;
constexpr double kHistogramHalfWidthSd = 4.0;
constexpr int kTrendBlocks = 10;

/// Fewest equivalent degrees of freedom of a block mean of the frame variance at which the level
/// tests may reject: block means distributed as scaled chi^2 with nu degrees of freedom push the
/// block test's false-alarm rate (nominal 1/300) to 1.32 times nominal at nu = 100, 1.68 at 50,
/// 4.5 at 10 (400 000 simulated series each: docs/stationarity.md).
constexpr double kMinBlockDof = 100.0;
constexpr int kMinFramesForTime = 10;  ///< fewer frames: no stationarity test, n_eff = 1
constexpr int kMinSize = 8;
constexpr int kHeatCells = 64;


// ---------------------------------------------------------------------------------------------
// Measurements

struct WrapTest {
    double ratio_x = 1.0, ratio_y = 1.0;
    bool periodic = false;
};

/// Is every frame one period of a torus? The mean squared step across the wrap (last column to
/// first, last row to first) is compared with the mean squared step between neighbours inside
/// the frame and with 2 * variance, its value for unrelated edges: a frame is periodic along an
/// axis when the wrap step is closer to the interior step.
WrapTest wrap_test(std::span<const Image> frames, double variance) {
    double ix = 0, wx = 0, iy = 0, wy = 0;
    double nix = 0, nwx = 0, niy = 0, nwy = 0;
    for (const Image& f : frames) {
        const int w = f.width, h = f.height;
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x + 1 < w; ++x) {
                const double d = double(f.at(x + 1, y)) - f.at(x, y);
                ix += d * d;
            }
            const double d = double(f.at(0, y)) - f.at(w - 1, y);
            wx += d * d;
        }
        for (int y = 0; y + 1 < h; ++y)
            for (int x = 0; x < w; ++x) {
                const double d = double(f.at(x, y + 1)) - f.at(x, y);
                iy += d * d;
            }
        for (int x = 0; x < w; ++x) {
            const double d = double(f.at(x, 0)) - f.at(x, h - 1);
            wy += d * d;
        }
        nix += double(h) * (w - 1), nwx += h, niy += double(w) * (h - 1), nwy += w;
    }
    ix /= nix, wx /= nwx, iy /= niy, wy /= nwy;
    WrapTest t;
    const auto ratio = [](double wrap, double inner) {
        return inner > 0 ? wrap / inner : (wrap > 0 ? INFINITY : 1.0);
    };
    t.ratio_x = ratio(wx, ix);
    t.ratio_y = ratio(wy, iy);
    const double unrelated = 2.0 * variance;
    t.periodic = std::abs(wx - ix) < std::abs(wx - unrelated) &&
                 std::abs(wy - iy) < std::abs(wy - unrelated);
    return t;
}

PeriodogramSummary summarize(const Periodogram& p) {
    PeriodogramSummary s;
    const int w = p.width, h = p.height;
    double total = 0, kw = 0, mxx = 0, myy = 0, mxy = 0, best = -1;
    for (int ky = 0; ky < h; ++ky) {
        const double fy = Periodogram::frequency(ky, h);
        for (int kx = 0; kx < w; ++kx) {
            const double fx = Periodogram::frequency(kx, w);
            const double v = p.power[size_t(ky) * w + kx];
            total += v;
            kw += v * std::hypot(fx, fy);
            mxx += v * fx * fx, myy += v * fy * fy, mxy += v * fx * fy;
            if (v > best) {
                best = v;
                // one member of the conjugate pair, canonically the one with fx > 0 (or fy > 0)
                const bool flip = fx < 0 || (fx == 0 && fy < 0);
                s.peak_fx = (flip ? -fx : fx) + 0.0, s.peak_fy = (flip ? -fy : fy) + 0.0;
                s.peak_power = v;
            }
        }
    }
    s.total_power = total / (double(w) * h);
    if (total > 0) {
        s.centroid = kw / total;
        mxx /= total, myy /= total, mxy /= total;
        const double tr = mxx + myy, det = mxx * myy - mxy * mxy;
        const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
        const double l1 = 0.5 * tr + disc, l2 = 0.5 * tr - disc;
        s.anisotropy = l1 > 0 ? 1.0 - l2 / l1 : 0.0;
        s.orientation_deg = 0.5 * std::atan2(2 * mxy, mxx - myy) * 180.0 / std::numbers::pi;
    }
    // Centred (fftshift) block averages of the power for the report's heat map.
    const int bx = (w + kHeatCells - 1) / kHeatCells, by = (h + kHeatCells - 1) / kHeatCells;
    s.heat_width = (w + bx - 1) / bx;
    s.heat_height = (h + by - 1) / by;
    std::vector<double> sum(size_t(s.heat_width) * s.heat_height, 0.0);
    std::vector<int> cnt(sum.size(), 0);
    for (int r = 0; r < h; ++r) {
        const int ky = (r - h / 2 + h) % h;
        for (int c = 0; c < w; ++c) {
            const int kx = (c - w / 2 + w) % w;
            const size_t cell = size_t(r / by) * s.heat_width + c / bx;
            sum[cell] += p.power[size_t(ky) * w + kx];
            ++cnt[cell];
        }
    }
    s.heat.resize(sum.size());
    for (size_t i = 0; i < sum.size(); ++i)
        s.heat[i] = sum[i] > 0 ? std::log10(sum[i] / cnt[i]) : NAN;
    return s;
}

/// Radial autocovariance of one frame out to max_lag. A periodic frame uses the circular sample
/// autocovariance as it is; otherwise the mean-removed frame is zero-padded to twice its size so
/// the circular product has no wrapped pairs, and each lag is divided by its number of overlapping
/// pixel pairs (the unbiased-lag estimator), then averaged in the same rings.
std::vector<double> frame_autocovariance(const Image& f, bool periodic, int max_lag) {
    if (periodic) {
        return radial_autocovariance(autocovariance(f), f.width, f.height,
                                               max_lag);
    }
    const int w = f.width, h = f.height, pw = 2 * w, ph = 2 * h;
    double sum = 0;
    for (float v : f.data) sum += v;
    const double mean = sum / double(f.data.size());
    Image padded;
    padded.width = pw;
    padded.height = ph;
    padded.data.assign(size_t(pw) * ph, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            padded.data[size_t(y) * pw + x] = static_cast<float>(f.at(x, y) - mean);
    std::vector<double> acov = autocovariance(padded);
    const double n_pad = double(pw) * ph;
    for (int y = 0; y < ph; ++y) {
        const int dy = std::abs(y < ph / 2 ? y : y - ph);
        for (int x = 0; x < pw; ++x) {
            const int dx = std::abs(x < pw / 2 ? x : x - pw);
            double& v = acov[size_t(y) * pw + x];
            v = (dx < w && dy < h) ? v * n_pad / (double(w - dx) * (h - dy)) : 0.0;
        }
    }
    return radial_autocovariance(acov, pw, ph, max_lag);
}

/// Residuals of y from its least-squares line over the index: what varies from frame to frame
/// once a slow drift (the thing the stationarity tests look for) is taken out.
std::vector<double> detrended(const std::vector<double>& y) {
    const size_t n = y.size();
    const double xm = 0.5 * double(n - 1);
    double ym = 0;
    for (double v : y) ym += v;
    ym /= double(n);
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < n; ++i) {
        sxx += (double(i) - xm) * (double(i) - xm);
        sxy += (double(i) - xm) * (y[i] - ym);
    }
    const double b = sxx > 0 ? sxy / sxx : 0.0;
    std::vector<double> r(n);
    for (size_t i = 0; i < n; ++i) r[i] = y[i] - ym - b * (double(i) - xm);
    return r;
}

/// Integrated autocorrelation time tau = 1 + 2 sum_{l>=1} rho(l) of one or more series of equal
/// length, pooled, by Geyer's initial positive sequence estimator (Geyer 1992, Statistical
/// Science 7(4) §3.3): sums of adjacent pairs rho(2m) + rho(2m+1) are added while positive and
/// kept non-increasing, which follows long, small tails that a fixed window cuts off. Each
/// series is detrended first, so a drift does not read as correlation. A constant series counts
/// as fully correlated (tau = n).
struct Tau {
    double tau = 1.0;
    bool converged = true;  ///< false: still correlated at half the series length
};
Tau integrated_time(const std::vector<std::vector<double>>& series, bool detrend = true) {
    Tau t;
    if (series.empty() || series.front().size() < 4) return t;
    const size_t n = series.front().size();
    std::vector<std::vector<double>> dev;
    for (const auto& s : series) {
        dev.push_back(detrend ? detrended(s) : s);
        if (!detrend) {
            double mean = 0;
            for (double v : s) mean += v / double(s.size());
            for (double& v : dev.back()) v -= mean;
        }
    }
    double g0 = 0;
    for (const auto& d : dev)
        for (double v : d) g0 += v * v;
    g0 /= double(dev.size() * n);
    if (!(g0 > 1e-300)) return {double(n), true};
    const auto rho = [&](size_t l) {
        if (l == 0) return 1.0;
        double g = 0;
        for (const auto& d : dev)
            for (size_t i = 0; i + l < n; ++i) g += d[i] * d[i + l];
        return g / double(dev.size() * (n - l)) / g0;
    };
    double sum = 0, previous = INFINITY;
    t.converged = false;
    for (size_t m = 0; 2 * m + 1 < n / 2; ++m) {
        double pair = rho(2 * m) + rho(2 * m + 1);
        if (pair <= 0) {
            t.converged = true;
            break;
        }
        pair = std::min(pair, previous);
        previous = pair;
        sum += pair;
    }
    t.tau = std::clamp(-1.0 + 2.0 * sum, 1.0, double(n));
    return t;
}

/// Relative variance per frame of the level all annuli share (SpectrumTheory::common), estimated
/// from the frames when there is no theory, with the number of frames per independent one of
/// that level. The level m_j = mean over the annuli H with at least 64 bins of log P_b(j) (a
/// common factor adds in logs; Var log P_b = 1 / pairs for many pairs) varies by c plus the
/// annuli's own scatter, mean_H (inflation / pairs_b) / |H|, which is subtracted. Each annulus's
/// linear trend in log power is removed first: a drift of the spectrum's shape (a zoom shifts log
/// S smoothly) must not read as a fluctuating level, and the trend test measures the level's.
struct CommonLevel {
    double variance = 0.0;
    double tau = 1.0;
};
CommonLevel common_level(const std::vector<std::vector<double>>& profiles,
                         const RadialProfile& mean, double inflation) {
    CommonLevel c;
    if (profiles.size() < 4) return c;
    double scatter = 0;
    std::vector<size_t> H;
    for (size_t b = 0; b < mean.power.size(); ++b)
        if (mean.count[b] >= 64 && mean.frequency[b] > 0 && mean.frequency[b] < 0.5 &&
            mean.power[b] > 0) {
            H.push_back(b);
            scatter += inflation / (0.5 * double(mean.count[b]));
        }
    if (H.empty()) return c;
    const double nh = double(H.size());
    scatter /= nh * nh;
    std::vector<double> level(profiles.size(), 0.0), series(profiles.size());
    for (size_t b : H) {
        for (size_t j = 0; j < profiles.size(); ++j)
            series[j] = std::log(std::max(profiles[j][b], 1e-300 * mean.power[b]) / mean.power[b]);
        const std::vector<double> d = detrended(series);
        for (size_t j = 0; j < profiles.size(); ++j) level[j] += d[j] / nh;
    }
    double ss = 0;
    for (double v : level) ss += v * v;
    c.variance = std::max(0.0, ss / double(level.size() - 2) - scatter);
    c.tau = integrated_time({level}).tau;
    return c;
}


/// Power at which the verdict states the drift it could see.
constexpr double kPower = 0.8;

/// The covariance of the per-frame variance when the frames are stationary: C(l) = variance
/// rho(l), with the degrees of freedom of `variance` (infinity when it is the scene's).
struct LevelModel {
    double variance = 0.0;
    std::vector<double> rho;
    double dof = INFINITY;
    std::string source;
};

/// sum_l>=1 rho(l)^2 over the lags: n / (1 + 2 that) is the effective number of frames behind an
/// estimate of the series' variance.
double variance_dof(size_t n, const std::vector<double>& rho) {
    double s = 1.0;
    for (size_t l = 1; l < rho.size() && l < n; ++l) s += 2.0 * rho[l] * rho[l];
    return std::max(2.0, double(n) / s);
}

/// The series' variance from differences at the lag L where rho first drops to 1/2:
/// E[(v_{j+L} - v_j)^2] = 2 variance (1 - rho(L)). A slow drift of the level adds little at that
/// lag, so it does not hide itself by inflating the variance as the scatter about a line does.
double variance_from_differences(const std::vector<double>& v, const std::vector<double>& rho) {
    const size_t n = v.size();
    size_t L = 1;
    while (L + 1 < n / 4 && L < rho.size() && rho[L] > 0.5) ++L;
    const double r = L < rho.size() ? rho[L] : 0.0;
    double s = 0.0;
    for (size_t j = 0; j + L < n; ++j) s += (v[j + L] - v[j]) * (v[j + L] - v[j]);
    return s / (double(n - L) * 2.0 * std::max(1.0 - r, 1e-3));
}

/// The scene's when its theory holds (the covariance of the frame variances in time, both parts
/// through the window: TheoryComparison::frame_variance_covariance); its envelopes with the
/// variance from the frames when the scene is keyframed (the slower of the two correlations);
/// otherwise an AR(1) correlation with the frames' integrated time and the variance about a line.
LevelModel level_model(const std::vector<double>& v, const TimeCorrelation& tc,
                       const TheoryComparison* theory) {
    const size_t n = v.size();
    LevelModel m;
    if (theory && theory->frame_variance_covariance.size() >= n &&
        theory->frame_variance_covariance[0] > 0) {
        const std::vector<double>& cov = theory->frame_variance_covariance;
        m.variance = cov[0];
        m.rho.resize(n);
        for (size_t l = 0; l < n; ++l) m.rho[l] = cov[l] / cov[0];
        m.source = "scene theory";
        return m;
    }
    if (!tc.r2.empty()) {
        m.rho.resize(n);
        for (size_t l = 0; l < n; ++l) m.rho[l] = std::max(tc.r2[l], tc.r4[l]);
        m.variance = variance_from_differences(v, m.rho);
        m.dof = variance_dof(n, m.rho);
        m.source = "scene correlation, variance from the frames";
        return m;
    }
    // Not detrended: removing a line takes the slow part of the correlation with it, and the
    // AR(1) then underestimates the slope's error (2 of 24 still seeds were called drifting).
    const double tau = integrated_time({v}, false).tau;
    const double phi = (tau - 1.0) / (tau + 1.0);  // tau = (1 + phi) / (1 - phi)
    m.rho.assign(1, 1.0);
    while (m.rho.size() < n && m.rho.back() * phi > 1e-6) m.rho.push_back(m.rho.back() * phi);
    m.variance = variance_from_differences(v, m.rho);
    m.dof = variance_dof(n, m.rho);
    m.source = "estimated from the frames (AR(1) with their integrated time)";
    return m;
}

// Structure function at dyadic lags up to a quarter of the smaller side, H(s) pooled over the
// frames (Kaplan & Kuo eq. 21).
StructureSummary structure_of(std::span<const Image> frames) {
    const int quarter = std::min(frames.front().width, frames.front().height) / 4;
    int max_s = 0;
    while ((4 << max_s) <= quarter) ++max_s;  // lags up to 2^{max_s + 1} <= quarter
    StructureAccumulator acc(max_s);
    for (const Image& f : frames) acc.add(f);
    return acc.summary();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

namespace {

void check_frames(const std::vector<Image>& frames, const AnalyzeOptions& opt,
                  long long first_frame) {
    if (frames.empty()) throw ValueError(opt.input + ": no frames to analyse");
    const int w = frames.front().width, h = frames.front().height;
    if (w < kMinSize || h < kMinSize)
        throw ValueError(opt.input + ": frames are " + std::to_string(w) + "x" + std::to_string(h) +
                         ": analysis needs at least " + std::to_string(kMinSize) + "x" +
                         std::to_string(kMinSize) + " pixels");
    for (size_t j = 0; j < frames.size(); ++j) {
        const Image& f = frames[j];
        if (f.width != w || f.height != h || f.data.size() != size_t(w) * h)
            throw ValueError(opt.input + ": frame " + std::to_string(first_frame + long(j)) +
                             " is " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                             ", the first is " + std::to_string(w) + "x" + std::to_string(h));
        size_t bad = 0;
        for (float v : f.data) bad += !std::isfinite(v);
        if (bad)
            throw ValueError(opt.input + ": frame " + std::to_string(first_frame + long(j)) +
                             " has " + std::to_string(bad) +
                             " non-finite values (NaN or infinity)");
    }
}

/// Display values in [0, 1] mapped back to the field values [lo, hi] they stand for.
struct DisplayMapping {
    bool mapped = false;
    double lo = 0, hi = 1;
    double clipped = 0;  ///< share of the values at 0 or 1
};
DisplayMapping map_display_values(std::vector<Image>& frames, const ClosedForm& theory) {
    DisplayMapping m;
    std::tie(m.lo, m.hi) = theory.display_range();
    m.mapped = true;
    size_t at_edge = 0, count = 0;
    for (Image& f : frames) {
        count += f.data.size();
        for (float& v : f.data) {
            at_edge += (v <= 0.0f || v >= 1.0f);
            v = static_cast<float>(m.lo + double(v) * (m.hi - m.lo));
        }
    }
    m.clipped = double(at_edge) / double(count);
    return m;
}

/// One-point statistics of all pixels of all frames.
void measure_one_point(const std::vector<Image>& frames, AnalysisResult& R) {
    std::vector<float> pooled;
    std::span<const float> all(frames.front().data);
    if (frames.size() > 1) {
        pooled.reserve(frames.size() * frames.front().data.size());
        for (const Image& f : frames) pooled.insert(pooled.end(), f.data.begin(), f.data.end());
        all = pooled;
    }
    R.moments = moments(all);
    const double sd = std::sqrt(R.moments.variance);
    const double half = sd > 0 ? kHistogramHalfWidthSd * sd : 0.5;
    R.histogram = histogram(all, R.moments.mean - half, R.moments.mean + half, kHistogramBins);
}

/// The frame-averaged periodogram (summed in frame order, then scaled: the bits of average) and
/// the radial autocovariance out to min(w, h) / 4; returns each frame's radial profile, kept for
/// the correlation time. Periodicity decides the window: none for torus frames, Hann otherwise.
std::vector<std::vector<double>> measure_spectra(const std::vector<Image>& frames,
                                                 const WrapTest& wt, AnalysisResult& R) {
    const size_t n = frames.size();
    const Window window = wt.periodic ? Window::None : Window::Hann;
    Periodogram avg;
    std::vector<std::vector<double>> frame_profiles;
    for (size_t j = 0; j < n; ++j) {
        Periodogram p = periodogram(frames[j], window);
        if (n > 1) frame_profiles.push_back(radial_average(p).power);
        if (j == 0) {
            avg.width = p.width;
            avg.height = p.height;
            avg.power.assign(p.power.size(), 0.0);
        }
        for (size_t i = 0; i < p.power.size(); ++i) avg.power[i] += p.power[i];
    }
    const double inv = 1.0 / double(n);
    for (double& v : avg.power) v *= inv;
    R.spectrum = radial_average(avg);
    R.periodogram = summarize(avg);
    R.periodogram.window = wt.periodic ? "none" : "hann";
    R.periodogram.periodic = wt.periodic;
    R.periodogram.wrap_ratio_x = wt.ratio_x;
    R.periodogram.wrap_ratio_y = wt.ratio_y;

    R.max_lag = std::min(R.width, R.height) / 4;
    R.autocovariance.assign(size_t(R.max_lag) + 1, 0.0);
    for (const Image& f : frames) {
        const auto a = frame_autocovariance(f, wt.periodic, R.max_lag);
        for (size_t r = 0; r < a.size(); ++r) R.autocovariance[r] += a[r];
    }
    for (double& v : R.autocovariance) v *= inv;
    return frame_profiles;
}

/// Correlation between frames estimated from the frames themselves (10 or more): the integrated
/// times of the frame means, variances and relative annulus powers.
TimeCorrelation time_correlation_from_frames(
    const AnalysisResult& R, const std::vector<std::vector<double>>& frame_profiles) {
    const size_t n = R.frame_stats.size(), quarter = n / 4;
    std::vector<double> means(n), vars(n);
    for (size_t j = 0; j < n; ++j)
        means[j] = R.frame_stats[j].mean, vars[j] = R.frame_stats[j].variance;
    std::vector<std::vector<double>> rel;
    for (size_t b = 0; b < R.spectrum.power.size(); ++b) {
        if (R.spectrum.count[b] == 0 ||
            !(R.spectrum.frequency[b] > 0 && R.spectrum.frequency[b] < 0.5) ||
            !(R.spectrum.power[b] > 0))
            continue;
        std::vector<double> s(n);
        for (size_t j = 0; j < n; ++j) s[j] = frame_profiles[j][b] / R.spectrum.power[b];
        rel.push_back(std::move(s));
    }
    const Tau tm = integrated_time({means}), tv = integrated_time({vars});
    const Tau ts = integrated_time(rel);
    TimeCorrelation tc;
    tc.source = "frames";
    tc.n_eff_mean = std::max(1.0, double(n) / tm.tau);
    tc.n_eff_variance = std::max(1.0, double(n) / tv.tau);
    tc.n_eff_spectrum = std::max(1.0, double(n) / ts.tau);
    tc.q_eff = std::max(1.0, double(quarter) / ts.tau);
    tc.n_eff_population = tc.n_eff_spectrum;
    tc.q_eff_population = tc.q_eff;
    tc.converged = tm.converged && tv.converged && ts.converged;
    return tc;
}

/// Records tc in R (as frames per independent one) with notes on how far to trust it.
void record_time_correlation(const TimeCorrelation& tc, AnalysisResult& R) {
    const double n = double(R.frames);
    R.tau_source = tc.source;
    R.tau_mean = n / tc.n_eff_mean;
    R.tau_variance = n / tc.n_eff_variance;
    R.tau_spectrum = n / tc.n_eff_spectrum;
    if (tc.source == "frames" && n / std::max(1.0, R.tau_spectrum) < 20)
        R.notes.push_back("the frames hold only about " +
                          format_number(n / std::max(1.0, R.tau_spectrum), 2) +
                          " independent ones: the correlation time and the common level of the "
                          "spectrum are rough estimates and the drift z may be off by tens of "
                          "percent; give --scene for the exact correlation of an animated scene");
    if (!tc.converged)
        R.notes.push_back(
            "frames are correlated over more than half of the sequence: the "
            "correlation time is a lower bound and the z values are approximate");
}

/// The spectral drift between the first and last quarter of the frames, its z corrected for
/// correlated frames and for the level common to all annuli. spectral_drift's variance,
/// 2 P^2 / (pairs q), assumes independent frames and bins. A quarter of q correlated frames is
/// worth q_eff, and the impulse population adds a level common to all annuli (relative variance
/// c per frame, c / q_eff_population per quarter):
///     z_corrected = z sqrt((1 / (pairs q)) / (1 / (pairs q_eff) + c_q)).
/// The common level's drift is what the trend test on the frame variance measures.
void spectral_drift_test(const std::vector<Image>& frames, const WrapTest& wt,
                         const std::vector<std::vector<double>>& frame_profiles,
                         const TimeCorrelation& tc, const AnalysisResult& R, Stationarity& st) {
    const size_t quarter = frames.size() / 4;
    const std::span<const Image> all(frames);
    st.drift = spectral_drift(all.first(quarter), all.last(quarter),
                              wt.periodic ? Window::None : Window::Hann);
    st.q_eff = tc.q_eff;
    std::vector<double> pairs, common;
    for (size_t b = 0; b < R.spectrum.power.size(); ++b) {
        if (R.spectrum.count[b] == 0 ||
            !(R.spectrum.frequency[b] > 0 && R.spectrum.frequency[b] < 0.5))
            continue;
        pairs.push_back(0.5 * double(R.spectrum.count[b]));
        common.push_back(R.theory && R.theory->spectrum ? R.theory->spectrum->common[b] : NAN);
    }
    double c_data = NAN, q_eff_level = tc.q_eff_population;
    if (!(R.theory && R.theory->spectrum)) {
        const CommonLevel cl =
            common_level(frame_profiles, R.spectrum, wt.periodic ? 1.0 : kHannInflation);
        c_data = cl.variance;
        q_eff_level = std::clamp(double(quarter) / cl.tau, 1.0, double(quarter));
    }
    st.common_variance = 0;
    st.z_corrected.resize(st.drift.z.size());
    for (size_t i = 0; i < st.drift.z.size(); ++i) {
        const double pr = i < pairs.size() ? pairs[i] : 1.0;
        const double c = std::isfinite(c_data) ? c_data : (i < common.size() ? common[i] : 0.0);
        const double cq = c / q_eff_level;
        st.common_variance = std::max(st.common_variance, cq);
        st.z_corrected[i] = st.drift.z[i] * std::sqrt((1.0 / (pr * double(quarter))) /
                                                      (1.0 / (pr * tc.q_eff) + cq));
        st.max_abs_z_corrected = std::max(st.max_abs_z_corrected, std::abs(st.z_corrected[i]));
    }
}

/// Stationarity over time: three tests share the family's false-alarm rate (Bonferroni, so the
/// verdict's rate is at most kFamilyAlpha): the level's trend, its block means and the spectral
/// drift.
Stationarity stationarity_verdict(const std::vector<Image>& frames, const WrapTest& wt,
                                  const std::vector<std::vector<double>>& frame_profiles,
                                  const TimeCorrelation& tc, const AnalysisResult& R,
                                  double drift_of_interest) {
    const size_t n = frames.size();
    Stationarity st;
    st.trend_blocks = kTrendBlocks;
    st.t_limit = kZLimit;
    if (n < size_t(kMinFramesForTime)) {
        st.available = false;
        st.reason = n == 1 ? "one frame"
                           : "needs >= " + std::to_string(kMinFramesForTime) + " frames (" +
                                 std::to_string(n) + " given)";
        return st;
    }
    st.available = true;
    std::vector<double> vars(n);
    for (size_t j = 0; j < n; ++j) vars[j] = R.frame_stats[j].variance;
    st.trend = trend(vars, kTrendBlocks);
    st.quarter = static_cast<int>(n / 4);
    spectral_drift_test(frames, wt, frame_profiles, tc, R, st);
    const double alpha = kFamilyAlpha / 3.0;
    st.family_alpha = kFamilyAlpha;
    st.z_threshold = bonferroni_threshold(static_cast<int>(st.drift.z.size()), alpha);
    const LevelModel lm = level_model(vars, tc, R.theory ? &*R.theory : nullptr);
    st.level_model = lm.source;
    st.level_covariance.resize(lm.rho.size());
    for (size_t l = 0; l < lm.rho.size(); ++l) st.level_covariance[l] = lm.variance * lm.rho[l];
    st.power = kPower;
    st.level = level_drift(vars, lm.variance, lm.rho, kTrendBlocks, lm.dof, alpha, kPower);
    st.level_z_limit = bonferroni_threshold(1, alpha);
    st.blocks_z_limit = -numeric::normal_quantile_lower(alpha);
    st.drift_of_interest = drift_of_interest;
    st.detectable_drift = st.level.detectable_change / std::abs(st.level.mean);
    const double level = R.theory ? R.theory->expected_frame_variance : st.level.mean;
    st.block_dof = 2.0 * level * level / st.level.block_mean_variance;
    st.min_block_dof = kMinBlockDof;
    const bool level_valid = st.block_dof >= kMinBlockDof;
    if (!level_valid)
        st.level_note = "level tests not applied: a block mean of the frame variance is worth " +
                        format_number(st.block_dof, 3) + " degrees of freedom (< " +
                        format_number(kMinBlockDof, 3) +
                        "; few impulses or few kernel widths in the window): too far from normal "
                        "for their z";
    const bool level_rejects = std::abs(st.level.z_trend) >= st.level_z_limit ||
                               st.level.z_blocks >= st.blocks_z_limit;
    const bool rejects =
        (level_valid && level_rejects) || st.max_abs_z_corrected >= st.z_threshold;
    st.verdict = rejects ? "not stationary"
                 : level_valid && st.detectable_drift <= drift_of_interest ? "stationary"
                                                                           : "inconclusive";
    st.stationary = st.verdict == "stationary";
    return st;
}

/// The closed-form comparison, when the theory covers these frames (a sum of layers, nothing
/// keyframed); notes where it does not.
void compare_with(const ClosedForm* theory, bool sum_of_layers, const TimeCorrelation& tc,
                  const DisplayMapping& dm, AnalysisResult& R) {
    if (theory && !sum_of_layers) R.notes.push_back(theory->not_covered());
    const bool keyframed = theory && theory->keyframed();
    if (keyframed)
        R.notes.push_back(
            "layer parameters of the scene are keyframed: the statistics vary in time, so there "
            "is no comparison with the (stationary) theory");
    if (!sum_of_layers || keyframed) return;
    R.theory = theory->compare(R, tc, dm.mapped, dm.lo, dm.hi, dm.clipped);
    if (dm.mapped && dm.clipped > 0.001)
        R.notes.push_back("display input: " + format_number(dm.clipped * 100.0, 3) +
                          " % of pixels at the ends of the range; theory assumes a Gaussian "
                          "marginal censored there");
}

/// The results only asked for: the structure function and the per-pixel variance map.
void optional_results(const std::vector<Image>& frames, const AnalyzeOptions& opt,
                      AnalysisResult& R) {
    if (opt.structure) R.structure = structure_of(frames);
    if (!opt.variance_map.empty()) {
        if (frames.size() < 2)
            throw ValueError("--variance-map " + opt.variance_map +
                             ": needs a sequence of at least 2 frames (realizations)");
        PixelVariance pv;
        for (const Image& f : frames) pv.add(f);
        R.variance_map = pv.variance();
    }
}

}  // namespace

AnalysisResult analyze_frames(std::vector<Image> frames, const AnalyzeOptions& opt,
                              const std::string& kind, bool raw, int bits, long long first_frame,
                              const ClosedForm* theory) {
    check_frames(frames, opt, first_frame);
    if (!opt.scene.empty() && !theory)
        throw std::logic_error("analyze_frames: --scene " + opt.scene + " without its closed form");
    if (opt.scene.empty() && !opt.sets.empty())
        throw ValueError("--set " + opt.sets.front() + ": needs --scene");
    AnalysisResult R;
    R.input = opt.input;
    R.kind = kind;
    R.raw = raw;
    R.bits = bits;
    R.width = frames.front().width;
    R.height = frames.front().height;
    R.frames = static_cast<int>(frames.size());
    R.first_frame = first_frame;
    const size_t n = frames.size();

    // Scene first: a display input is mapped back to field values before anything is measured.
    DisplayMapping dm;
    if (theory) {
        for (const auto& wmsg : theory->warnings()) R.notes.push_back(wmsg);
        if (!raw) dm = map_display_values(frames, *theory);
    }
    // The closed forms (spectra, correlation in time, fourth cumulants) are those of a sum of
    // layers; a scene that composes them otherwise is measured without them.
    const bool sum_of_layers = theory && theory->sum_of_layers();

    measure_one_point(frames, R);
    const WrapTest wt = wrap_test(frames, R.moments.variance);
    const auto frame_profiles = measure_spectra(frames, wt, R);
    R.frame_stats = frame_stats(frames);

    // Correlation between frames: how many independent frames the averages are worth. From the
    // scene's envelopes when there is one; else estimated from the frames (10 or more); else
    // none are assumed independent.
    TimeCorrelation tc;
    if (sum_of_layers && n > 1)
        tc = theory->time_correlation(n, n / 4);
    else if (n >= size_t(kMinFramesForTime))
        tc = time_correlation_from_frames(R, frame_profiles);
    record_time_correlation(tc, R);
    compare_with(theory, sum_of_layers, tc, dm, R);
    R.stationarity = stationarity_verdict(frames, wt, frame_profiles, tc, R, opt.drift);
    if (!raw && !dm.mapped)
        R.notes.push_back(
            "display values in [0, 1] (8/16-bit source); give --scene to map them "
            "back to field values and compare with theory");
    if (kind == "video")
        R.notes.push_back("video: lossy compression alters the fine-scale spectrum and adds noise");
    optional_results(frames, opt, R);
    return R;
}

}  // namespace impulse::analysis
