// SPDX-License-Identifier: Apache-2.0
#pragma once
// Generalized stochastic subdivision (Lewis 1986 §2, Lewis 1987; docs/subdivision.md derives
// every equation cited here). Each level halves the spacing: a new node is the Wiener estimate
// x^ = sum_k a_k x_k from a neighbourhood of 2N (1-D) or 2N x 2N (2-D) nodes of the levels
// before it (Lewis 1987 eq. 3, 9, 10), plus a displacement u of variance
// R(0) - sum_k a_k R(target - k) (eq. 7), the a_k solving R(target - m) = sum_k a_k R(m - k)
// (eq. 4, 11, 12) for the autocorrelation at that level's spacing. Randomness is keyed by
// (seed, level, node) so a region computed later or larger agrees with the first where they
// overlap.
//
// Units: lags and positions are in output samples (the finest spacing is 1).

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace impulse::synth {

/// The autocorrelation R(x, y) of the field (x, y lags in output samples), R(-x, -y) = R(x, y);
/// 1-D synthesis uses R(x, 0).
struct Acf {
    std::function<double(double x, double y)> R;
    std::string name;  ///< for messages and the printed estimate
};

/// One --param KEY=VALUE.
using AcfParam = std::pair<std::string, std::string>;

/// R from a model name and its parameters (lengths in output samples):
/// - a named model of the kernels library defined by its autocorrelation: markov, gaussian,
///   markaussian, matern, oscillatory_markov (e^{-r/l} cos(omega r), Lewis 1987 Table 1),
///   oscillatory_gaussian (cos(omega r) e^{-r^2/l^2}, Lewis 1986 Fig. 1); keys variance,
///   length, exponent, nu, omega;
/// - `expression` with key expr: R of r (radial profile) or of x and y (any 2-D function);
/// - `table` with key file: a CSV file of rows r,R (linear in between, 0 beyond the last row).
/// The profile models and expressions of r take the anisotropy keys aspect (>= 1: the
/// correlation is `aspect` times longer along `angle` than across it), angle (degrees from +x)
/// and separable (1: R(u) R(v) / R(0) in the rotated frame instead of the swept R(|(u, v)|)).
/// Throws ValueError naming the key.
Acf make_acf(const std::string& model, const std::vector<AcfParam>& params);

/// The remedies of Lewis 1987 §4.3 for a numerically singular neighbourhood matrix.
enum class Singular {
    Reduce,        ///< the largest neighbourhood whose matrix is positive definite
    PseudoInverse  ///< the Moore–Penrose inverse at the requested size
};

struct GssOptions {
    int dims = 2;           ///< 1 or 2
    int max_neighbors = 8;  ///< largest neighbourhood size 2N per axis (even, 2 .. 16)
    /// Error threshold (Lewis 1987 §4.1): per level and class the smallest N whose estimation
    /// error (eq. 7) is within tolerance * R(0) of the largest neighbourhood's. 0: always the
    /// largest (max_neighbors).
    double tolerance = 1e-4;
    Singular singular = Singular::Reduce;
    /// 2-D diagonal-bias remedy (Lewis 1987 §6.1): grow N (up to max_neighbors) until the
    /// largest coefficient on the outer ring is at most debias * the largest coefficient.
    /// 0: off.
    double debias = 0.05;
    /// Spacing of the coarsest level, a power of two; 0: the smallest power of two beyond
    /// which |R| <= top_correlation * R(0) (its nodes are drawn independently, as Lewis seeds
    /// the subdivision "using uncorrelated random numbers").
    int top_spacing = 0;
    double top_correlation = 1e-3;
    uint64_t seed = 0;
    /// false: independent displacements of variance (7), as in the paper; true: the same
    /// variances, correlated between the level's new nodes so their covariance is R
    /// (docs/subdivision.md "Correlated displacements").
    bool correlated = true;
};

/// Throws ValueError naming the first invalid option.
void validate(const GssOptions& options);

/// Coefficients of one class of new nodes at one level.
struct ClassCoefficients {
    std::string name;      ///< "mid" (1-D), "face", "edge_x", "edge_y"
    int tx2 = 1, ty2 = 0;  ///< target offset in half coarse cells from node (t_x, t_y)
    int neighbors = 0;     ///< 2N, the neighbourhood size per axis
    /// Observation offsets (c, r) in coarse cells from (t_x, t_y), row-major (r outer).
    std::vector<std::pair<int, int>> offsets;
    std::vector<double> a;        ///< a_k, one per offset (eq. 4, 11, 12)
    double variance = 0.0;        ///< displacement variance, eq. 7
    bool pseudo_inverse = false;  ///< solved by the Moore–Penrose inverse (singular matrix)
};

/// Correlated displacements (GssOptions::correlated): u_k(p) = sum_{k'} sum_j
/// beta[k][k'](j) w_{k'}(p + j), w the keyed normals of the level's new nodes, cells p, j in
/// [-radius, radius]^dims (docs/subdivision.md "Correlated displacements").
struct DisplacementFilter {
    int radius = 0;  ///< J; -1: independent displacements (the paper's)
    /// beta[(k * classes + k') * side^dims + (jy + J) * side + (jx + J)], side = 2J + 1
    std::vector<double> beta;
};

struct LevelPlan {
    int spacing = 1;  ///< the new (finer) spacing h in output samples; coarse spacing 2h
    std::vector<ClassCoefficients> classes;
    DisplacementFilter filter;
    int max_n() const;  ///< the largest N of the level's classes
};

struct Plan {
    int dims = 1;
    int top_spacing = 1;            ///< spacing of the coarsest level (power of two)
    double variance = 0;            ///< R(0)
    std::vector<LevelPlan> levels;  ///< coarsest first
};

/// The coefficients of every level from spacing `top_spacing` down to 1 (top_spacing a power
/// of two; 0: chosen as GssOptions::top_spacing says). Throws ValueError when R is not
/// non-negative definite (a negative eigenvalue of a neighbourhood's covariance matrix with its
/// target, Lewis 1987 §6.2 "negative determinants").
Plan plan_subdivision(const Acf& acf, const GssOptions& options, int top_spacing = 0);

/// The displacement filter of one level (its classes solved): the spectral square root of the
/// covariance R - (covariance of the estimates) the new nodes lack.
DisplacementFilter displacement_filter(const Acf& acf, int dims, double s,
                                       const std::vector<ClassCoefficients>& classes);

/// The automatic top spacing (GssOptions::top_spacing = 0), R scanned to lags of `limit`
/// samples (a periodic field's period: a coarser top is clipped to it anyway).
int auto_top_spacing(const Acf& acf, const GssOptions& options, int limit = 1 << 22);

/// Coefficients of one class for coarse spacing s and the observation offsets given (for
/// neighbourhoods clipped by a boundary). Exposed for tests and the refinement.
ClassCoefficients solve_class(const Acf& acf, double s, int tx2, int ty2,
                              const std::vector<std::pair<int, int>>& offsets, Singular singular);

/// A synthesized field: width x height samples, row-major, top row first; sample (i, j) is at
/// position (x0 + i, y0 + j). 1-D: height 1.
struct Field {
    int64_t x0 = 0, y0 = 0;
    int width = 0, height = 0;
    std::vector<double> values;
    Plan plan;
};

/// Extendable output: the region [x0, x0 + width) x [y0, y0 + height) of the infinite field of
/// `seed`; any two regions agree where they overlap. Sizes: 2^k + 1 samples per axis
/// (k >= 1; 1-D: height 1). Periodic output: the field of period width (x height), sizes 2^k,
/// x0 = y0 = 0. Throws ValueError for other sizes.
Field synthesize(const Acf& acf, const GssOptions& options, int64_t x0, int64_t y0, int width,
                 int height, bool periodic = false);
/// The same with a plan made before (plan_subdivision, or Field::plan of an earlier call with
/// the same autocorrelation, options and, when periodic, size): the per-level solves and
/// displacement filters are not repeated. Only options.seed may differ.
Field synthesize(Plan plan, const GssOptions& options, int64_t x0, int64_t y0, int width,
                 int height, bool periodic = false);

/// Refinement (Lewis 1987 Fig. 5): data (w x h, row-major; h = 1 for 1-D) at every factor-th
/// node of a ((w - 1) factor + 1) x ((h - 1) factor + 1) field; the data are kept exactly,
/// the finer levels are synthesized around them. Neighbourhoods are clipped at the data's
/// edges (their coefficients solved for the nodes that exist). The mean of the data is the
/// field's mean. factor a power of two >= 2.
Field refine(const std::vector<double>& data, int w, int h, int factor, const Acf& acf,
             const GssOptions& options);

/// Lewis 1987 eq. 15 estimate of R at integer lags (in data samples) and a fitted model.
struct AcfEstimate {
    double mean = 0, variance = 0;
    std::vector<double> along_x, along_y;  ///< R^(lag, 0), R^(0, lag), lag = 0 .. max
    /// variance * exp(-(d / length)^exponent), d the distance in output samples (a
    /// markaussian fitted to the estimates at the lags where they are positive).
    double length = 1, exponent = 1;
    Acf acf;              ///< the fitted model, lags in output samples
    std::string summary;  ///< the printed estimate
};
/// Estimates from data sampled every `factor` output samples (lengths scaled by it).
AcfEstimate estimate_acf(const std::vector<double>& data, int w, int h, int factor);

/// One standard normal per (seed, level, node position): the displacement of that node.
double node_normal(uint64_t seed, int level, int64_t x, int64_t y);

/// The JSON {"levels": [{"spacing", "neighbors", "coefficients", "variance"}, ...]}.
std::string plan_json(const Plan& plan);

}  // namespace impulse::synth
