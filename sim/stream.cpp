// SPDX-License-Identifier: Apache-2.0
// A still layer's field as a stream function: the flow along its level lines. The same lattice
// and Catmull-Rom interpolation as curl noise (sim/detail/lattice.h), with the layer's own kernel in
// place of the (1 - q)^3 bump and the normalisation computed from its semivariogram.

#include <cmath>
#include <sstream>

#include "sim/sim.h"
#include "sim/detail/lattice.h"
#include "numeric/errors.h"

namespace impulse::sim {
namespace {

constexpr int kNodesPerCell = 8;

/// Adds a cell's terms a_k h(X - x_k; theta_k) at node (X, Y).
struct KernelContribution {
    std::function<double(double, double, double)> kernel;
    double r2 = 0.0;
    bool random = false;
    void operator()(double X, double Y, const CellImpulses& c, double& value) const {
        for (size_t k = 0; k < c.x.size(); ++k) {
            const double dx = X - c.x[k], dy = Y - c.y[k];
            if (dx * dx + dy * dy >= r2) continue;
            const double theta = random ? static_cast<double>(c.theta0[k]) : 0.0;
            value += c.amplitude[k] * kernel(dx, dy, theta);
        }
    }
};

class StreamFunctionFlow final : public detail::LatticeStreamFlow<KernelContribution> {
public:
    StreamFunctionFlow(const StreamFunction& psi, Keyframed speed)
        : LatticeStreamFlow(psi.process, kNodesPerCell, std::move(speed)) {
        m_contribution = {psi.kernel, psi.radius * psi.radius,
                          psi.process.orientation == OrientationMode::Random};
        // Unit RMS speed: divide by sqrt(E|grad psi|^2) (gain cancels but for its sign).
        m_norm = (psi.gain < 0 ? -1.0 : 1.0) / std::sqrt(stream_gradient_variance(psi));
    }
};

void validate(const StreamFunction& psi) {
    std::ostringstream s;
    if (psi.process.lifetime_s > 0) s << "stream function: the process must be still (lifetime 0)";
    else if (!(psi.radius > 0) || psi.process.cell_size < psi.radius)
        s << "stream function: expected 0 < radius <= cell_size";
    else if (!(psi.gain != 0) || !std::isfinite(psi.gain))
        s << "stream function: expected a finite gain != 0";
    else if (!psi.kernel || !psi.semivariogram)
        s << "stream function: kernel and semivariogram are required";
    if (!s.str().empty()) throw ValueError(s.str());
}

}  // namespace

double stream_gradient_variance(const StreamFunction& psi) {
    validate(psi);
    // psi_I(x) = sum_ab w_a(tx) w_b(ty) psi(i - 1 + a, j - 1 + b), so d psi_I/dx =
    // (1/hx) sum_ab d_a(tx) w_b(ty) psi_ab and, psi being stationary with covariance
    // K(tau) = lambda E[a^2] C(tau) (Campbell), its mean square over a lattice cell is
    // (1/hx^2) sum_pq D(p) W(q) K(p hx, q hy), D(p) = sum_{a - a' = p} int_0^1 d_a d_a' dt and
    // W(q) likewise from w. The weights are cubics: 4-point Gauss-Legendre is exact. D sums to
    // zero (the d_a do, the w_a summing to 1), so C may be replaced by -(C(0) - C): the
    // semivariogram, whose quadrature keeps its accuracy where C(0) - C is small.
    const double gx[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                          0.8611363115940526};
    const double gw[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                          0.3478548451374538};
    double D[7] = {0}, W[7] = {0};  // index p + 3
    for (int g = 0; g < 4; ++g) {
        double w[4], d[4], dd[4];
        detail::catmull_rom(0.5 * (1.0 + gx[g]), w, d, dd);
        for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) {
                D[a - b + 3] += 0.5 * gw[g] * d[a] * d[b];
                W[a - b + 3] += 0.5 * gw[g] * w[a] * w[b];
            }
    }
    const detail::Layout layout(psi.process);
    const double hx = layout.cell_x / kNodesPerCell, hy = layout.cell_y / kNodesPerCell;
    const double scale = psi.process.intensity * amplitude_second_moment(psi.process.amplitude);
    double sum = 0.0;
    for (int q = -3; q <= 3; ++q)
        for (int p = -3; p <= 3; ++p) {
            const double weight = D[p + 3] * W[q + 3] / (hx * hx) + W[p + 3] * D[q + 3] / (hy * hy);
            // gamma(tau) = gamma(-tau), gamma(0) = 0: each pair of lags once.
            if (p < 0 || (p == 0 && q <= 0)) continue;
            sum -= 2.0 * weight * psi.semivariogram(p * hx, q * hy);
        }
    return scale * sum;
}

std::unique_ptr<Flow> make_stream_flow(StreamFunction psi, Keyframed speed) {
    validate(psi);
    return std::make_unique<StreamFunctionFlow>(psi, std::move(speed));
}

}  // namespace impulse::sim
