// SPDX-License-Identifier: Apache-2.0
// The marginal law of shot noise from its characteristic function (Campbell / Levy–Khintchine),
// exact on a lattice: see kernels/shot_noise.h.

#include "kernels/shot_noise.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "numeric/errors.h"
#include "numeric/fft.h"

namespace impulse::kernels {

KernelValueLaw kernel_value_law(const Kernel& kernel, int bins, int n) {
    if (bins < 2 || n < 2) throw ValueError("kernel_value_law: needs bins >= 2 and n >= 2");
    const double R = kernel.radius(), a = kernel.params().aspect;
    // Sample in the kernel's own frame (theta = -orientation undoes its turn), so an elongated
    // kernel's narrow axis gets all n samples too.
    const double hu = 2.0 * R / n, hv = 2.0 * R / (a * n), cell = hu * hv;
    const double theta = -kernel.params().orientation;
    std::vector<double> v(size_t(n) * n);
    double v_max = 0.0, sum2 = 0.0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double h =
                std::abs(kernel.evaluate(-R + (i + 0.5) * hu, -R / a + (j + 0.5) * hv, theta));
            v[size_t(j) * n + i] = h;
            v_max = std::max(v_max, h);
            sum2 += h * h;
        }
    KernelValueLaw law;
    law.area.assign(size_t(bins), 0.0);
    if (!(v_max > 0.0) || !(kernel.integral_sq() > 0.0)) return law;
    // Campbell's variance is lambda E[a^2] int h^2: rescale the values so the grid agrees.
    law.grid_ratio = sum2 * cell / kernel.integral_sq();
    const double scale = 1.0 / std::sqrt(law.grid_ratio);
    law.v_max = v_max * scale;
    const double to_bin = (bins - 1) / v_max;
    for (double h : v) {
        const double t = h * to_bin;
        const int b = std::min(static_cast<int>(t), bins - 2);
        const double f = t - b;
        law.area[size_t(b)] += cell * (1.0 - f);
        law.area[size_t(b) + 1] += cell * f;
    }
    return law;
}

namespace {

/// The jumps' rate measure on a periodic lattice of spacing dx: index j >= 0 holds position
/// j dx, index N + j position j dx for j < 0.
class JumpLattice {
public:
    explicit JumpLattice(int n) : m_rate(size_t(n), 0.0), m_n(n) {}
    std::vector<double>& rate() { return m_rate; }

    /// Rate r of jumps +-s, s = t dx, half each, split linearly between the nearest nodes.
    void add_sign(double t, double r) {
        const int j = static_cast<int>(t);
        const double f = t - j;
        add_pair(j, r * (1.0 - f));
        add_pair(j + 1, r * f);
    }
    /// Rate r of jumps uniform on [-s, s], s = t dx: the exact linear-split mass of node j is
    /// the second difference G(j + 1) - 2 G(j) + G(j - 1) of G(c) = int_{-inf}^c F, F the jumps'
    /// CDF in lattice units (G = (c + t)^2 / 4t on [-t, t], c beyond it). Inside, 1 / 2t.
    void add_uniform(double t, double r) {
        auto G = [t](double c) { return c < -t ? 0.0 : c > t ? c : (c + t) * (c + t) / (4.0 * t); };
        const int last = static_cast<int>(t) + 1;
        for (int j = 0; j <= last; ++j) {
            const double m = (j + 1 <= t) ? 1.0 / (2.0 * t) : G(j + 1.0) - 2.0 * G(j) + G(j - 1.0);
            add_pair(j, j == 0 ? r * m : 2.0 * r * m);
        }
    }
    /// Rate r of jumps N(0, s^2), s = t dx: the density sampled at the nodes and normalised (the
    /// sampled Gaussian keeps its variance to rounding for t >= 1); below one node, three nodes
    /// holding the variance t^2 exactly.
    void add_normal(double t, double r) {
        if (t < 1.0) {
            m_rate[0] += r * (1.0 - t * t);
            add_pair(1, r * t * t);
            return;
        }
        const int last = static_cast<int>(std::ceil(8.5 * t));
        m_w.resize(size_t(last) + 1);
        double sum = 0.0;
        // exp(-j^2 / 2t^2) by the recurrence w_{j+1} = w_j r_j, r_{j+1} = r_j c (two products
        // a node instead of an exp; relative rounding j x 1e-16).
        const double c = std::exp(-1.0 / (t * t));
        double w = 1.0, ratio = std::exp(-0.5 / (t * t));
        for (int j = 0; j <= last; ++j) {
            m_w[size_t(j)] = w;
            sum += (j == 0 ? 1.0 : 2.0) * w;
            w *= ratio;
            ratio *= c;
        }
        m_rate[0] += r * m_w[0] / sum;
        for (int j = 1; j <= last; ++j) add_pair(j, 2.0 * r * m_w[size_t(j)] / sum);
    }

private:
    /// Rate r split evenly between nodes +j and -j (all of it at node 0 for j = 0).
    void add_pair(int j, double r) {
        if (j == 0) {
            m_rate[0] += r;
            return;
        }
        m_rate[size_t(j)] += 0.5 * r;
        m_rate[size_t(m_n - j)] += 0.5 * r;
    }
    std::vector<double> m_rate, m_w;
    int m_n;
};

double amplitude_second_moment(AmplitudeLaw a) {
    return a == AmplitudeLaw::Uniform ? 1.0 / 3.0 : 1.0;
}

/// The scales s = |m| v of the jumps with their rates (lambda x node rate x area), binned like
/// the kernel's values on [0, s_max].
std::vector<double> jump_scales(double lambda, const KernelValueLaw& values,
                                const std::vector<WeightNode>& weights, double& s_max) {
    double m_max = 0.0;
    for (const auto& w : weights) m_max = std::max(m_max, std::abs(w.multiplier));
    s_max = m_max * values.v_max;
    const int bins = static_cast<int>(values.area.size());
    std::vector<double> rate(size_t(bins), 0.0);
    if (!(s_max > 0.0)) return rate;
    for (const auto& w : weights) {
        const double to_bin = std::abs(w.multiplier) / m_max;
        for (int b = 0; b < bins; ++b) {
            const double t = b * to_bin;
            const int i = std::min(static_cast<int>(t), bins - 2);
            const double f = t - i, r = lambda * w.rate * values.area[size_t(b)];
            rate[size_t(i)] += r * (1.0 - f);
            rate[size_t(i) + 1] += r * f;
        }
    }
    return rate;
}

/// The compound Poisson law on the lattice of a jump rate measure (symmetric, wrapped as in
/// JumpLattice): P^ = exp(rate^ - Lambda) (Levy–Khintchine; the transform of a symmetric measure
/// is real), unwrapped so index j holds position (j - N/2) dx; rounding below 0 is cut.
std::vector<double> compound_poisson(const std::vector<double>& rate) {
    const int N = static_cast<int>(rate.size());
    numeric::RealFft2d fft(1, N, numeric::FftPlans::Both);
    double total = 0.0;
    for (int j = 0; j < N; ++j) total += rate[size_t(j)];
    std::copy(rate.begin(), rate.end(), fft.real());
    fft.forward();
    for (int k = 0; k < fft.half_cols(); ++k)
        fft.spectrum()[k] = std::exp(fft.spectrum()[k].real() - total);
    fft.inverse();
    std::vector<double> p(static_cast<size_t>(N));
    for (int j = 0; j < N; ++j) p[size_t(j)] = std::max(fft.real()[(j + N / 2) % N] / N, 0.0);
    return p;
}

}  // namespace

ShotNoiseCdf::ShotNoiseCdf(double lambda, const KernelValueLaw& values, AmplitudeLaw amplitude,
                           const std::vector<WeightNode>& weights) {
    double s_max = 0.0;
    const std::vector<double> scale_rate = jump_scales(lambda, values, weights, s_max);
    const int bins = static_cast<int>(scale_rate.size());
    double var = 0.0;
    for (int b = 1; b < bins; ++b) {
        const double s = s_max * b / (bins - 1);
        var += scale_rate[size_t(b)] * s * s;
        m_rate += scale_rate[size_t(b)];
    }
    var *= amplitude_second_moment(amplitude);
    if (!(var > 0.0) || !std::isfinite(var)) {
        std::ostringstream s;
        s << "marginal: layer standard deviation = " << std::sqrt(std::max(var, 0.0))
          << ": must be > 0 (a constant layer cannot be shaped)";
        throw ValueError(s.str());
    }
    m_sd = std::sqrt(var);
    // The lattice spans +-(12 sd + 9 s_max): the sum beyond is below 1e-15 for every layer
    // with more than about one impulse in reach (its tails are lighter than 12 sd plus a few
    // of the largest jumps), and wraps around only that far.
    const int N = kLattice;
    m_dx = 2.0 * (12.0 * m_sd + 9.0 * s_max) / N;
    JumpLattice lattice(N);
    for (int b = 1; b < bins; ++b) {
        const double r = scale_rate[size_t(b)];
        if (r == 0.0) continue;
        const double t = s_max * b / (bins - 1) / m_dx;
        switch (amplitude) {
            case AmplitudeLaw::Sign:
                lattice.add_sign(t, r);
                break;
            case AmplitudeLaw::Uniform:
                lattice.add_uniform(t, r);
                break;
            case AmplitudeLaw::Normal:
                lattice.add_normal(t, r);
                break;
        }
    }
    const std::vector<double> p = compound_poisson(lattice.rate());
    m_lower.resize(size_t(N));
    m_upper.resize(size_t(N));
    double below = 0.0, above = 0.0;
    for (int j = 0; j < N; ++j) {
        m_lower[size_t(j)] = below + 0.5 * p[size_t(j)];
        below += p[size_t(j)];
        const int k = N - 1 - j;
        m_upper[size_t(k)] = above + 0.5 * p[size_t(k)];
        above += p[size_t(k)];
    }
}

std::pair<double, double> ShotNoiseCdf::operator()(double x) const {
    const int N = kLattice;
    const double t = std::clamp(x / m_dx + N / 2, 0.0, N - 1.0);
    const int i = std::min(static_cast<int>(t), N - 2);
    const double f = t - i;
    const double p = m_lower[size_t(i)] * (1.0 - f) + m_lower[size_t(i) + 1] * f;
    const double q = m_upper[size_t(i)] * (1.0 - f) + m_upper[size_t(i) + 1] * f;
    return {std::clamp(p, 1e-300, 1.0), std::clamp(q, 1e-300, 1.0)};
}

double ShotNoiseCdf::atom() const { return std::exp(-m_rate); }

}  // namespace impulse::kernels
