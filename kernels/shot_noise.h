// SPDX-License-Identifier: Apache-2.0
#pragma once
// The marginal distribution of shot noise X = sum_k m_k a_k h(x - x_k) (Lewis 1986 §3: a
// Poisson process of intensity lambda, kernel h, i.i.d. symmetric amplitudes a_k, weight
// multipliers m_k such as a temporal envelope), computed from its characteristic function
// (Campbell / Levy–Khintchine):
//     log phi(u) = lambda E_m int (E_a[exp(i u m a h(x))] - 1) dx.
// The kernel enters only through the pushforward of dx by |h| (the area on which |h| takes each
// value), so every kernel type is handled alike by sampling h on a fine grid over its support.
// The jump law J = m a h is put on a lattice, and the compound Poisson law of the sum is exact
// on that lattice: p = IDFT(exp(DFT(rate) - Lambda)). Used as F_x by the distribution shaping
// (kernels/shaping.h). Included from the end of kernels/kernels.h.

#include <memory>
#include <utility>
#include <vector>

#include "kernels/kernel.h"

namespace impulse::kernels {

/// The law of the amplitudes a_k (all symmetric about 0): N(0, 1), uniform on [-1, 1], +-1.
/// Mirrors sim::Amplitude, which this library cannot see.
enum class AmplitudeLaw { Normal, Uniform, Sign };

/// The pushforward of the area measure by |h|: `area[b]` is the area (texture units^2) on which
/// |h| is near b * v_max / (bins - 1), the area of each grid cell split linearly between the two
/// nearest bins. Built from h at the midpoints of an n x n grid over the kernel's support box
/// in its own frame ([-R, R] x [-R / aspect, R / aspect]), then every value is scaled by one
/// factor so that sum area v^2 equals Kernel::integral_sq() exactly (the grid's error is a
/// rescaling of the variance, which Campbell's theorem fixes).
struct KernelValueLaw {
    double v_max = 0.0;
    std::vector<double> area;
    /// sum area v^2 / int h^2 before the rescaling (1 - the grid's relative error).
    double grid_ratio = 1.0;
};
/// Deterministic; n x n kernel evaluations (n = 512 by default: ~10-50 ms).
KernelValueLaw kernel_value_law(const Kernel& kernel, int bins = 2048, int n = 512);

/// A multiplier of the impulse weights and the relative rate of impulses that carry it: for a
/// still layer {gain, 1}; for an animated one, the envelope w at age a_i times the gain, with
/// the rate of births at t - a_i (1 per node without thinning, over the nodes' count).
struct WeightNode {
    double multiplier = 1.0;
    double rate = 1.0;
};

/// The CDF of X - E[X] on a lattice: symmetric, mean 0. Immutable; deterministic.
class ShotNoiseCdf {
public:
    static constexpr int kLattice = 1 << 15;

    /// lambda > 0 (impulses per unit area at rate 1), the kernel's value law, the amplitude law
    /// and the weight nodes (their rates scale lambda: live intensity = lambda sum rate).
    /// Throws ValueError when the variance is 0.
    ShotNoiseCdf(double lambda, const KernelValueLaw& values, AmplitudeLaw amplitude,
                 const std::vector<WeightNode>& weights);

    /// (F(x), 1 - F(x)) for X - E[X] = x, each from its own tail sum (full precision in both
    /// tails), F mid-point at the atoms (ties share the middle of their step, as the empirical
    /// F_x does); linear between lattice nodes.
    std::pair<double, double> operator()(double x) const;
    /// Standard deviation (Campbell: sqrt(lambda E[a^2] E[m^2] int h^2)).
    double sd() const { return m_sd; }
    /// Expected number of impulses with a nonzero value at a point (sum of the jump rates).
    double impulses() const { return m_rate; }
    /// Probability that no impulse reaches a point (exp(-impulses)): the atom at the mean.
    double atom() const;
    double step() const { return m_dx; }

private:
    std::vector<double> m_lower, m_upper;  ///< P(X < x_j) + p_j / 2 and P(X > x_j) + p_j / 2
    double m_dx = 1.0, m_sd = 0.0, m_rate = 0.0;
};

}  // namespace impulse::kernels
