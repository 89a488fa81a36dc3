// SPDX-License-Identifier: Apache-2.0
// Velocity fields: uniform wind, shear, vortices, sources/sinks, curl noise, sampled grids.
// Each returns divergence and vorticity analytically so the Jacobian (d ln J/dt = div v) and
// vorticity-driven spin (d theta/dt = w/2) are integrated along with the position.

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim/lattice.h"
#include "sim/layout.h"
#include "sim/rng.h"
#include "sim/sim.h"

namespace impulse::sim {
namespace {

constexpr double kPi = std::numbers::pi;

double max_corner_distance(const Box& r, double cx, double cy) {
    const double dx = std::max(std::abs(r.x0 - cx), std::abs(r.x1 - cx));
    const double dy = std::max(std::abs(r.y0 - cy), std::abs(r.y1 - cy));
    return std::hypot(dx, dy);
}

class UniformFlow final : public Flow {
public:
    UniformFlow(Keyframed vx, Keyframed vy) : m_vx(std::move(vx)), m_vy(std::move(vy)) {}
    void add(double t, size_t n, const double*, const double*, double* vx, double* vy, double*,
             double*) const override {
        const double ux = m_vx.value(t), uy = m_vy.value(t);
        for (size_t i = 0; i < n; ++i) vx[i] += ux, vy[i] += uy;
    }
    double max_speed(const Box&) const override { return std::hypot(m_vx.max_abs(), m_vy.max_abs()); }
    std::array<double, 4> velocity_bounds(const Box&) const override {
        return {m_vx.min(), m_vx.max(), m_vy.min(), m_vy.max()};
    }

private:
    Keyframed m_vx, m_vy;
};

class ShearFlow final : public Flow {
public:
    ShearFlow(Keyframed rate, Keyframed cx, Keyframed cy, Keyframed angle)
        : m_rate(std::move(rate)), m_cx(std::move(cx)), m_cy(std::move(cy)),
          m_angle(std::move(angle)) {}
    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy, double*,
             double* curl) const override {
        const double k = m_rate.value(t), cx = m_cx.value(t), cy = m_cy.value(t);
        const double a = m_angle.value(t), dx = std::cos(a), dy = std::sin(a);
        for (size_t i = 0; i < n; ++i) {
            // s = (p - c) . n_perp with n_perp = (-dy, dx)
            const double s = -(x[i] - cx) * dy + (y[i] - cy) * dx;
            vx[i] += k * s * dx;
            vy[i] += k * s * dy;
            curl[i] -= k;
        }
    }
    double max_speed(const Box& r) const override {
        // |s| is at most the distance to the centre whatever the angle; the distance to the
        // farthest corner is convex in the centre, so its maximum over the centre's range is at
        // a corner of that range.
        double d = 0.0;
        for (double cx : {m_cx.min(), m_cx.max()})
            for (double cy : {m_cy.min(), m_cy.max()}) d = std::max(d, max_corner_distance(r, cx, cy));
        return m_rate.max_abs() * d;
    }

private:
    Keyframed m_rate, m_cx, m_cy, m_angle;
};

class VortexFlow final : public Flow {
public:
    VortexFlow(VortexModel model, Keyframed cx, Keyframed cy, Keyframed gamma, Keyframed core)
        : m_model(model), m_cx(std::move(cx)), m_cy(std::move(cy)), m_gamma(std::move(gamma)),
          m_core(std::move(core)) {}
    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy, double*,
             double* curl) const override {
        const double cx = m_cx.value(t), cy = m_cy.value(t), g = m_gamma.value(t);
        const double rc = m_core.value(t), rc2 = rc * rc;
        const double w0 = g / (kPi * rc2);  // vorticity at the centre
        for (size_t i = 0; i < n; ++i) {
            const double dx = x[i] - cx, dy = y[i] - cy;
            const double r2 = dx * dx + dy * dy;
            // v = (v_theta / r) (-dy, dx); f = v_theta / r
            double f, w;
            if (m_model == VortexModel::LambOseen) {
                const double e = std::exp(-r2 / rc2);
                // (1 - e) / r^2 -> 1 / rc^2 as r -> 0; expm1 keeps it accurate near the axis
                f = r2 > 1e-12 * rc2 ? g / (2.0 * kPi) * (-std::expm1(-r2 / rc2)) / r2
                                     : g / (2.0 * kPi * rc2);
                w = w0 * e;
            } else {
                f = r2 < rc2 ? g / (2.0 * kPi * rc2) : g / (2.0 * kPi * r2);
                w = r2 < rc2 ? w0 : 0.0;
            }
            vx[i] -= f * dy;
            vy[i] += f * dx;
            curl[i] += w;
        }
    }
    double max_speed(const Box&) const override {
        // Peak of v_theta: Lamb–Oseen 0.6382 G/(2 pi rc) at r = 1.1209 rc; Rankine G/(2 pi rc).
        const double peak = m_gamma.max_abs() / (2.0 * kPi * m_core.min());
        return m_model == VortexModel::LambOseen ? 0.6382 * peak : peak;
    }

private:
    VortexModel m_model;
    Keyframed m_cx, m_cy, m_gamma, m_core;
};

class SourceFlow final : public Flow {
public:
    SourceFlow(Keyframed cx, Keyframed cy, Keyframed rate, Keyframed radius)
        : m_cx(std::move(cx)), m_cy(std::move(cy)), m_rate(std::move(rate)), m_radius(radius) {}
    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double*) const override {
        const double cx = m_cx.value(t), cy = m_cy.value(t), k = m_rate.value(t);
        const double radius = m_radius.value(t);
        if (radius <= 0) {
            for (size_t i = 0; i < n; ++i) {
                vx[i] += k * (x[i] - cx);
                vy[i] += k * (y[i] - cy);
                div[i] += 2.0 * k;
            }
            return;
        }
        const double inv_r2 = 1.0 / (radius * radius);
        for (size_t i = 0; i < n; ++i) {
            const double dx = x[i] - cx, dy = y[i] - cy;
            const double q = (dx * dx + dy * dy) * inv_r2;
            const double g = std::exp(-q);
            vx[i] += k * g * dx;
            vy[i] += k * g * dy;
            div[i] += k * g * (2.0 - 2.0 * q);  // div(k g(r) (x - c)) = k (2 g + r g')
        }
    }
    double max_speed(const Box& r) const override {
        const double k = m_rate.max_abs();
        // |v| = rate r exp(-r^2 / radius^2) peaks at r = radius / sqrt(2), growing with radius.
        if (m_radius.max() > 0) return k * m_radius.max() * std::sqrt(0.5) * std::exp(-0.5);
        double d = 0.0;
        for (const auto& kx : m_cx.keys)
            for (const auto& ky : m_cy.keys) d = std::max(d, max_corner_distance(r, kx.second, ky.second));
        return k * d;
    }

private:
    Keyframed m_cx, m_cy, m_rate, m_radius;
};

/// Adds a cell's terms a_i phi(|X - x_i|^2 / s^2) at node (X, Y).
struct CurlContribution {
    double inv_s2 = 1.0;
    void operator()(double X, double Y, const CellImpulses& c, double& psi) const {
        for (size_t k = 0; k < c.x.size(); ++k) {
            const double ddx = X - c.x[k], ddy = Y - c.y[k];
            const double q = (ddx * ddx + ddy * ddy) * inv_s2;
            if (q < 1.0) {
                const double u = 1.0 - q;
                psi += c.amplitude[k] * u * u * u;
            }
        }
    }
};

/// Curl of a sparse-convolution potential psi = sum a_i phi(|x - x_i|^2 / s^2),
/// phi(q) = (1 - q)^3: v = (d psi/dy, -d psi/dx), curl v = -lap psi.
///
/// psi is evaluated exactly at the nodes of a fixed lattice (spacing s/8, sim/lattice.h) and
/// interpolated with Catmull-Rom bicubics; the velocity is the curl of that interpolant, so it
/// stays exactly divergence-free (div curl = 0) while an evaluation costs 16 node reads instead
/// of a sum over ~36 impulses. Node values are cached for the region the simulator prepares;
/// outside it they are computed on the fly (the same numbers).
class CurlNoiseFlow final : public detail::LatticeStreamFlow<CurlContribution> {
public:
    static constexpr double kPerCell = 4.0;  // impulses per s x s cell: 4 pi per kernel area
    static constexpr int kNodesPerCell = 8;
    CurlNoiseFlow(uint64_t seed, double scale, Keyframed speed,
                  std::optional<std::array<double, 2>> period)
        : LatticeStreamFlow(potential_process(seed, scale, period), kNodesPerCell, std::move(speed)) {
        // E|grad psi|^2 = lambda E[a^2] int |grad phi|^2 = lambda * 1.2 pi (independent of s),
        // so unit RMS speed needs amplitudes scaled by 1/sqrt(1.2 pi lambda).
        m_norm = 1.0 / std::sqrt(1.2 * kPi * m_lattice.config().intensity);
        const detail::Layout& L = m_lattice.layout();
        m_contribution.inv_s2 = 1.0 / (L.cell_x * L.cell_y);
    }

private:
    static ProcessConfig potential_process(uint64_t seed, double scale,
                                           std::optional<std::array<double, 2>> period) {
        ProcessConfig c;
        c.seed = seed;
        c.layer = 0x40000000u;  // a stream of its own, apart from every layer's births
        c.cell_size = scale;
        c.period = period;
        c.intensity = kPerCell / (scale * scale);
        c.amplitude = Amplitude::Normal;
        return c;
    }
};

class GridFlow final : public Flow {
public:
    GridFlow(VectorGrid g, Keyframed gain) : m_g(std::move(g)), m_gain(std::move(gain)) {
        const int w = m_g.width, h = m_g.height;
        m_div.assign(m_g.vx.size(), 0.0f);
        m_curl.assign(m_g.vx.size(), 0.0f);
        auto at = [&](const std::vector<float>& v, int i, int j) {
            i = std::clamp(i, 0, w - 1), j = std::clamp(j, 0, h - 1);
            return static_cast<double>(v[static_cast<size_t>(j) * w + i]);
        };
        const double inv = 1.0 / m_g.spacing;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i) {
                // central differences (one-sided at the edges through the clamp, halved span)
                const double sx = (i == 0 || i == w - 1) ? 1.0 : 0.5;
                const double sy = (j == 0 || j == h - 1) ? 1.0 : 0.5;
                const double dvx_dx = sx * inv * (at(m_g.vx, i + 1, j) - at(m_g.vx, i - 1, j));
                const double dvy_dy = sy * inv * (at(m_g.vy, i, j + 1) - at(m_g.vy, i, j - 1));
                const double dvy_dx = sx * inv * (at(m_g.vy, i + 1, j) - at(m_g.vy, i - 1, j));
                const double dvx_dy = sy * inv * (at(m_g.vx, i, j + 1) - at(m_g.vx, i, j - 1));
                m_div[static_cast<size_t>(j) * w + i] = static_cast<float>(dvx_dx + dvy_dy);
                m_curl[static_cast<size_t>(j) * w + i] = static_cast<float>(dvy_dx - dvx_dy);
            }
        for (size_t k = 0; k < m_g.vx.size(); ++k)
            m_max = std::max(m_max, std::hypot(double(m_g.vx[k]), double(m_g.vy[k])));
    }
    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double* curl) const override {
        const double gain = m_gain.value(t);
        const int w = m_g.width, h = m_g.height;
        for (size_t i = 0; i < n; ++i) {
            const double fx = std::clamp((x[i] - m_g.origin_x) / m_g.spacing - 0.5, 0.0, w - 1.0);
            const double fy = std::clamp((y[i] - m_g.origin_y) / m_g.spacing - 0.5, 0.0, h - 1.0);
            const int i0 = std::min(static_cast<int>(fx), w - 1), j0 = std::min(static_cast<int>(fy), h - 1);
            const int i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
            const double ax = fx - i0, ay = fy - j0;
            auto lerp = [&](const std::vector<float>& v) {
                const double a = v[size_t(j0) * w + i0], b = v[size_t(j0) * w + i1];
                const double c = v[size_t(j1) * w + i0], d = v[size_t(j1) * w + i1];
                return (a + ax * (b - a)) + ay * ((c + ax * (d - c)) - (a + ax * (b - a)));
            };
            vx[i] += gain * lerp(m_g.vx);
            vy[i] += gain * lerp(m_g.vy);
            div[i] += gain * lerp(m_div);
            curl[i] += gain * lerp(m_curl);
        }
    }
    double max_speed(const Box&) const override { return m_gain.max_abs() * m_max; }

private:
    VectorGrid m_g;
    Keyframed m_gain;
    std::vector<float> m_div, m_curl;
    double m_max = 0.0;
};

}  // namespace

void FlowSum::add(double t, size_t n, const double* x, const double* y, double* vx, double* vy,
                  double* div, double* curl) const {
    for (const auto& f : m_terms) f->add(t, n, x, y, vx, vy, div, curl);
}
double FlowSum::max_speed(const Box& region) const {
    double s = 0.0;
    for (const auto& f : m_terms) s += f->max_speed(region);
    return s;
}
std::array<double, 4> FlowSum::velocity_bounds(const Box& region) const {
    std::array<double, 4> b{0, 0, 0, 0};
    for (const auto& f : m_terms) {
        const auto t = f->velocity_bounds(region);
        for (int i = 0; i < 4; ++i) b[i] += t[i];
    }
    return b;
}

void FlowSum::prepare(const Box& region) {
    for (auto& f : m_terms) f->prepare(region);
}

std::unique_ptr<Flow> make_uniform_flow(Keyframed vx, Keyframed vy) {
    return std::make_unique<UniformFlow>(std::move(vx), std::move(vy));
}
std::unique_ptr<Flow> make_shear_flow(Keyframed rate, Keyframed cx, Keyframed cy,
                                      Keyframed angle) {
    return std::make_unique<ShearFlow>(std::move(rate), std::move(cx), std::move(cy),
                                       std::move(angle));
}
std::unique_ptr<Flow> make_vortex_flow(VortexModel model, Keyframed cx, Keyframed cy,
                                       Keyframed circulation, Keyframed core_radius) {
    return std::make_unique<VortexFlow>(model, std::move(cx), std::move(cy),
                                        std::move(circulation), std::move(core_radius));
}
std::unique_ptr<Flow> make_source_flow(Keyframed cx, Keyframed cy, Keyframed rate,
                                       Keyframed radius) {
    return std::make_unique<SourceFlow>(std::move(cx), std::move(cy), std::move(rate),
                                        std::move(radius));
}
std::unique_ptr<Flow> make_curl_noise_flow(uint64_t seed, double scale, Keyframed speed,
                                           std::optional<std::array<double, 2>> period) {
    return std::make_unique<CurlNoiseFlow>(seed, scale, std::move(speed), period);
}
std::unique_ptr<Flow> make_grid_flow(VectorGrid grid, Keyframed gain) {
    return std::make_unique<GridFlow>(std::move(grid), std::move(gain));
}

}  // namespace impulse::sim
