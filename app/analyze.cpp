// SPDX-License-Identifier: Apache-2.0
// `impulse analyze`: read frames, measure them with the analysis estimators, and compare the
// measurements with the closed-form theory of a scene (Campbell's theorem, design.md §1) with
// tolerances derived from each estimator's sampling error (design.md §5).

#include "app/analyze.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <span>
#include <sstream>

#include "app/commands.h"
#include "kernels/kernels.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"
#include "numeric/errors.h"
#include "numeric/gaussian.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;
using analysis::Image;

constexpr int kHistogramBins = 64;
constexpr double kHistogramHalfWidthSd = 4.0;
constexpr double kFamilyAlpha = 0.01;  ///< family-wise false-alarm rate of the max|z| tests
constexpr double kZLimit = 4.0;        ///< |z| limit for mean, variance and the trend t
constexpr int kTrendBlocks = 10;
constexpr int kMinFramesForTime = 10;  ///< fewer frames: no stationarity test, n_eff = 1
constexpr int kMinSize = 8;
constexpr int kHeatCells = 64;
constexpr double kMaxClippedForSpectrum = 1e-4;  ///< display inputs: judge the spectrum below it
/// Variance inflation of an average of Hann-windowed periodogram bins: the DFT-even Hann window
/// makes neighbouring bins correlate with coefficients (1, -2/3, 1/6) per axis, so a sum of bins
/// has sum rho^2 = 35/18 times the variance per axis (Percival & Walden 1993 ch. 6). Using the
/// 2-D product is conservative for one-bin-wide annuli (radial neighbours fall outside).
constexpr double kHannInflation = (35.0 / 18.0) * (35.0 / 18.0);

std::string format_number(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

/// z with P(Z > z) = p, 0 < p < 0.5.
double normal_upper_quantile(double p) { return -numeric::normal_quantile_lower(p); }

/// Two-sided Bonferroni threshold for the maximum of m |z| values at family-wise level alpha.
double bonferroni_threshold(int m, double alpha) {
    return normal_upper_quantile(alpha / (2.0 * std::max(1, m)));
}

/// Wilson–Hilferty normal deviate of r = X / E[X] for X ~ Gamma(shape): nearly exact for the
/// mean of `shape` independent exponentials, which is what an annulus mean of periodogram bins is
/// (Wilson & Hilferty 1931; for large shape it is (r - 1) sqrt(shape)).
double wilson_hilferty_z(double ratio, double shape) {
    const double v = 1.0 / (9.0 * shape);
    return (std::cbrt(std::max(ratio, 0.0)) - (1.0 - v)) / std::sqrt(v);
}

// ---------------------------------------------------------------------------------------------
// Reading the input

struct Loaded {
    std::vector<Image> frames;
    std::string kind;
    bool raw = true;
    int bits = 32;
    long long first = 0;
};

Image to_image(render::Frame&& f) {
    Image im;
    im.width = f.width;
    im.height = f.height;
    im.data = std::move(f.data);
    return im;
}

std::string unknown_type_message(const std::string& path) {
    const std::string ext = fs::path(path).extension().string();
    return path + ": unknown input type" + (ext.empty() ? std::string() : " \"" + ext + "\"") +
           ": expected an image in a format OpenImageIO reads (.exr .hdr .png .tif .jpg ...), a "
           "sequence pattern (frame_####.exr, frame_%04d.png) or a video (.mp4 .mov .mkv .webm)";
}

Image read_frame(const std::string& path) {
    try {
        return to_image(output::read_image(path));
    } catch (const IoError& e) {
        throw IoError(one_line(e.what()));
    }
}

output::ImageInfo probe(const std::string& path) {
    try {
        return output::probe_image(path);
    } catch (const IoError& e) {
        throw IoError(one_line(e.what()));
    }
}

Loaded load_input(const AnalyzeOptions& opt) {
    const std::string& in = opt.input;
    if (in.empty()) throw ValueError("analyze: no input given");
    const long long cap = opt.max_frames > 0 ? opt.max_frames : LLONG_MAX;
    if (opt.max_frames < 0)
        throw ValueError("--max-frames " + std::to_string(opt.max_frames) + ": must be >= 1");
    long long a = 0, b = LLONG_MAX;
    const bool ranged = !opt.frames.empty();
    if (ranged) std::tie(a, b) = parse_frame_range(opt.frames, LLONG_MAX);
    Loaded L;
    L.first = a;
    std::error_code ec;

    if (output::is_video_path(in)) {
        if (!fs::exists(in, ec)) throw IoError(in + ": no such file");
        output::quiet_video_logs();
        int w = 0, h = 0;
        std::vector<std::vector<float>> luma;
        try {
            luma = output::decode_video_luma(in, w, h);
        } catch (const IoError& e) {
            throw IoError(one_line(e.what()));
        }
        const long long n = static_cast<long long>(luma.size());
        if (n == 0) throw IoError(in + ": no frames could be decoded");
        if (ranged && b >= n)
            throw ValueError("--frames " + opt.frames + ": outside [0, " + std::to_string(n) +
                             ") (" + in + " has " + std::to_string(n) + " frames)");
        const long long last = std::min(b, n - 1);
        for (long long f = a; f <= last && static_cast<long long>(L.frames.size()) < cap; ++f) {
            Image im;
            im.width = w;
            im.height = h;
            im.data = std::move(luma[static_cast<size_t>(f)]);
            L.frames.push_back(std::move(im));
        }
        L.kind = "video";
        L.raw = false;
        L.bits = 8;
        return L;
    }

    // A sequence rendered with --frames 100-199 starts at 100: without --frames, analyse from
    // the first frame present.
    if (!ranged && !expand_pattern(in, 0).empty() && !fs::exists(expand_pattern(in, 0), ec))
        if (const long long first = first_frame_present(in); first > 0) a = L.first = first;
    const std::string first_name = expand_pattern(in, a);
    if (!first_name.empty()) {
        if (!fs::exists(first_name, ec))
            throw IoError(first_name + ": no such file (frame " + std::to_string(a) + " of " + in +
                          ")");
        if (!output::is_readable_image_path(first_name)) throw ValueError(unknown_type_message(in));
        const output::ImageInfo info = probe(first_name);
        for (long long f = a; f <= b && static_cast<long long>(L.frames.size()) < cap; ++f) {
            const std::string name = expand_pattern(in, f);
            if (!fs::exists(name, ec)) break;  // the sequence ends at the first missing frame
            L.frames.push_back(read_frame(name));
            const Image& im = L.frames.back();
            if (im.width != L.frames.front().width || im.height != L.frames.front().height)
                throw ValueError(name + ": frame is " + std::to_string(im.width) + "x" +
                                 std::to_string(im.height) + ", " + first_name + " is " +
                                 std::to_string(L.frames.front().width) + "x" +
                                 std::to_string(L.frames.front().height));
        }
        L.kind = "sequence";
        L.raw = info.is_float;
        L.bits = info.bits;
        return L;
    }

    if (!fs::exists(in, ec)) throw IoError(in + ": no such file");
    if (!output::is_readable_image_path(in)) throw ValueError(unknown_type_message(in));
    if (ranged && (a != 0 || b != 0))
        throw ValueError("--frames " + opt.frames + ": " + in + " is one image (frame 0)");
    const output::ImageInfo info = probe(in);
    L.frames.push_back(read_frame(in));
    L.kind = "image";
    L.raw = info.is_float;
    L.bits = info.bits;
    return L;
}

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

PeriodogramSummary summarize(const analysis::Periodogram& p) {
    PeriodogramSummary s;
    const int w = p.width, h = p.height;
    double total = 0, kw = 0, mxx = 0, myy = 0, mxy = 0, best = -1;
    for (int ky = 0; ky < h; ++ky) {
        const double fy = analysis::Periodogram::frequency(ky, h);
        for (int kx = 0; kx < w; ++kx) {
            const double fx = analysis::Periodogram::frequency(kx, w);
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
        return analysis::radial_autocovariance(analysis::autocovariance(f), f.width, f.height,
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
    std::vector<double> acov = analysis::autocovariance(padded);
    const double n_pad = double(pw) * ph;
    for (int y = 0; y < ph; ++y) {
        const int dy = std::abs(y < ph / 2 ? y : y - ph);
        for (int x = 0; x < pw; ++x) {
            const int dx = std::abs(x < pw / 2 ? x : x - pw);
            double& v = acov[size_t(y) * pw + x];
            v = (dx < w && dy < h) ? v * n_pad / (double(w - dx) * (h - dy)) : 0.0;
        }
    }
    return analysis::radial_autocovariance(acov, pw, ph, max_lag);
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
Tau integrated_time(const std::vector<std::vector<double>>& series) {
    Tau t;
    if (series.empty() || series.front().size() < 4) return t;
    const size_t n = series.front().size();
    std::vector<std::vector<double>> dev;
    for (const auto& s : series) dev.push_back(detrended(s));
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
                         const analysis::RadialProfile& mean, double inflation) {
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

/// Effective number of independent frames among n consecutive ones whose statistic has
/// correlation r(l) at a lag of l frames: Var(mean) = (s^2 / n) (1 + 2 sum (1 - l/n) r(l)).
double effective_frames(size_t n, const std::vector<double>& r) {
    double f = 1.0;
    for (size_t l = 1; l < n && l < r.size(); ++l) f += 2.0 * (1.0 - double(l) / double(n)) * r[l];
    return std::clamp(double(n) / f, 1.0, double(n));
}

// ---------------------------------------------------------------------------------------------
// Theory

/// Moments of Y = clamp(Z, a, b) for a standard normal Z: how a display range censors a
/// Gaussian field (8-bit inputs are clipped to [0, 1] at mean +- 3 sd by default).
struct Censored {
    double mean = 0.0, variance = 1.0;
    double gain = 1.0;  ///< P(a < Z < b): the linear gain of the clip (Price's theorem)
};
Censored censored_normal(double a, double b) {
    const double Pa = numeric::normal_cdf(a), Pb = numeric::normal_cdf(b);
    const double pa = numeric::normal_pdf(a), pb = numeric::normal_pdf(b);
    Censored c;
    c.mean = a * Pa + (pa - pb) + b * (1 - Pb);
    const double m2 = a * a * Pa + (Pb - Pa + a * pa - b * pb) + b * b * (1 - Pb);
    c.variance = m2 - c.mean * c.mean;
    c.gain = Pb - Pa;
    return c;
}

/// (1/T) int_0^T w(a)^4 da of an envelope, by the midpoint rule (exact for the Hann envelope,
/// a trigonometric polynomial of degree 8, with more than 8 points).
double envelope_fourth_mean(sim::Envelope e, double T) {
    const int n = 4096;
    double s = 0;
    for (int i = 0; i < n; ++i) {
        const double w = sim::envelope_weight(e, (i + 0.5) * T / n, T);
        s += w * w * w * w;
    }
    return s / n;
}

/// Temporal correlation of a layer without flow at lag dt: int w(a)^p w(a + dt)^p da /
/// int w^2p. p = 1: the field (the time half of the space-time covariance, design.md §1);
/// p = 2: the impulse population's fourth-cumulant term, E[a^4 w^4].
double envelope_correlation(sim::Envelope e, double T, double dt, int p = 1) {
    const int n = 4096;
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
        const double a = (i + 0.5) * T / n;
        const double w = std::pow(sim::envelope_weight(e, a, T), p);
        s += w * std::pow(sim::envelope_weight(e, a + dt, T), p);
        s2 += w * w;
    }
    return s2 > 0 ? s / s2 : 0.0;
}

bool isotropic(const kernels::Kernel& k) {
    return !k.has_carrier() && k.params().aspect == 1.0 && !k.is_grid();
}

/// A layer's spectrum in pixel units tabulated in |k| (cycles per pixel), interpolated with the
/// 4-point Lagrange cubic: exact for cubics, so the quadratic nulls of |H|^2 between side lobes are
/// followed (linear interpolation fills them in and overstates the power there several-fold).
struct RadialTable {
    double step = 0.0;
    std::vector<double> value;  ///< value[i] = S(i * step); one extra node before 0 by symmetry
    double operator()(double rho) const {
        const double x = rho / step;
        const size_t i = static_cast<size_t>(x);
        if (i + 2 >= value.size()) return 0.0;
        const double t = x - double(i);
        const double p0 = i == 0 ? value[1] : value[i - 1];  // S is even in |k|
        const double p1 = value[i], p2 = value[i + 1], p3 = value[i + 2];
        const double v = -t * (t - 1) * (t - 2) / 6 * p0 + (t + 1) * (t - 1) * (t - 2) / 2 * p1 -
                         (t + 1) * t * (t - 2) / 2 * p2 + (t + 1) * t * (t - 1) / 6 * p3;
        return std::max(v, 0.0);
    }
};

struct LayerSpectrum {
    kernels::Kernel kernel;
    double zoom = 1.0;
    double scale = 0.0;  ///< gain^2 lambda E[a^2] (1/T int w^2): S_tex = scale |H|^2
    bool aliasing = false;
    bool fixed_anisotropic = false;  ///< every impulse has the kernel's own, anisotropic shape
    RadialTable table;               ///< angular mean of S in value^2 px^2 at |k| cycles/px
    double far_alias = 0.0;          ///< images m with max(|mx|, |my|) in [2, 8], summed at k = 0
    /// S at (fx, fy) cycles per pixel, exact (orientation and aspect included), no aliasing.
    double exact(double fx, double fy) const {
        return zoom * zoom * scale * kernel.power_spectrum(fx * zoom, fy * zoom);
    }
};

/// Annuli below this index hold too few DFT bins (about 2 pi b) for their mean to stand for the
/// angular average of an anisotropic spectrum: there the bins are evaluated exactly.
constexpr double kExactAnnuli = 16.0;

LayerSpectrum layer_spectrum(const scenes::LayerConfig& layer, double zoom, int n_max) {
    LayerSpectrum L{kernels::Kernel(layer.kernel), zoom, 0.0, false, false, {}, 0.0};
    const kernels::Kernel& k = L.kernel;
    L.scale = scenes::layer_theory(layer).variance / k.integral_sq();
    const double R_px = k.radius() * zoom;
    const bool iso = isotropic(k);
    // A random orientation per impulse averages the spectrum over angle: then the angular mean is
    // the spectrum. Flow- or vorticity-driven orientations are approximated by it too.
    L.fixed_anisotropic = !iso && layer.process.orientation == sim::OrientationMode::Fixed;
    // S_px(rho) = zoom^2 S_tex(rho zoom): a pixel is 1/zoom texture units (docs/scenes.md).
    // Anisotropic kernels: the angular mean over 36 directions of Kernel::power_spectrum (the
    // average Kernel::radial_power_spectrum takes over 180, which costs five times as much for
    // a table whose points are 1/8 of an oscillation apart anyway).
    const auto S = [&](double rho) {
        const int n = 36;
        if (iso) return zoom * zoom * L.scale * k.radial_power_spectrum(rho * zoom);
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            const double a = std::numbers::pi * (i + 0.5) / n;
            sum += L.exact(rho * std::cos(a), rho * std::sin(a));
        }
        return sum / n;
    };
    // Pixel sampling aliases frequencies beyond Nyquist onto the grid; the nearest images
    // (|m| <= 1 per axis) are added where the spectrum at Nyquist is not negligible.
    L.aliasing = iso || S(0.5) > 1e-7 * L.scale * k.integral_sq();
    const double rho_max = (L.aliasing ? 1.0 : 0.0) + 0.5 * std::numbers::sqrt2 + 0.01;
    // The spectrum of a kernel of radius R oscillates on a scale of about 1/(2R). Isotropic
    // kernels (one quadrature per point) get 64 points per oscillation, enough for the cubic to
    // follow the nulls to well under the sampling error of a 1024^2 frame (checked against
    // rendered frames), but no finer than 1/8 of the DFT bin spacing; the others (36 directions
    // per point) get 4, an approximation near the nulls of the angular mean.
    L.table.step = iso ? std::max(1.0 / (128.0 * std::max(R_px, 0.5)), 1.0 / (8.0 * n_max))
                       : 1.0 / (8.0 * std::max(R_px, 0.5));
    const size_t n = static_cast<size_t>(std::ceil(rho_max / L.table.step)) + 3;
    L.table.value.assign(n, 0.0);
    tbb::parallel_for(size_t(0), n,
                      [&](size_t i) { L.table.value[i] = S(double(i) * L.table.step); });
    if (L.aliasing) {
        // Kernels cut off with a jump (a Gabor or Gaussian truncated at R) have spectra with
        // slow power-law tails whose far images still add up: sum the images with
        // max(|mx|, |my|) in [2, M] once, at k = 0, as a white floor (they vary little across
        // the band). Isotropic: S depends on |m| only, M = 8; otherwise the exact 2-D spectrum
        // at the lattice points, M = 4 (the quadratures get slower as |k| grows). One half-plane
        // is evaluated: S(m) = S(-m).
        const int M = iso ? 8 : 4;
        std::vector<std::pair<int, int>> points;
        for (int my = 0; my <= M; ++my)
            for (int mx = -M; mx <= M; ++mx)
                if (std::max(std::abs(mx), my) >= 2 && (my > 0 || mx > 0) && (!iso || (mx >= my)))
                    points.push_back({mx, my});
        std::vector<double> value(points.size());
        tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
            const auto [mx, my] = points[i];
            const double v = iso ? S(std::hypot(mx, my)) : L.exact(mx, my);
            // multiplicity: the point and its mirror -m; for isotropic kernels also the other
            // members of the 8-fold symmetry class (mx >= my >= 0 listed once)
            int mult = 2;
            if (iso) mult = (my == 0 || mx == my) ? 4 : 8;
            value[i] = mult * v;
        });
        for (double v : value) L.far_alias += v;
    }
    return L;
}

/// The layer's expected periodogram on the DFT grid of a w x h frame (aliasing included).
std::vector<double> layer_grid(const LayerSpectrum& L, int w, int h) {
    std::vector<double> g(size_t(w) * h);
    const int m = L.aliasing ? 1 : 0;
    const int side = std::min(w, h);
    tbb::parallel_for(0, h, [&](int ky) {
        const double fy = analysis::Periodogram::frequency(ky, h);
        for (int kx = 0; kx < w; ++kx) {
            const double fx = analysis::Periodogram::frequency(kx, w);
            double s = 0;
            const bool exact = L.fixed_anisotropic && std::hypot(fx, fy) * side < kExactAnnuli;
            for (int my = -m; my <= m; ++my)
                for (int mx = -m; mx <= m; ++mx)
                    s += (exact && mx == 0 && my == 0) ? L.exact(fx, fy)
                                                       : L.table(std::hypot(fx + mx, fy + my));
            g[size_t(ky) * w + kx] = s + L.far_alias;
        }
    });
    return g;
}

/// Expected value of the Hann-windowed periodogram from the unwindowed one: the DFT-even Hann
/// window's transform has taps (1/2, -1/4, -1/4), so E[P_w(k)] = sum_m c_m^2 S(k - m) / sum c^2,
/// i.e. a circular (1/6, 2/3, 1/6) smoothing along each axis. The DC bin is zero first: the
/// estimator removes the mean, whose bin then leaks nothing.
std::vector<double> hann_smooth(std::vector<double> g, int w, int h) {
    g[0] = 0.0;
    std::vector<double> t(g.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            t[size_t(y) * w + x] =
                (2.0 / 3.0) * g[size_t(y) * w + x] +
                (1.0 / 6.0) * (g[size_t(y) * w + (x + 1) % w] + g[size_t(y) * w + (x + w - 1) % w]);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            g[size_t(y) * w + x] =
                (2.0 / 3.0) * t[size_t(y) * w + x] +
                (1.0 / 6.0) * (t[size_t((y + 1) % h) * w + x] + t[size_t((y + h - 1) % h) * w + x]);
    return g;
}

std::vector<double> annulus_means(std::vector<double> grid, int w, int h) {
    analysis::Periodogram p;
    p.width = w;
    p.height = h;
    p.power = std::move(grid);
    return analysis::radial_average(p).power;
}

/// Radial ring values of the theoretical autocovariance at integer lags 0..max_lag (pixels).
std::vector<double> layer_autocovariance(const LayerSpectrum& L, double zoom, int max_lag) {
    std::vector<double> c(size_t(max_lag) + 1, 0.0);
    const kernels::Kernel& k = L.kernel;
    const bool iso = isotropic(k);
    const double reach = 2.0 * k.radius();  // h * h~ vanishes beyond twice the support radius
    tbb::parallel_for(0, max_lag + 1, [&](int r) {
        const double tau = r / zoom;  // texture units
        if (tau >= reach) return;
        double a = 0;
        if (iso) {
            a = k.autocorrelation(tau, 0.0);
        } else {
            // ring average: mean over 8 directions in [0, pi) (C(tau) = C(-tau))
            const int n = 8;
            for (int j = 0; j < n; ++j) {
                const double t = std::numbers::pi * (j + 0.5) / n;
                a += k.autocorrelation(tau * std::cos(t), tau * std::sin(t)) / n;
            }
        }
        c[size_t(r)] = L.scale * a;
    });
    return c;
}

/// How many independent frames the averages over frames are worth.
struct TimeCorrelation {
    std::string source = "none";  ///< "scene", "frames" or "none" (fewer than 10 frames)
    double n_eff_mean = 1, n_eff_variance = 1, n_eff_spectrum = 1;
    double n_eff_population = 1;  ///< for the impulse-count (fourth-cumulant) fluctuations
    double q_eff = 1, q_eff_population = 1;  ///< the same for each quarter of the drift test
    bool converged = true;
};

/// From the scene: without flow a layer's field at lags of l frames correlates as its envelope,
/// r(l) = (w * w~)(l / fps) / int w^2 (design.md §1; 1 for a still layer), layers weighted by
/// their variance. The frame mean follows r, periodogram bins and the frame variance follow r^2
/// (Gaussian approximation). Advection by a flow moves the pattern without changing the power of
/// a periodic frame and decorrelates the rest sooner, so this is exact or conservative with flows.
TimeCorrelation scene_time_correlation(const scenes::Scene& scene, size_t n, size_t quarter) {
    std::vector<double> r(n, 0.0), r4(n, 0.0);
    double total = 0, total4 = 0;
    for (const auto& layer : scene.layers) {
        const double v = scenes::layer_theory(layer).variance;
        total += v;
        total4 += v * v;
        const auto& p = layer.process;
        for (size_t l = 0; l < n; ++l) {
            const double dt = double(l) / scene.output.fps;
            const bool moving = p.lifetime_s > 0;
            r[l] += v * (moving ? envelope_correlation(p.envelope, p.lifetime_s, dt) : 1.0);
            r4[l] += v * v * (moving ? envelope_correlation(p.envelope, p.lifetime_s, dt, 2) : 1.0);
        }
    }
    for (size_t l = 0; l < n; ++l) {
        if (total > 0) r[l] /= total;
        if (total4 > 0) r4[l] /= total4;
    }
    std::vector<double> r2(n);
    for (size_t l = 0; l < n; ++l) r2[l] = r[l] * r[l];
    TimeCorrelation tc;
    tc.source = "scene";
    tc.n_eff_mean = effective_frames(n, r);
    tc.n_eff_variance = tc.n_eff_spectrum = effective_frames(n, r2);
    tc.n_eff_population = effective_frames(n, r4);
    tc.q_eff = quarter > 0 ? effective_frames(quarter, r2) : 1.0;
    tc.q_eff_population = quarter > 0 ? effective_frames(quarter, r4) : 1.0;
    return tc;
}

TheoryComparison compare_with_theory(const scenes::Scene& scene, const std::string& path,
                                     AnalysisResult& R, const TimeCorrelation& tc, bool mapped,
                                     double lo, double hi, double clipped) {
    TheoryComparison T;
    T.scene = path;
    T.hash = scene.hash;
    T.mapped = mapped;
    T.map_lo = lo, T.map_hi = hi;
    T.clipped_fraction = clipped;
    T.z_limit = kZLimit;
    const scenes::Theory th = scenes::scene_theory(scene);
    T.field_mean = th.mean;
    T.field_variance = th.variance;
    const bool zoom_constant = scene.camera.zoom.is_constant();
    T.zoom = scene.camera.zoom.value(0.0);
    if (!zoom_constant) T.no_spectrum = "camera zoom is animated";
    if (!zoom_constant)
        R.notes.push_back(
            "camera zoom is animated: no theoretical spectrum or autocovariance; the "
            "sampling errors of mean and variance use the zoom at t = 0");
    // The closed forms are those of the stationary sum of layers: a transform or a birth region
    // makes the texture something else, and the comparison below says so by disagreeing.
    if (scene.transform.type != output::FieldTransform::Type::None)
        R.notes.push_back(
            "the scene has a [shading.transform] (marble or wood): the theory describes the "
            "field before the transform, not this texture");
    for (size_t i = 0; i < scene.layers.size(); ++i)
        if (scene.layers[i].process.region)
            R.notes.push_back("layer[" + std::to_string(i) +
                              "] has a birth region: the theory holds only where the region "
                              "accepts every birth within a kernel radius");
    if (scene.output.width != R.width || scene.output.height != R.height)
        R.notes.push_back("scene output.size " + std::to_string(scene.output.width) + "x" +
                          std::to_string(scene.output.height) + " differs from the input " +
                          std::to_string(R.width) + "x" + std::to_string(R.height) +
                          " (the theory per pixel does not depend on it)");

    const int w = R.width, h = R.height;
    const double N = double(w) * h;
    const double sd_field = std::sqrt(th.variance);
    // Display inputs: clipping to [lo, hi] (Gaussian approximation of the marginal) and the
    // quantisation to 2^bits - 1 levels (uniform rounding error, white, variance step^2 / 12).
    Censored cens;
    double quant = 0.0;
    if (mapped) {
        if (sd_field > 0)
            cens = censored_normal((lo - th.mean) / sd_field, (hi - th.mean) / sd_field);
        const double step = (hi - lo) / (std::ldexp(1.0, std::min(R.bits, 24)) - 1.0);
        quant = step * step / 12.0;
    }
    const double g2 = cens.gain * cens.gain;

    // Per-layer spectra on the DFT grid, their sum, annulus means and fourth-cumulant weights.
    std::vector<double> grid(size_t(w) * h, quant);
    std::vector<std::vector<double>> layer_annuli;
    std::vector<double> c4;  // relative covariance of all bins from impulse-count fluctuations
    std::vector<double> acov_theory(size_t(R.max_lag) + 1, 0.0);
    double K4 = 0.0;  // fourth-cumulant term of Var(sample variance) times N
    double diff_var = 0.0;
    bool diff_known = true, any_animated = false;
    const bool hann = R.periodogram.window == "hann";
    for (const auto& layer : scene.layers) {
        const auto& p = layer.process;
        const double ea2 = sim::amplitude_second_moment(p.amplitude);
        const double ea4 = sim::amplitude_fourth_moment(p.amplitude);
        const bool animated = p.lifetime_s > 0;
        any_animated = any_animated || animated;
        const double W2 =
            animated ? sim::envelope_sq_integral(p.envelope, p.lifetime_s) / p.lifetime_s : 1.0;
        const double W4 = animated ? envelope_fourth_mean(p.envelope, p.lifetime_s) : 1.0;
        const double lambda_px = p.intensity / (T.zoom * T.zoom);
        const double lv = scenes::layer_theory(layer).variance;
        // Cov(P(k), P(k')) gains lambda_px N E[a^4 w^4] |H|^2 |H'|^2 / N^2 = c S(k) S(k') for a
        // compound Poisson field: the relative covariance c below is shared by every bin.
        c4.push_back(ea4 * W4 / (ea2 * ea2 * W2 * W2 * lambda_px * N));
        const kernels::Kernel k(layer.kernel);
        K4 += g2 * g2 * lambda_px * ea4 * W4 * std::pow(layer.gain.value(0.0), 4) *
              std::pow(k.integral_sq() * T.zoom * T.zoom, 2);
        if (layer.flow)
            diff_known = false;
        else if (animated)
            diff_var +=
                2.0 * g2 * lv *
                (1.0 - envelope_correlation(p.envelope, p.lifetime_s, 1.0 / scene.output.fps));

        const LayerSpectrum ls = layer_spectrum(layer, T.zoom, std::max(w, h));
        std::vector<double> lg = layer_grid(ls, w, h);
        for (size_t i = 0; i < lg.size(); ++i) {
            lg[i] *= g2;
            grid[i] += lg[i];
        }
        layer_annuli.push_back(annulus_means(hann ? hann_smooth(lg, w, h) : lg, w, h));
        if (zoom_constant) {
            const auto ac = layer_autocovariance(ls, T.zoom, R.max_lag);
            for (size_t r = 0; r < ac.size(); ++r) acov_theory[r] += g2 * ac[r];
        }
    }

    // Mean: Var(frame mean) = S(0) / N (the DC bin of the aliased spectrum).
    T.sd_frame_mean = std::sqrt(grid[0] / N);
    T.sd_mean = T.sd_frame_mean / std::sqrt(tc.n_eff_mean);
    T.mean = th.mean + (mapped ? sd_field * cens.mean : 0.0);
    // Variance: the sample variance over N pixels of P(k) / N summed, Var = 2 sum S^2 / N^2 for a
    // Gaussian field, plus the fourth cumulant lambda E[a^4] E[w^4] (int h^2)^2 / N of shot noise.
    double s2 = 0;
    for (size_t i = 1; i < grid.size(); ++i) s2 += grid[i] * grid[i];
    T.sd_frame_variance = std::sqrt(2.0 * s2 / (N * N) + K4 / N);
    T.sd_variance =
        std::sqrt(2.0 * s2 / (N * N) / tc.n_eff_variance + K4 / N / tc.n_eff_population);
    const double field_var = mapped ? th.variance * cens.variance : th.variance;
    // E[pooled sample variance] = sigma^2 - Var(pooled mean).
    T.variance = field_var + quant - T.sd_mean * T.sd_mean;
    T.z_mean = T.sd_mean > 0 ? (R.moments.mean - T.mean) / T.sd_mean
                             : (R.moments.mean == T.mean ? 0.0 : INFINITY);
    T.z_variance = T.sd_variance > 0 ? (R.moments.variance - T.variance) / T.sd_variance : INFINITY;
    T.mean_agrees = std::abs(T.z_mean) < kZLimit;
    T.variance_agrees = std::abs(T.z_variance) < kZLimit;

    if (zoom_constant) {
        // Autocovariance rings: Campbell's theorem with h * h~, less Var(frame mean) (every frame
        // is measured about its own mean), plus the white quantisation noise at lag 0.
        for (double& v : acov_theory) v -= T.sd_frame_mean * T.sd_frame_mean;
        acov_theory[0] += quant;
        T.autocovariance = acov_theory;

        SpectrumTheory S;
        if (hann) grid = hann_smooth(std::move(grid), w, h);
        grid[0] = 0.0;
        std::vector<double> squares(grid.size());
        for (size_t i = 0; i < grid.size(); ++i) squares[i] = grid[i] * grid[i];
        S.power = annulus_means(std::move(grid), w, h);
        const std::vector<double> mean_square = annulus_means(std::move(squares), w, h);
        const auto& M = R.spectrum;
        const size_t na = M.power.size();
        S.ratio.assign(na, NAN);
        S.z.assign(na, NAN);
        S.common.assign(na, 0.0);
        const double infl = hann ? kHannInflation : 1.0;
        for (size_t b = 0; b < na; ++b) {
            if (M.count[b] == 0 || !(M.frequency[b] > 0 && M.frequency[b] < 0.5) ||
                !(S.power[b] > 0))
                continue;
            double c = 0;
            for (size_t l = 0; l < layer_annuli.size(); ++l)
                c += c4[l] * layer_annuli[l][b] * layer_annuli[l][b];
            c /= S.power[b] * S.power[b];
            S.common[b] = c;
            // Independent pairs in the annulus, reduced where the expected power varies across
            // it (near the nulls between side lobes): a sum of exponentials with means S_i has
            // the variance of (sum S_i)^2 / sum S_i^2 equal ones.
            const double evenness = S.power[b] * S.power[b] / mean_square[b];
            const double pairs = 0.5 * double(M.count[b]) * evenness / infl;
            const double relvar = 1.0 / (pairs * tc.n_eff_spectrum) + c / tc.n_eff_population;
            S.ratio[b] = M.power[b] / S.power[b];
            S.z[b] = wilson_hilferty_z(S.ratio[b], 1.0 / relvar);
            S.max_abs_z = std::max(S.max_abs_z, std::abs(S.z[b]));
            ++S.compared;
        }
        S.threshold = bonferroni_threshold(S.compared, kFamilyAlpha);
        S.agrees = S.compared > 0 && S.max_abs_z < S.threshold;
        // Clipping at the ends of the display range is a nonlinearity: its distortion (odd
        // Hermite terms of the clip, Price's theorem) spreads power into the nulls and the high
        // frequencies, and for the heavier-than-Gaussian tails of sparse noise it is not known in
        // closed form. Judge the spectrum of a display input only when clipping is negligible.
        if (mapped && clipped > kMaxClippedForSpectrum)
            S.not_judged = format_number(100.0 * clipped, 3) +
                           " % of the display values are clipped (more than " +
                           format_number(100.0 * kMaxClippedForSpectrum, 3) +
                           " %): the clip distorts the spectrum; widen output.range to compare";
        if (!S.not_judged.empty()) S.agrees = false;
        T.spectrum = std::move(S);
    }
    if (diff_known) {
        if (any_animated) diff_var += 2.0 * quant;  // rounding errors of two frames
        T.diff_variance = diff_var;
    }
    return T;
}

// Structure function at dyadic lags up to a quarter of the smaller side, H(s) pooled over the
// frames (Kaplan & Kuo eq. 21).
analysis::StructureSummary structure_of(std::span<const Image> frames) {
    const int quarter = std::min(frames.front().width, frames.front().height) / 4;
    int max_s = 0;
    while ((4 << max_s) <= quarter) ++max_s;  // lags up to 2^{max_s + 1} <= quarter
    analysis::StructureAccumulator acc(max_s);
    for (const Image& f : frames) acc.add(f);
    return acc.summary();
}

}  // namespace

// ---------------------------------------------------------------------------------------------

AnalysisResult analyze_frames(std::vector<Image> frames, const AnalyzeOptions& opt,
                              const std::string& kind, bool raw, int bits, long long first_frame) {
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

    AnalysisResult R;
    R.input = opt.input;
    R.kind = kind;
    R.raw = raw;
    R.bits = bits;
    R.width = w;
    R.height = h;
    R.frames = static_cast<int>(frames.size());
    R.first_frame = first_frame;
    const size_t n = frames.size();

    // Scene first: a display input is mapped back to field values before anything is measured.
    std::optional<scenes::Scene> scene;
    std::string scene_path;
    bool mapped = false;
    double lo = 0, hi = 1, clipped = 0;
    if (!opt.scene.empty()) {
        scene_path = scenes::resolve_scene(opt.scene);
        scene = scenes::load_scene(scene_path, opt.sets);
        for (const auto& wmsg : scene->warnings) R.notes.push_back(wmsg);
        if (!raw) {
            const output::ValueMapping m = scenes::Renderer(*scene).mapping();
            lo = m.lo, hi = m.hi;
            mapped = true;
            size_t at_edge = 0;
            for (Image& f : frames)
                for (float& v : f.data) {
                    at_edge += (v <= 0.0f || v >= 1.0f);
                    v = static_cast<float>(lo + double(v) * (hi - lo));
                }
            clipped = double(at_edge) / (double(n) * w * h);
        }
    } else if (!opt.sets.empty()) {
        throw ValueError("--set " + opt.sets.front() + ": needs --scene");
    }
    // The closed forms below (spectra, correlation in time, fourth cumulants) are those of a sum
    // of layers; a scene that composes them otherwise is measured without them.
    const bool theory = scene && scenes::is_sum_of_layers(*scene);
    if (scene && !theory)
        R.notes.push_back(
            "the scene composes its layers (blend, opacity, visible or warp, docs/scenes.md "
            "\"Composition\"): the theory here covers sums of layers, so no comparison with it; "
            "the display range still maps the values back");

    // One-point statistics of all pixels of all frames.
    {
        std::vector<float> pooled;
        std::span<const float> all(frames.front().data);
        if (n > 1) {
            pooled.reserve(n * w * h);
            for (const Image& f : frames) pooled.insert(pooled.end(), f.data.begin(), f.data.end());
            all = pooled;
        }
        R.moments = analysis::moments(all);
        const double sd = std::sqrt(R.moments.variance);
        const double half = sd > 0 ? kHistogramHalfWidthSd * sd : 0.5;
        R.histogram =
            analysis::histogram(all, R.moments.mean - half, R.moments.mean + half, kHistogramBins);
    }

    // Periodicity decides the window: none for torus frames, Hann otherwise.
    const WrapTest wt = wrap_test(frames, R.moments.variance);
    const analysis::Window window = wt.periodic ? analysis::Window::None : analysis::Window::Hann;

    // Frame-averaged periodogram (summed in frame order, then scaled: the bits of
    // analysis::average), with each frame's radial profile kept for the correlation time.
    analysis::Periodogram avg;
    std::vector<std::vector<double>> frame_profiles;
    for (size_t j = 0; j < n; ++j) {
        analysis::Periodogram p = analysis::periodogram(frames[j], window);
        if (n > 1) frame_profiles.push_back(analysis::radial_average(p).power);
        if (j == 0) {
            avg.width = p.width;
            avg.height = p.height;
            avg.power.assign(p.power.size(), 0.0);
        }
        for (size_t i = 0; i < p.power.size(); ++i) avg.power[i] += p.power[i];
    }
    const double inv = 1.0 / double(n);
    for (double& v : avg.power) v *= inv;
    R.spectrum = analysis::radial_average(avg);
    R.periodogram = summarize(avg);
    R.periodogram.window = wt.periodic ? "none" : "hann";
    R.periodogram.periodic = wt.periodic;
    R.periodogram.wrap_ratio_x = wt.ratio_x;
    R.periodogram.wrap_ratio_y = wt.ratio_y;

    // Radial autocovariance out to min(w, h) / 4, averaged over frames.
    R.max_lag = std::min(w, h) / 4;
    R.autocovariance.assign(size_t(R.max_lag) + 1, 0.0);
    for (const Image& f : frames) {
        const auto a = frame_autocovariance(f, wt.periodic, R.max_lag);
        for (size_t r = 0; r < a.size(); ++r) R.autocovariance[r] += a[r];
    }
    for (double& v : R.autocovariance) v *= inv;

    R.frame_stats = analysis::frame_stats(frames);

    // Correlation between frames: how many independent frames the averages are worth. From the
    // scene's envelopes when there is one; else estimated from the frames (10 or more); else
    // none are assumed independent.
    const size_t quarter = n / 4;
    TimeCorrelation tc;
    if (theory && n > 1) {
        tc = scene_time_correlation(*scene, n, quarter);
    } else if (n >= size_t(kMinFramesForTime)) {
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
        tc.source = "frames";
        tc.n_eff_mean = std::max(1.0, double(n) / tm.tau);
        tc.n_eff_variance = std::max(1.0, double(n) / tv.tau);
        tc.n_eff_spectrum = std::max(1.0, double(n) / ts.tau);
        tc.q_eff = std::max(1.0, double(quarter) / ts.tau);
        tc.n_eff_population = tc.n_eff_spectrum;
        tc.q_eff_population = tc.q_eff;
        tc.converged = tm.converged && tv.converged && ts.converged;
    }
    R.tau_source = tc.source;
    R.tau_mean = double(n) / tc.n_eff_mean;
    R.tau_variance = double(n) / tc.n_eff_variance;
    R.tau_spectrum = double(n) / tc.n_eff_spectrum;
    if (tc.source == "frames" && n / std::max(1.0, R.tau_spectrum) < 20)
        R.notes.push_back("the frames hold only about " +
                          format_number(double(n) / std::max(1.0, R.tau_spectrum), 2) +
                          " independent ones: the correlation time and the common level of the "
                          "spectrum are rough estimates and the drift z may be off by tens of "
                          "percent; give --scene for the exact correlation of an animated scene");
    if (!tc.converged)
        R.notes.push_back(
            "frames are correlated over more than half of the sequence: the "
            "correlation time is a lower bound and the z values are approximate");

    bool keyframed = false;
    if (scene)
        for (const auto& l : scene->layers) keyframed = keyframed || l.keyframed();
    if (keyframed)
        R.notes.push_back(
            "layer parameters of the scene are keyframed: the statistics vary in time, so there "
            "is no comparison with the (stationary) theory");
    if (theory && !keyframed) {
        R.theory = compare_with_theory(*scene, scene_path, R, tc, mapped, lo, hi, clipped);
        if (mapped && clipped > 0.001)
            R.notes.push_back("display input: " + format_number(clipped * 100.0, 3) +
                              " % of pixels at the ends of the range; theory assumes a Gaussian "
                              "marginal censored there");
    }

    // Stationarity over time.
    Stationarity& st = R.stationarity;
    st.trend_blocks = kTrendBlocks;
    st.t_limit = kZLimit;
    if (n < size_t(kMinFramesForTime)) {
        st.available = false;
        st.reason = n == 1 ? "one frame"
                           : "needs >= " + std::to_string(kMinFramesForTime) + " frames (" +
                                 std::to_string(n) + " given)";
    } else {
        st.available = true;
        std::vector<double> vars(n);
        for (size_t j = 0; j < n; ++j) vars[j] = R.frame_stats[j].variance;
        st.trend = analysis::trend(vars, kTrendBlocks);
        st.quarter = static_cast<int>(quarter);
        const std::span<const Image> all(frames);
        st.drift = analysis::spectral_drift(all.first(quarter), all.last(quarter));
        // spectral_drift's variance, 2 P^2 / (pairs q), assumes independent frames and bins. A
        // quarter of q correlated frames is worth q_eff, and the impulse population adds a level
        // common to all annuli (relative variance c per frame, c / q_eff_population per quarter):
        //     z_corrected = z sqrt((1 / (pairs q)) / (1 / (pairs q_eff) + c_q)).
        // The common level's drift is what the trend test on the frame variance measures.
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
        st.z_threshold = bonferroni_threshold(static_cast<int>(st.drift.z.size()), kFamilyAlpha);
        st.stationary =
            std::abs(st.trend.t) < st.t_limit && st.max_abs_z_corrected < st.z_threshold;
        const size_t block = n / kTrendBlocks;
        if (double(block) < 2.0 * R.tau_variance)
            R.notes.push_back("trend blocks of " + std::to_string(block) +
                              " frames are shorter than twice the correlation time of the frame "
                              "variance (" +
                              format_number(R.tau_variance, 3) +
                              " frames): the trend's standard error may be low and t inflated");
    }
    if (!raw && !mapped)
        R.notes.push_back(
            "display values in [0, 1] (8/16-bit source); give --scene to map them "
            "back to field values and compare with theory");
    if (kind == "video")
        R.notes.push_back("video: lossy compression alters the fine-scale spectrum and adds noise");
    if (opt.structure) R.structure = structure_of(frames);
    if (!opt.variance_map.empty()) {
        if (n < 2)
            throw ValueError("--variance-map " + opt.variance_map +
                             ": needs a sequence of at least 2 frames (realizations)");
        analysis::PixelVariance pv;
        for (const Image& f : frames) pv.add(f);
        R.variance_map = pv.variance();
    }

    return R;
}

AnalysisResult analyze_input(const AnalyzeOptions& options) {
    Loaded L = load_input(options);
    return analyze_frames(std::move(L.frames), options, L.kind, L.raw, L.bits, L.first);
}

}  // namespace impulse::app
