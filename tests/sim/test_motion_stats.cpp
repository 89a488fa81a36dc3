// SPDX-License-Identifier: Apache-2.0
// Temporal stationarity of the animated process in flows (design.md §1, §5): per-frame mean and
// variance against Campbell's theorem, the radial spectrum early and late, the frame-to-frame
// change against the closed form of the Hann envelope's autocorrelation, and the three ways an
// uncompensated divergent flow breaks stationarity (uniform divergence, localized source,
// pulsing source) — each must be repaired by sqrt(J) and caught without it.
//
// Every run is a 128x128 cosine-kernel field (R = 6 px, 16 impulses per kernel area, normal
// amplitudes, Hann lifetimes) rendered through the scene loader and scenes::Renderer, on fixed
// seeds. Tolerances come from the sampling error: closed forms where they exist (written out
// next to each use), otherwise the scatter of block means of the run itself, with blocks of two
// lifetimes (nearly independent; see kBlocks). Set IMPULSE_TEST_REPORT=1 to print every
// statistic next to its band.

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;

namespace {

constexpr double kPi = std::numbers::pi;

// ---------------------------------------------------------------------------------------------
// Run layout
//
// fps 12 and a 2 s lifetime: 24 frames per lifetime. 960 frames = 80 s = 40 lifetimes, cut into
// 20 blocks of 48 frames = 2 lifetimes. The frame variance decorrelates within one lifetime
// (its autocorrelation is a mix of rho_w^2 and the w^2 autocorrelation, both zero beyond T), so
// adjacent block means correlate by c = int_0^T u rho(u) du / (L tau_int - 2 int_0^T u rho du)
// = 0.04 for L = 2T (computed for the still field; motion only shortens the memory). That
// shrinks the block-scatter standard error by a factor sqrt(1 - 2c) ~ 0.96: a threshold of 5
// standard errors is really 4.8. Under the null, (mean - expected) / se follows Student's t
// with 19 degrees of freedom: P(|t_19| > 5) = 8e-5, P(|t_19| > 5.5) = 2.6e-5.

constexpr int kSize = 128;
constexpr double kFps = 12.0;
constexpr double kLifetime = 2.0;
constexpr int kFrames = 960;
constexpr int kBlocks = 20;
constexpr double kBlockT = 5.0;  // single comparisons, t_19: two-sided p = 8e-5

bool reporting() { return std::getenv("IMPULSE_TEST_REPORT") != nullptr; }
template <class... A>
void report(const char* fmt, A... a) {
    if (reporting()) {
        std::printf(fmt, a...);
        std::fflush(stdout);
    }
}

struct SceneSpec {
    std::string flows;  ///< [[layer.flow]] tables ("" = still particles that live and die)
    double lifetime = kLifetime;
    bool jacobian = true;
    std::string envelope = "hann";
    int64_t frames = kFrames;  ///< output.frames (timeline length)
};

std::string scene_text(const SceneSpec& s) {
    std::ostringstream t;
    t << "[output]\nsize = [" << kSize << ", " << kSize << "]\nfps = " << kFps
      << "\nframes = " << s.frames << "\n\n[[layer]]\nseed = 31\ndensity = 16.0\n"
      << "amplitude = \"normal\"\nlifetime = " << s.lifetime << "\nenvelope = \"" << s.envelope
      << "\"\nsubsteps = 2\njacobian = " << (s.jacobian ? "true" : "false")
      << "\n[layer.kernel]\ntype = \"cosine\"\nradius = 6.0\n\n"
      << s.flows;
    return t.str();
}

const std::string kWind = "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [10.0, 4.0]\n";
// Lamb–Oseen vortex in the middle of the frame: peak speed 0.638 G / (2 pi rc) = 13.5 px/s.
const std::string kVortex =
    "[[layer.flow]]\ntype = \"vortex\"\ncenter = [64.0, 64.0]\ncirculation = 4000.0\n"
    "core = 30.0\nmodel = \"lamb-oseen\"\n";
// Localized sink, radius 30 % of the frame: div at the centre 2 rate = -1/s.
const std::string kSink =
    "[[layer.flow]]\ntype = \"source\"\ncenter = [64.0, 64.0]\nrate = -0.5\nradius = 38.0\n";
// Uniform divergence 2 rate = 0.25/s everywhere (design.md §5 case 1).
const std::string kDivergence =
    "[[layer.flow]]\ntype = \"source\"\ncenter = [64.0, 64.0]\nrate = 0.125\nradius = 0.0\n";
// Localized source, radius 30 % of the frame: div 2 rate = 1/s at the centre, J up to e^2 over a
// lifetime there; div < 0 beyond r = radius, where the outflow slows and crowds (case 2).
const std::string kLocalSource =
    "[[layer.flow]]\ntype = \"source\"\ncenter = [64.0, 64.0]\nrate = 0.5\nradius = 38.0\n";

/// Pulsing uniform source (case 3): rate keyed 0, +a, 0, -a, 0 every second, smoothstep eased,
/// period 4 s, over `seconds`; divergence 2 rate = 0.7 sin-like.
std::string pulsing_flow(double amplitude, int seconds) {
    std::ostringstream t;
    t << "[[layer.flow]]\ntype = \"source\"\ncenter = [64.0, 64.0]\nradius = 0.0\n"
      << "rate = { ease = \"smooth\", keys = [";
    const double phase[4] = {0.0, 1.0, 0.0, -1.0};
    for (int s = 0; s <= seconds; ++s)
        t << (s ? ", " : "") << "[" << s << ".0, " << amplitude * phase[s % 4] << "]";
    t << "] }\n";
    return t.str();
}

// ---------------------------------------------------------------------------------------------
// Rendering a run and its per-frame statistics

analysis::Image to_image(const render::Frame& f) { return {f.width, f.height, f.data}; }

struct Run {
    std::vector<double> mean, variance, diff_variance;  ///< analysis::frame_stats per frame
    /// Second moment about the known mean 0 in a 4x4 grid of 32x32 windows, per frame.
    std::array<std::vector<double>, 16> window_m2;
    std::vector<analysis::Image> first, last;  ///< kept frames (spectral tests)
};

/// Renders frames 0, stride, 2 stride, ... ((count - 1) stride) of the scene in order with one
/// Renderer, keeping the first and last `keep` frames. Cached: several tests share runs.
const Run& run(const SceneSpec& spec, int count, int stride = 1, int keep = 0) {
    static std::map<std::string, Run> cache;
    const std::string text = scene_text(spec);
    const std::string key = text + "#" + std::to_string(count) + "/" + std::to_string(stride) +
                            "/" + std::to_string(keep);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    scenes::Renderer renderer(scenes::load_scene_string(text, "motion.toml"));
    Run r;
    render::Frame frame;
    std::array<analysis::Image, 2> pair;
    for (int i = 0; i < count; ++i) {
        renderer.render(static_cast<int64_t>(i) * stride, frame);
        pair[0] = std::move(pair[1]);
        pair[1] = to_image(frame);
        const auto st = analysis::frame_stats(std::span(pair).subspan(i == 0 ? 1 : 0));
        r.mean.push_back(st.back().mean);
        r.variance.push_back(st.back().variance);
        if (i > 0) r.diff_variance.push_back(st.back().diff_variance);
        for (int w = 0; w < 16; ++w) {
            const int x0 = (w % 4) * 32, y0 = (w / 4) * 32;
            double s = 0.0;
            for (int y = y0; y < y0 + 32; ++y)
                for (int x = x0; x < x0 + 32; ++x) s += double(frame.at(x, y)) * frame.at(x, y);
            r.window_m2[w].push_back(s / 1024.0);
        }
        if (i < keep) r.first.push_back(pair[1]);
        if (i >= count - keep) r.last.push_back(pair[1]);
    }
    return cache.emplace(key, std::move(r)).first->second;
}

/// Block means of a series: their mean, sample standard deviation and the standard error of
/// the run mean, sd / sqrt(B).
struct BlockEstimate {
    std::vector<double> means;
    double mean = 0.0, sd = 0.0, se = 0.0;
};
BlockEstimate blocks_of(const std::vector<double>& series, int blocks = kBlocks) {
    BlockEstimate b;
    b.means = analysis::block_means(series, blocks);
    for (double m : b.means) b.mean += m / blocks;
    double ss = 0.0;
    for (double m : b.means) ss += (m - b.mean) * (m - b.mean);
    b.sd = std::sqrt(ss / (blocks - 1));
    b.se = b.sd / std::sqrt(double(blocks));
    return b;
}

// ---------------------------------------------------------------------------------------------
// Closed forms (design.md §1, Campbell's theorem)

/// Normalised autocorrelation of the Hann envelope w(a) = sin^2(pi a / T) on [0, T):
///   (w * w~)(D) = int_0^{T-D} w(a) w(a + D) da
///              = 1/4 [ (T - D)(1 + cos(th D) / 2) + (3 / (2 th)) sin(th D) ],   th = 2 pi / T,
/// from sin^2 = (1 - cos)/2 and int_0^{T-D} cos(th a) da = int_0^{T-D} cos(th (a + D)) da
/// = -sin(th D) / th; at D = 0 it is 3T/8 = int w^2. Returned divided by 3T/8; 0 for D >= T.
double hann_rho(double lag_s, double lifetime_s) {
    const double D = std::abs(lag_s), T = lifetime_s;
    if (D >= T) return 0.0;
    const double th = 2.0 * kPi / T;
    return ((T - D) * (1.0 + 0.5 * std::cos(th * D)) + 1.5 * std::sin(th * D) / th) / (1.5 * T);
}

struct Closed {
    double sigma2 = 0.0;  ///< Campbell variance, scenes::layer_theory
    double lambda = 0.0;  ///< live impulses per unit area
    double int_h = 0.0, int_h2 = 0.0;
    double area_rho2 = 0.0;  ///< int rho_h(tau)^2 d^2 tau, rho_h = (h * h~) / int h^2
    double pixels = double(kSize) * kSize;
    kernels::Kernel kernel;

    explicit Closed(const scenes::LayerConfig& layer)
        : sigma2(scenes::layer_theory(layer).variance),
          lambda(layer.process.intensity),
          int_h(kernels::Kernel(layer.kernel).integral()),
          int_h2(kernels::Kernel(layer.kernel).integral_sq()),
          kernel(layer.kernel) {
        // Simpson in r over the support 2R of the (isotropic) autocorrelation. The kernel is the
        // same in every run and Kernel::autocorrelation is a quadrature (~20 ms a call): once.
        static const double cached = [this] {
            const double R2 = 2.0 * kernel.radius();
            const int n = 48;
            const double h = R2 / n;
            double s = 0.0;
            for (int i = 0; i <= n; ++i) {
                const double r = i * h, p = rho_h(r);
                s += (i == 0 || i == n ? 1.0 : (i % 2 ? 4.0 : 2.0)) * 2.0 * kPi * r * p * p;
            }
            return s * h / 3.0;
        }();
        area_rho2 = cached;
    }
    double rho_h(double d) const { return kernel.autocorrelation(d, 0.0) / int_h2; }
    /// Var of a frame's spatial mean: (sigma^2 / N^2) sum_{x,y} rho_h(x - y) <= (sigma^2 / N)
    /// int rho_h = sigma^2 (int h)^2 / (N int h^2) (edges only lower it).
    double var_frame_mean() const { return sigma2 * int_h * int_h / (int_h2 * pixels); }
    /// E[population variance of a frame] = sigma^2 - Var(frame mean).
    double frame_variance() const { return sigma2 - var_frame_mean(); }
    /// Sampling sd of one frame's variance: Var(s^2) ~ (1/N) sum_tau Cov(f^2(x), f^2(x+tau)) =
    /// (1/N) [2 int C^2 + cum4] with 2 int C^2 = 2 sigma^4 area_rho2 (Gaussian part) and the
    /// fourth cumulant of the Poisson sum beta E[a^4] int w^4 dt (int h^2)^2, beta int w^4 =
    /// lambda 35/128 for Hann (int sin^8 = 35T/128), E[a^4] = 3. Where a flow changes J, the
    /// cumulant part scales locally by J (density 1/J times weight^4 J^2): `j_max` bounds it.
    double sd_frame_variance(double j_max = 1.0) const {
        const double gauss = 2.0 * sigma2 * sigma2 * area_rho2;
        const double cum4 = lambda * 3.0 * (35.0 / 128.0) * int_h2 * int_h2 * j_max;
        return std::sqrt((gauss + cum4) / pixels);
    }
};

Closed closed_for(const SceneSpec& spec) {
    const scenes::Scene s = scenes::load_scene_string(scene_text(spec), "motion.toml");
    return Closed(s.layers.front());
}

double max_abs_deviation(const std::vector<double>& v, double centre) {
    double m = 0.0;
    for (double x : v) m = std::max(m, std::abs(x - centre));
    return m;
}

struct NamedFlow {
    const char* name;
    std::string flows;
    double j_max;  ///< bound on J over a lifetime where the divergence is positive
};

/// The three flows of the stationarity tests. The sink's divergence k g (2 - 2q) is positive
/// only beyond r = radius, at most 2 |k| e^-2 = 0.135/s: J <= e^{0.135 T} = 1.31.
std::vector<NamedFlow> flows() {
    return {{"uniform wind", kWind, 1.0},
            {"Lamb-Oseen vortex", kVortex, 1.0},
            {"localized sink", kSink, std::exp(2.0 * 0.5 * std::exp(-2.0) * kLifetime)}};
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// 1. Per-frame mean and variance; run mean of the frame variance against the closed form

TEST_CASE("motion: per-frame mean and variance stay in their sampling bands", "[sim][stats]") {
    // 960 frames per flow, each checked against 5 sd (Closed::var_frame_mean,
    // Closed::sd_frame_variance). The frame mean is a sum over thousands of impulses, close to
    // normal: P(|z| > 5) = 5.7e-7 per frame; its autocorrelation is rho_w, whose integral is
    // 2T/3 = 16 frames, so the run holds ~60 independent frames: ~3e-5 family-wise. The frame
    // variance is a quadratic form with 2 / (relative sd)^2 ~ 320 degrees of freedom: its upper
    // tail at +5 sd is that of chi^2_320, 4e-6 per frame (Wilson-Hilferty); its memory is
    // ~T/2 = 12 frames, ~80 independent frames: ~3e-4 family-wise.
    for (const NamedFlow& f : flows()) {
        INFO(f.name);
        SceneSpec spec;
        spec.flows = f.flows;
        const Closed th = closed_for(spec);
        const Run& r = run(spec, kFrames);
        const double sd_mean = std::sqrt(th.var_frame_mean());
        const double sd_var = th.sd_frame_variance(f.j_max);
        const double dev_mean = max_abs_deviation(r.mean, 0.0);
        const double dev_var = max_abs_deviation(r.variance, th.frame_variance());
        report(
            "[per-frame] %-18s max|mean|/sd = %.2f (band 5); max|var - %.4f|/sd = %.2f (band 5, sd "
            "%.4f)\n",
            f.name, dev_mean / sd_mean, th.frame_variance(), dev_var / sd_var, sd_var);
        CHECK(dev_mean < 5.0 * sd_mean);
        CHECK(dev_var < 5.0 * sd_var);
    }
}

TEST_CASE("motion: run mean of the frame variance matches Campbell's theorem", "[sim][stats]") {
    // E[frame variance] = sigma^2 - Var(frame mean) (the population variance is about the frame's
    // own mean; the correction is 0.35 % here). Standard error from 20 blocks of two lifetimes;
    // |t| < 5 (t_19: p = 8e-5 per flow).
    std::vector<NamedFlow> all = flows();
    all.insert(all.begin(), NamedFlow{"no flow", "", 1.0});
    for (const NamedFlow& f : all) {
        INFO(f.name);
        SceneSpec spec;
        spec.flows = f.flows;
        const Closed th = closed_for(spec);
        const BlockEstimate b = blocks_of(run(spec, kFrames).variance);
        const double t = (b.mean - th.frame_variance()) / b.se;
        report("[run mean]  %-18s mean var %.4f vs %.4f: t = %+.2f (band 5, se %.4f)\n", f.name,
               b.mean, th.frame_variance(), t, b.se);
        CHECK(std::abs(t) < kBlockT);
        // Trend of the frame variance over the run: slope / block-based stderr ~ t_18,
        // P(|t_18| > 5) = 9e-5.
        const analysis::Trend tr = analysis::trend(run(spec, kFrames).variance, kBlocks);
        report("[run mean]  %-18s variance trend t = %+.2f (band 5)\n", f.name, tr.t);
        CHECK(std::abs(tr.t) < 5.0);
    }
}

// ---------------------------------------------------------------------------------------------
// 2. Radially averaged spectrum, early against late

TEST_CASE("motion: radial spectrum of the first and last 50 frames agree", "[sim][stats]") {
    // analysis::spectral_drift's variance model (each annulus holds count/2 independent
    // exponential values per frame) needs independent frames. Frames one lifetime apart hold
    // disjoint sets of particles (alive at t means born in (t - T, t]), and births are Poisson
    // in space-time, so such frames are exactly independent: the run renders 300 frames with a
    // stride of T * fps = 24 (600 s) and compares the first 50 with the last 50. Then each z is
    // close to N(0, 1) (the fourth-cumulant correction is ~1 / (N lambda) = 4e-4); with 63
    // annuli (|k| in (0, 0.5) cycles/px) a Bonferroni bound max|z| < 4.5 has family-wise
    // P = 63 x 6.8e-6 = 4.3e-4.
    const int stride = static_cast<int>(kLifetime * kFps);
    for (const NamedFlow& f : flows()) {
        INFO(f.name);
        SceneSpec spec;
        spec.flows = f.flows;
        spec.frames = 300 * stride;
        const Run& r = run(spec, 300, stride, 50);
        const analysis::SpectralDrift d = analysis::spectral_drift(r.first, r.last);
        report("[spectrum]  %-18s max|z| = %.2f over %zu annuli (band 4.5)\n", f.name, d.max_abs_z,
               d.z.size());
        CHECK(d.z.size() >= 60);
        CHECK(d.max_abs_z < 4.5);
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Frame-to-frame change

TEST_CASE("motion: frame-to-frame change is stationary and nothing pops", "[sim][stats]") {
    // Without motion the field's temporal autocovariance is sigma^2 rho_w(D) with rho_w the
    // normalised Hann autocorrelation (hann_rho), so E[var(f_t+D - f_t)] = 2 sigma^2 (1 - rho_w)
    // less the variance of the difference's frame mean, 2 sigma^2 (1 - rho_w) (int h)^2 /
    // (N int h^2). At D = 1/12 s, T = 2 s: 1 - rho_w = 0.0114, the difference carries 2.3 % of
    // 2 sigma^2: Hann particles fade in and out, nothing pops. A uniform wind v shifts the
    // field: the autocovariance becomes sigma^2 rho_w(D) rho_h(v D), exact again. For any flow
    // with |v| <= vmax and |div v| <= dmax, each impulse's covariance with itself one frame
    // later is at least that of a still one times rho_h(vmax D) e^{-dmax D / 2} (rho_h decreases
    // with the lag for this kernel, sqrt(J) changes by at most e^{dmax D / 2}), so
    // 2 sigma^2 (1 - rho_w rho_h(vmax D) e^{-dmax D/2}) bounds the expected difference variance.
    const double D = 1.0 / kFps;
    struct Case {
        const char* name;
        std::string flows;
        bool exact;   ///< closed form (true) or upper bound (false)
        double dmax;  ///< bound on |div v| (the sink's is 2 |rate| at its centre)
    };
    const std::vector<Case> cases = {{"no flow", "", true, 0.0},
                                     {"uniform wind", kWind, true, 0.0},
                                     {"Lamb-Oseen vortex", kVortex, false, 0.0},
                                     {"localized sink", kSink, false, 2.0 * 0.5}};
    double hann_still = 0.0, hann_still_se = 0.0;
    for (const Case& c : cases) {
        INFO(c.name);
        SceneSpec spec;
        spec.flows = c.flows;
        const scenes::Scene scene = scenes::load_scene_string(scene_text(spec), "motion.toml");
        const Closed th(scene.layers.front());
        const Run& r = run(spec, kFrames);
        const double rho_w = hann_rho(D, kLifetime);
        const double mean_term = th.int_h * th.int_h / (th.int_h2 * th.pixels);
        double expected = 0.0;
        if (c.flows.empty()) {
            expected = 2.0 * th.sigma2 * (1.0 - rho_w) * (1.0 - mean_term);
        } else if (c.exact) {
            const double shift = std::hypot(10.0, 4.0) * D;
            expected = 2.0 * th.sigma2 * (1.0 - rho_w * th.rho_h(shift)) -
                       2.0 * th.sigma2 * (1.0 - rho_w) * mean_term;
        } else {
            const numeric::Box view{0, 0, double(kSize), double(kSize)};
            const numeric::Box region = view.expanded(th.kernel.radius());
            const double vmax = scene.layers.front().flow->max_speed(region);
            expected =
                2.0 * th.sigma2 * (1.0 - rho_w * th.rho_h(vmax * D) * std::exp(-0.5 * c.dmax * D));
        }
        const BlockEstimate b = blocks_of(r.diff_variance);
        const double t = (b.mean - expected) / b.se;
        // Stationarity: trend over the run, and the first ten block means against the last ten
        // (pooled within-half scatter, 18 degrees of freedom: P(|t_18| > 5) = 9e-5).
        const analysis::Trend tr = analysis::trend(r.diff_variance, kBlocks);
        double m1 = 0, m2 = 0;
        for (int i = 0; i < kBlocks / 2; ++i)
            m1 += b.means[i] / (kBlocks / 2), m2 += b.means[i + kBlocks / 2] / (kBlocks / 2);
        double ss = 0;
        for (int i = 0; i < kBlocks / 2; ++i)
            ss += (b.means[i] - m1) * (b.means[i] - m1) +
                  (b.means[i + kBlocks / 2] - m2) * (b.means[i + kBlocks / 2] - m2);
        const double pooled = ss / (kBlocks - 2);
        const double t_halves = (m1 - m2) / std::sqrt(pooled * 2.0 / (kBlocks / 2));
        report(
            "[diff]      %-18s diff var %.5f = %.4f x 2 sigma^2; %s %.5f: t = %+.2f; trend t = "
            "%+.2f; halves t = %+.2f\n",
            c.name, b.mean, b.mean / (2.0 * th.sigma2), c.exact ? "expected" : "bound", expected, t,
            tr.t, t_halves);
        CHECK(std::abs(tr.t) < 5.0);
        CHECK(std::abs(t_halves) < 5.0);
        if (c.exact)
            CHECK(std::abs(t) < kBlockT);
        else
            CHECK(t < kBlockT);
        if (c.flows.empty()) hann_still = b.mean, hann_still_se = b.se;
    }

    SECTION("a box envelope pops, and the statistic sees it") {
        // Box lifetimes switch impulses on and off: the autocorrelation is 1 - D/T, and the
        // expected difference variance 2 sigma^2 (D / T) (1 - mean term) = 3.6x the Hann one.
        SceneSpec spec;
        spec.envelope = "box";
        const Closed th = closed_for(spec);
        const BlockEstimate b = blocks_of(run(spec, kFrames).diff_variance);
        const double mean_term = th.int_h * th.int_h / (th.int_h2 * th.pixels);
        const double expected = 2.0 * th.sigma2 * (D / kLifetime) * (1.0 - mean_term);
        const double t = (b.mean - expected) / b.se;
        const double t_vs_hann = (b.mean - hann_still) / std::hypot(b.se, hann_still_se);
        report(
            "[diff]      box envelope       diff var %.5f vs %.5f: t = %+.2f; vs Hann t = %+.1f\n",
            b.mean, expected, t, t_vs_hann);
        CHECK(std::abs(t) < kBlockT);
        CHECK(t_vs_hann > kBlockT);
    }
}

// ---------------------------------------------------------------------------------------------
// 4. The three ways an uncompensated divergent flow breaks stationarity (design.md §5)

TEST_CASE("motion: uniform divergence keeps the frame variance only with sqrt(J)", "[sim][stats]") {
    // v = 0.125 (x - c): div = 0.25/s, J = e^{0.25 age}. Without sqrt(J) the variance is
    // sigma^2 int w^2 e^{-0.25 a} da / int w^2 ~ 0.78 sigma^2. The statistic is the run mean of
    // the frame variance against a no-flow run of the same process: the difference of two
    // block-estimated means, ~ t with ~38 degrees of freedom: |t| < 5 has P = 1.3e-5.
    SceneSpec still;
    const BlockEstimate ref = blocks_of(run(still, kFrames).variance);
    for (bool jacobian : {true, false}) {
        SceneSpec spec;
        spec.flows = kDivergence;
        spec.jacobian = jacobian;
        const BlockEstimate b = blocks_of(run(spec, kFrames).variance);
        const double t = (b.mean - ref.mean) / std::hypot(b.se, ref.se);
        report(
            "[case a]    jacobian %-5s mean var %.4f vs no flow %.4f (%+.1f %%): t = %+.2f (band "
            "5)\n",
            jacobian ? "on" : "off", b.mean, ref.mean, 100.0 * (b.mean / ref.mean - 1.0), t);
        if (jacobian)
            CHECK(std::abs(t) < kBlockT);
        else
            CHECK(t < -kBlockT);  // the mechanism is what keeps it in the band
    }
}

TEST_CASE("motion: localized source keeps the variance even across windows only with sqrt(J)",
          "[sim][stats]") {
    // Second moment about the known mean 0 (unbiased for sigma^2 in any window) in 16 windows of
    // 32x32, averaged over the run; each window's standard error from its own 20 block means
    // (so the heavier tails of large sqrt(J) weights near the source are in it). 16 windows,
    // t_19: Bonferroni max|t| < 5.5 has family-wise P = 16 x 2.6e-5 = 4.2e-4.
    for (bool jacobian : {true, false}) {
        SceneSpec spec;
        spec.flows = kLocalSource;
        spec.jacobian = jacobian;
        const Closed th = closed_for(spec);
        const Run& r = run(spec, kFrames);
        double max_t = 0.0, lo = 1e300, hi = -1e300;
        std::string grid;
        for (int w = 0; w < 16; ++w) {
            const BlockEstimate b = blocks_of(r.window_m2[w]);
            const double t = (b.mean - th.sigma2) / b.se;
            max_t = std::max(max_t, std::abs(t));
            lo = std::min(lo, b.mean), hi = std::max(hi, b.mean);
            char cell[32];
            std::snprintf(cell, sizeof cell, "%+6.1f%s", t, w % 4 == 3 ? "\n" : " ");
            grid += cell;
        }
        report(
            "[case b]    jacobian %-5s window max|t| = %.2f (band 5.5), spread (max-min)/sigma^2 = "
            "%.1f %%\n%s",
            jacobian ? "on" : "off", max_t, 100.0 * (hi - lo) / th.sigma2, grid.c_str());
        if (jacobian)
            CHECK(max_t < 5.5);
        else
            CHECK(max_t > 5.5);
    }
}

TEST_CASE("motion: pulsing source keeps block means steady only with sqrt(J)", "[sim][stats]") {
    // Uniform divergence 0.7 sin-like with period 4 s (rate keys +-0.35, smooth), lifetime 1 s.
    // Blocks of 2 s = two lifetimes = half a period, so an uncompensated pulse shows as block
    // means alternating high and low. F = (scatter of the pulsing run's 40 block means) /
    // (scatter of a no-flow run's, same lifetime): both ~ sigma_B^2 chi^2_39 / 39 under the
    // null, F_{39,39} 0.999 quantile = 2.76. (With sqrt(J) the expected frame variance is
    // constant; only its fourth-cumulant sampling noise breathes with J, symmetrically about the
    // still value, which moves E[F] by a few per cent at most.) Without sqrt(J) the variance
    // swings by ~e^{+-0.35} over a period: F of order 10-20.
    constexpr double kLife1 = 1.0;
    constexpr int kPulseFrames = 960;  // 80 s = 20 periods
    constexpr int kPulseBlocks = 40;   // 24 frames = 2 s
    SceneSpec still;
    still.lifetime = kLife1;
    const BlockEstimate ref = blocks_of(run(still, kPulseFrames).variance, kPulseBlocks);
    for (bool jacobian : {true, false}) {
        SceneSpec spec;
        spec.lifetime = kLife1;
        spec.flows = pulsing_flow(0.35, 84);
        spec.jacobian = jacobian;
        const BlockEstimate b = blocks_of(run(spec, kPulseFrames).variance, kPulseBlocks);
        const double F = (b.sd * b.sd) / (ref.sd * ref.sd);
        report(
            "[case c]    jacobian %-5s block-mean variance F = %.2f (band 2.76); mean var %.4f vs "
            "%.4f\n",
            jacobian ? "on" : "off", F, b.mean, ref.mean);
        if (jacobian)
            CHECK(F < 2.76);
        else
            CHECK(F > 2.76);
    }
}
