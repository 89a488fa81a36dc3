// SPDX-License-Identifier: Apache-2.0
#pragma once
// Distribution shaping (Lewis 1986 §4): a memoryless monotone transfer g = F_y^-1(F_x(x))
// that gives a layer a chosen marginal distribution F_y, and the spectrum pre-correction of
// §4.1 ("design the spectrum of the undistorted noise so that a desired spectrum is achieved
// after distortion"), done with the iterative translation approximation method (ITAM) of
// Shields, Deodatis & Bocchini 2011. Included from the end of kernels/kernels.h.
//
// Which F_x (the layer's own marginal) to use:
//  * Shot noise (the default): the exact law of the unshaped layer, from its characteristic
//    function (Campbell / Levy–Khintchine, kernels/shot_noise.h) for the layer's kernel,
//    amplitude law, envelope and density, tabulated once per layer on a lattice of 2^15 nodes.
//    It carries the kurtosis and the atom of a sparse layer (a fraction exp(-impulses in reach)
//    of the plane sits exactly at the mean), which g maps to the middle of its step, so the
//    shaped layer misses its target by about half that atom: the KS distance measured on
//    rendered frames of a cosine layer (tests/scenes/test_shaping_accuracy.cpp) is at the
//    sampling noise (< 0.006 on 65536 independent pixels) from density 8 for normal, uniform
//    and sign amplitudes, and 0.010-0.013 at density 4 (exp(-4) / 2 = 0.009).
//  * Gaussian with the layer's closed-form mean and variance. Shot noise is a sum of many
//    kernels, so it is close to Gaussian when each point is covered by many impulses: its
//    excess kurtosis is E[a^4] int h^4 / (lambda E[a^2]^2 (int h^2)^2) (3 pi / density for a
//    still cosine kernel with normal amplitudes, pi / density with +-1 amplitudes;
//    scenes::layer_moments), and the Kolmogorov distance between F_x and the Gaussian is
//    about 0.023 x that kurtosis (Edgeworth): 0.014 at density 16 and 0.03 at density 8, so
//    KS <~ 0.01 needs a cosine kernel with normal amplitudes at density >~ 24. Always used for
//    the spectrum pre-correction, which models the field as Gaussian.
//  * Empirical: F_x measured on a calibration sample of the layer's own values (any layer,
//    including other synthesizers' sources, keyframes refused). It cannot undo atoms either.

#include <functional>
#include <optional>
#include <span>
#include <utility>

#include "kernels/kernel.h"
#include "kernels/shot_noise.h"

namespace impulse::kernels {

/// Target marginal distributions F_y.
enum class MarginalType { Uniform, Exponential, Laplace, Lognormal, StudentT, Empirical };

/// Names accepted in scene files, in enum order.
inline constexpr std::array<std::string_view, 6> kMarginalTypeNames = {
    "uniform", "exponential", "laplace", "lognormal", "student_t", "empirical"};

/// Name of a marginal type ("lognormal", ...).
std::string_view to_string(MarginalType type);
/// Marginal type from its name; nullopt when unknown.
std::optional<MarginalType> marginal_type_from_string(std::string_view name);

/// Parameters of a target distribution; only the fields of `type` are used.
struct MarginalParams {
    MarginalType type = MarginalType::Uniform;
    double a = 0.0;      ///< uniform: lower end of the support
    double b = 1.0;      ///< uniform: upper end, > a
    double rate = 1.0;   ///< exponential: rate > 0 (density rate exp(-rate y), y >= 0)
    double mu = 0.0;     ///< laplace, student_t: location; lognormal: mean of log y
    double scale = 1.0;  ///< laplace: b > 0 in exp(-|y - mu| / b) (Lewis 1986 §4); student_t: > 0
    double sigma = 1.0;  ///< lognormal: standard deviation of log y, > 0
    double nu = 4.0;     ///< student_t: degrees of freedom, > 2 (finite variance)
    /// empirical: >= 2 finite values, not all equal (e.g. an exemplar image's pixels); the
    /// distribution is their sample quantile function interpolated linearly (R's type 7).
    std::shared_ptr<const std::vector<double>> samples;
};

/// Throws impulse::ValueError naming the first invalid field ("marginal.sigma = -1: must be > 0").
void validate(const MarginalParams& params);

/// A target distribution: CDF, quantile function and moments. Immutable.
class Distribution {
public:
    /// Validates (throws ValueError).
    explicit Distribution(const MarginalParams& params);
    const MarginalParams& params() const { return m_params; }
    /// F_y(y).
    double cdf(double y) const;
    /// F_y^-1 given p and q = 1 - p computed separately, so both tails keep full precision
    /// (p, q in (0, 1), p + q = 1).
    double quantile(double p, double q) const;
    double quantile(double p) const { return quantile(p, 1.0 - p); }
    double mean() const { return m_mean; }
    double variance() const { return m_variance; }

private:
    MarginalParams m_params;
    std::vector<double> m_sorted;  ///< empirical: sorted samples
    double m_mean = 0.0, m_variance = 0.0;
};

/// How F_x, the layer's own marginal, is obtained (see the top of this file).
enum class SourceCdf { Gaussian, Empirical, ShotNoise };
inline constexpr std::array<std::string_view, 3> kSourceCdfNames = {"gaussian", "empirical",
                                                                    "shot_noise"};

/// g = F_y^-1(F_x(.)) tabulated for fast, monotone evaluation: kTableSize entries, linear
/// interpolation, clamped at the ends. Gaussian and shot-noise F_x: the table spans mean +- 8 sd
/// (beyond that, probability 1e-15 for the Gaussian, below 1e-6 for shot noise at density 4). Empirical F_x: it spans the calibration sample's range; F_x is
/// the mid-rank CDF of the sample (ties share the middle of their step). Immutable, cheap to
/// share; evaluation is deterministic.
class MarginalTransform {
public:
    static constexpr int kTableSize = 4096;
    static constexpr double kHalfWidthSd = 8.0;

    /// F_x Gaussian with the given mean and standard deviation (> 0). Throws ValueError.
    MarginalTransform(const MarginalParams& target, double source_mean, double source_sd);
    /// F_x the shot noise law `cdf` of X - source_mean (kernels/shot_noise.h).
    MarginalTransform(const MarginalParams& target, double source_mean,
                      std::shared_ptr<const ShotNoiseCdf> cdf);
    /// F_x measured on `calibration` (>= 2 finite values, not all equal). Throws ValueError.
    MarginalTransform(const MarginalParams& target, std::span<const float> calibration);

    /// g(x) from the table.
    float operator()(float x) const;
    /// values[i] = g(values[i] + offset), in place.
    void apply(std::span<float> values, double offset = 0.0) const;
    /// g(x) without the table, in double.
    double exact(double x) const;
    /// The translation function used by the spectrum pre-correction: y = F_y^-1(Phi(z)) of a
    /// standard Gaussian z, with z clamped to +-kHalfWidthSd like the table.
    double standard(double z) const;

    const Distribution& target() const { return m_target; }
    SourceCdf source() const { return m_source; }
    /// Mean and standard deviation of F_x (for an empirical F_x: of the calibration sample).
    double source_mean() const { return m_source_mean; }
    double source_sd() const { return m_source_sd; }
    /// The table: entry i is g(table_x0() + i * table_step()).
    const std::vector<float>& table() const { return m_table; }
    double table_x0() const { return m_x0; }
    double table_step() const { return m_step; }

private:
    void build_table(double x0, double x1);
    /// F_x as (p, q = 1 - p).
    std::pair<double, double> source_cdf(double x) const;

    Distribution m_target;
    SourceCdf m_source = SourceCdf::Gaussian;
    double m_source_mean = 0.0, m_source_sd = 1.0;
    std::shared_ptr<const std::vector<float>> m_calibration;  ///< sorted; empirical F_x only
    std::shared_ptr<const ShotNoiseCdf> m_shot_noise;          ///< shot-noise F_x only
    std::vector<float> m_table;
    double m_x0 = 0.0, m_step = 1.0, m_inv_step = 1.0;
};

/// The translation-process correlation map (Lewis 1986 §4.1 after Beckmann; Grigoriu 1995):
/// for standard Gaussians Z1, Z2 with correlation rho and Y = g(Z) (MarginalTransform::standard),
///     Cov(Y1, Y2) = R_Y(rho) = sum_{n>=1} c_n^2 / n! rho^n,  c_n = E[g(Z) He_n(Z)],
/// He_n the probabilists' Hermite polynomials. The c_n are computed by composite 16-point
/// Gauss–Legendre quadrature of g(z) He_n(z) phi(z) on [-8, 8] plus the exact tails of the
/// clamped g, rather than Gauss–Hermite: g can have kinks (empirical targets) and grow fast
/// (heavy tails), where Gauss–Hermite converges slowly. R_Y is increasing on [-1, 1] for a
/// monotone g, so it has an inverse.
class TranslationMap {
public:
    static constexpr int kMaxTerms = 256;
    explicit TranslationMap(const MarginalTransform& g);

    /// R_Y(rho), rho in [-1, 1] (clamped); the series' missing tail (remainder()) is added as
    /// remainder * rho^(N+1), so R_Y(1) = variance() exactly.
    double covariance(double rho) const;
    /// rho with R_Y(rho) = r; clamped to [-1, 1] when r is outside [R_Y(-1), R_Y(1)].
    double inverse(double r) const;
    /// E[Y] = c_0 and Var Y = R_Y(1) by quadrature.
    double mean() const { return m_mean; }
    double variance() const { return m_variance; }
    /// R_Y(-1) / R_Y(1): the most negative correlation a translated field can have.
    double min_correlation() const { return covariance(-1.0) / m_variance; }
    /// c_n / sqrt(n!), n = 0 .. N.
    const std::vector<double>& coefficients() const { return m_b; }
    /// Var Y - sum_{n=1}^N c_n^2 / n! (>= 0).
    double remainder() const { return m_remainder; }

private:
    std::vector<double> m_b;
    double m_mean = 0.0, m_variance = 0.0, m_remainder = 0.0;
};

/// Options of the spectrum pre-correction.
struct ItamOptions {
    /// Converged when the shaped spectrum is within this relative error of the target wherever
    /// the target is above 1 % of its peak; (0, 1)
    double tolerance = 0.02;
    int max_iterations = 200;  ///< 0: only predict the shaped spectrum of the kernel as it is
};

/// What the pre-correction achieved. Spectra are radial spectral densities of the shaped field
/// (value^2 per (cycle/unit)^2) on a grid of frequencies in cycles per unit.
struct PrecorrectionReport {
    bool converged = false;       ///< max_band_error <= tolerance
    int iterations = 0;           ///< ITAM iterations run
    double residual = 0.0;        ///< sqrt(int (S_Y - S_T)^2 k dk / int S_T^2 k dk), final kernel
    double max_band_error = 0.0;  ///< max |S_Y / S_T - 1| where S_T >= 1 % of its peak
    /// The direct inversion S_G = H^-1[rho(R_T)] needs negative values: their share of its
    /// mass (0 for a compatible target; > 0 means no Gaussian spectrum maps exactly onto it).
    double negative_fraction = 0.0;
    /// Share of the target's correlation curve (by r) below the translated field's most
    /// negative reachable correlation R_Y(-1) / Var Y.
    double unreachable_fraction = 0.0;
    std::string message;  ///< one line: what happened, with the residual
    std::vector<double> frequency, target, achieved;
};

/// A kernel whose shaped field has the target spectrum, and the report.
struct Precorrection {
    KernelParams kernel;  ///< Sampled radial kernel (the input kernel when max_iterations == 0)
    PrecorrectionReport report;
};

/// ITAM (Shields, Deodatis & Bocchini 2011): find the Gaussian spectrum S_G whose translated
/// field g(X) has the spectrum of `kernel` (shape only: S_T = Var Y * |H|^2 / int h^2), by
/// S_G <- S_G S_T / S_Y on a radial frequency grid, correlations by Hankel transforms
/// R(r) = 2 pi int S(k) J0(2 pi k r) k dk and the TranslationMap. S_G is updated where S_T is
/// above 1e-3 of its peak and keeps the target's shape beyond. Returns h = H^-1[sign(H) sqrt(S_G)]
/// as a Sampled radial kernel with the same int h^2 (so the unshaped variance is unchanged),
/// truncated at the smallest radius (a multiple of R / 4) that keeps the worst band within half
/// the budget left between ITAM's result and the tolerance: typically 2-3 R, so rendering costs
/// 4-9 times more. The report is for the truncated kernel. Isotropic kernels only (cosine,
/// gaussian, radial sampled with aspect 1); throws ValueError otherwise. The dynamics are
/// untouched, so it serves animated layers too. Deterministic; about 0.1-0.3 s.
///
/// Not every target is reachable: S_Y = sum_n c_n^2/n! S_G^{*n} holds self-convolutions of S_G,
/// wider than S_T, so a strongly skewed marginal (lognormal sigma >= ~0.75) cannot follow a
/// fast-decaying (e.g. Gaussian) spectrum near 1 % of its peak whatever S_G >= 0 is; and
/// correlations below R_Y(-1) / Var Y cannot be reached at all. Then the report says so, with
/// the residual, and the kernel is the closest found.
Precorrection precorrect_spectrum(const Kernel& kernel, const MarginalTransform& g,
                                  const ItamOptions& options = {});
/// Same for any isotropic target spectral density S_T(k) (k in cycles per unit; only its shape
/// matters); `length` (> 0) is its correlation length scale, which sets the grids (r up to
/// 8 length, k up to 16 / length). The kernel is H^-1[sqrt(S_G)], scaled to int h^2 = 1.
Precorrection precorrect_spectrum(const std::function<double(double)>& target, double length,
                                  const MarginalTransform& g, const ItamOptions& options = {});

}  // namespace impulse::kernels
