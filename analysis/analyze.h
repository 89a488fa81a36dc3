// SPDX-License-Identifier: Apache-2.0
#pragma once
// The analysis behind `impulse analyze`: measure frames of a texture with the estimators of
// analysis.h and, given a scene, compare the measurements with its closed-form theory
// (analysis/theory.h; design.md §1, §5). Reading the input from files is the command line's
// (app/analyze.h); the text, JSON and HTML reports are in analysis/report.h.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/estimators.h"
#include "analysis/structure.h"

namespace impulse::analysis {

/// What to analyse and against which scene.
struct AnalyzeOptions {
    std::string input;              ///< image, sequence pattern (f_####.exr, f_%04d.png) or video
    std::string scene;              ///< scene file or built-in name; empty: no theory
    std::vector<std::string> sets;  ///< --set overrides of the scene
    /// --size WxH: the scene's theory at render's --size ("": as the frames' metadata records,
    /// impulse:size and impulse:crop, else the scene's own framing)
    std::string size;
    /// --channel NAME: the channel of a multi-channel image to analyse ("": `value` when the
    /// image has one, else the luminance)
    std::string channel;
    std::string frames;             ///< "A-B" or "A", inclusive and 0-based; empty: from 0
    long long max_frames = 0;       ///< > 0: analyse at most this many frames
    bool structure = false;         ///< structure function and H(s) (Kaplan & Kuo eq. 21)
    std::string variance_map;       ///< CLI only: write the per-pixel variance over frames (EXR)
    bool json = false;              ///< CLI only: print JSON instead of text
    std::string json_file;          ///< CLI only: --json FILE writes the JSON there (text printed)
    std::string report;             ///< CLI only: write an HTML report here
    /// Relative change of the frame variance over the frames that a "stationary" verdict must
    /// have been able to see (80 % power); a weaker test says "inconclusive".
    double drift = 0.5;
};

/// Per-annulus comparison of the radial spectrum with theory.
struct SpectrumTheory {
    std::vector<double> power;  ///< expected annulus mean of the periodogram (value^2 px^2)
    std::vector<double> ratio;  ///< measured / theory
    std::vector<double> z;      ///< Wilson–Hilferty z of the ratio (NaN: annulus not compared)
    /// Relative covariance c that all annuli of one frame share through the fluctuating number
    /// and amplitudes of the impulses (compound Poisson fourth cumulant): Cov(P_b, P_b') =
    /// c P_b P_b' on top of the exponential scatter of each bin.
    std::vector<double> common;
    double max_abs_z = 0.0;  ///< over the compared annuli
    int compared = 0;        ///< annuli compared (non-empty, 0 < frequency < 0.5, theory > 0)
    double threshold = 0.0;  ///< Bonferroni threshold for `compared` tests, family alpha 0.01
    bool agrees = false;
    std::string
        not_judged;  ///< non-empty: no verdict, for this reason (e.g. clipped display values)
};

/// Closed-form statistics of the scene, as seen through the input (display mapping, pixels).
struct TheoryComparison {
    std::string scene;    ///< resolved scene path
    std::string hash;     ///< scene hash
    double zoom = 1.0;    ///< pixels per texture unit (camera)
    bool mapped = false;  ///< display input mapped back through [lo, hi]
    double map_lo = 0.0, map_hi = 1.0;
    double clipped_fraction = 0.0;  ///< display input: share of pixels at 0 or 1
    double field_mean = 0.0;        ///< Campbell's theorem (the scene's layer theory)
    double field_variance = 0.0;
    double mean = 0.0;               ///< expected sample mean (display censoring applied)
    double variance = 0.0;           ///< expected sample variance (less Var(mean), + quantisation)
    double sd_frame_mean = 0.0;      ///< sampling sd of one frame's mean
    double expected_frame_variance = 0.0;  ///< E[V] of one frame (less Var(frame mean))
    double sd_frame_variance = 0.0;  ///< sampling sd of one frame's variance
    double sd_mean = 0.0;            ///< sd of the pooled mean over the frames analysed
    double sd_variance = 0.0;        ///< sd of the pooled variance
    double z_mean = 0.0, z_variance = 0.0;
    bool mean_agrees = false, variance_agrees = false;
    double z_limit = 4.0;                    ///< |z| below this: agreement
    std::optional<SpectrumTheory> spectrum;  ///< absent when the camera zoom is animated
    std::string no_spectrum;                 ///< why `spectrum` is absent
    std::vector<double> autocovariance;      ///< expected ring values at lags 0..max_lag (or empty)
    std::optional<double> diff_variance;     ///< expected frame-difference variance (no flow)
    /// Variance of one frame's sample variance: the Gaussian part (2 sum S^2 / N^2, decorrelates
    /// in time as the field's correlation squared) and the impulse population's (fourth
    /// cumulant, as the envelope's fourth power).
    double frame_variance_gaussian = 0.0, frame_variance_population = 0.0;
    /// Cov(V_t, V_{t+l}) of the frame variances at lags l = 0..frames-1: both parts, each
    /// decorrelating with its layers' envelopes and with the uniform flows that carry new
    /// content through the window (docs/stationarity.md).
    std::vector<double> frame_variance_covariance;
};

/// Stationarity over time (sequences and videos with enough frames).
struct Stationarity {
    bool available = false;
    std::string reason;  ///< why not available
    int trend_blocks = 10;
    Trend trend;  ///< of the per-frame variance
    double t_limit = 4.0;
    int quarter = 0;                ///< frames in each of the first and last quarter
    SpectralDrift drift;  ///< first quarter against last quarter
    double q_eff = 1.0;             ///< independent frames each quarter is worth
    double common_variance = 0.0;   ///< largest relative variance of a quarter's common level
    std::vector<double>
        z_corrected;  ///< drift z with frame correlation and common level allowed for
    double max_abs_z_corrected = 0.0;  ///< max |z_corrected|
    double z_threshold = 0.0;          ///< Bonferroni threshold, family alpha 0.01
    /// The verdict: "stationary" (no test rejects at the family level, and a drift of
    /// `drift_of_interest` would have been seen with `power`), "not stationary" (a test
    /// rejects) or "inconclusive" (none rejects, but the frames could not have seen that drift).
    std::string verdict;
    double family_alpha = 0.01;  ///< false-alarm rate of the verdict, split over its three tests
    /// Level of the frame variance against its covariance when stationary (analysis.h): the
    /// trend's z (two-sided) and the block means' z (one-sided) at family_alpha / 3 each.
    LevelDrift level;
    std::string level_model;  ///< where that covariance comes from
    std::vector<double> level_covariance;  ///< that covariance C(l) = variance rho(l), l = 0..n-1
    /// Equivalent degrees of freedom of a block mean of the frame variance, 2 E[V]^2 / Var(block
    /// mean) (Satterthwaite): below min_block_dof the block means are too far from normal for
    /// the level tests' z (docs/stationarity.md), which then cannot reject: `level_note` says so.
    double block_dof = 0.0;
    double min_block_dof = 0.0;
    std::string level_note;
    double level_z_limit = 0.0, blocks_z_limit = 0.0;
    double power = 0.8;
    double detectable_drift = 0.0;   ///< relative change of the variance seen with `power`
    double drift_of_interest = 0.5;  ///< AnalyzeOptions::drift
    bool stationary = false;  ///< verdict == "stationary"
};

/// Power-spectrum summary of the frame-averaged 2-D periodogram.
struct PeriodogramSummary {
    std::string window;  ///< "none" (periodic frames) or "hann"
    bool periodic = false;
    double wrap_ratio_x = 0.0, wrap_ratio_y = 0.0;  ///< mean squared step across the wrap / inside
    double total_power = 0.0;  ///< sum of P / (w h): the variance the spectrum accounts for
    double peak_fx = 0.0, peak_fy = 0.0, peak_power = 0.0;  ///< strongest bin, cycles per pixel
    double centroid = 0.0;         ///< power-weighted mean |k|, cycles per pixel
    double anisotropy = 0.0;       ///< 1 - l2/l1 of the power-weighted tensor k k^T (0: isotropic)
    double orientation_deg = 0.0;  ///< direction of the principal axis of that tensor
    int heat_width = 0, heat_height = 0;
    std::vector<double> heat;  ///< centred, block-averaged log10 power for the report
};

struct AnalysisResult {
    std::string input;
    std::string kind;  ///< "image", "sequence" or "video"
    bool raw = true;   ///< float source (raw field values) or display values
    int bits = 32;     ///< bits per sample of the source
    int width = 0, height = 0;
    int frames = 0;
    long long first_frame = 0;
    Moments moments;      ///< of all pixels of all frames
    Histogram histogram;  ///< 64 bins over mean +- 4 sd
    PeriodogramSummary periodogram;
    RadialProfile spectrum;  ///< of the frame-averaged periodogram
    int max_lag = 0;
    std::vector<double> autocovariance;  ///< rings 0..max_lag, averaged over frames
    std::vector<FrameStats> frame_stats;
    /// Correlation between frames, as frames per independent one (n / effective n) for the
    /// frame mean, the frame variance and the periodogram; from the scene's envelopes, estimated
    /// from the frames (>= 10, no scene) or n (all frames counted as one).
    std::string tau_source = "none";  ///< "scene", "frames" or "none"
    double tau_mean = 1.0, tau_variance = 1.0, tau_spectrum = 1.0;
    Stationarity stationarity;
    std::optional<TheoryComparison> theory;
    /// With --structure: f(d) along x, y and the diagonal at dyadic lags up to a quarter of the
    /// frame, H(s) with its band over the frames (analysis/structure.cpp).
    std::optional<StructureSummary> structure;
    /// With a variance map requested: the per-pixel variance over the frames (Kaplan & Kuo
    /// Figs. 1-2; >= 2 frames).
    std::optional<Image> variance_map;
    std::vector<std::string> notes;
};

class ClosedForm;  // analysis/theory.h

/// The analysis of frames already in memory (values as they are; `raw` = false marks display
/// values for the theory comparison's mapping). `options.input` names them in the result.
/// `theory` is the closed form of options.scene (scenes::closed_form), required when a scene is
/// named.
AnalysisResult analyze_frames(std::vector<Image> frames, const AnalyzeOptions& options,
                              const std::string& kind, bool raw, int bits, long long first_frame,
                              const ClosedForm* theory = nullptr);

}  // namespace impulse::analysis
