// SPDX-License-Identifier: Apache-2.0
// Velocity fields: uniform wind, shear, vortices, sources/sinks, curl noise, sampled grids.
// Each returns divergence and vorticity analytically so the Jacobian (d ln J/dt = div v) and
// vorticity-driven spin (d theta/dt = w/2) are integrated along with the position.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "sim/detail/curl.h"
#include "sim/detail/lattice.h"
#include "sim/layout.h"
#include "numeric/rng.h"
#include "sim/sim.h"
#include "numeric/errors.h"

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
    bool divergence_free() const override { return true; }
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
        }
        if (curl)
            for (size_t i = 0; i < n; ++i) curl[i] -= k;
    }
    bool divergence_free() const override { return true; }
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
            if (curl) curl[i] += w;
        }
    }
    bool divergence_free() const override { return true; }
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
                if (div) div[i] += 2.0 * k;
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
            if (div) div[i] += k * g * (2.0 - 2.0 * q);  // div(k g(r) (x - c)) = k (2 g + r g')
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
    /// Without a radius the field is linear, v = rate (x - c): each component is a product of
    /// two intervals (the rate's keys and the offset from the centre's keys over the region),
    /// bounded by its corners. A source pushes outward, so the birth region reaches upstream
    /// only where a wind beside it blows toward the view (docs/design.md §3).
    std::array<double, 4> velocity_bounds(const Box& r) const override {
        if (m_radius.max() > 0) return Flow::velocity_bounds(r);
        const auto span = [&](double lo, double hi, const Keyframed& c) {
            const double d0 = lo - c.max(), d1 = hi - c.min();
            const double p[4] = {m_rate.min() * d0, m_rate.min() * d1, m_rate.max() * d0,
                                 m_rate.max() * d1};
            return std::pair{*std::min_element(p, p + 4), *std::max_element(p, p + 4)};
        };
        const auto [x0, x1] = span(r.x0, r.x1, m_cx);
        const auto [y0, y1] = span(r.y0, r.y1, m_cy);
        return {x0, x1, y0, y1};
    }

private:
    Keyframed m_cx, m_cy, m_rate, m_radius;
};

/// Curl of a sparse-convolution potential psi = sum a_i phi(|x - x_i|^2 / s^2),
/// phi(q) = (1 - q)^3: v = (d psi/dy, -d psi/dx), curl v = -lap psi (Bridson et al. 2007,
/// "Curl-noise for procedural fluid flow", in 2-D).
///
/// psi is evaluated exactly at the nodes of a fixed lattice (spacing s/8, nodes at whole
/// multiples of the spacing, so any region and any periodic copy sees the same node values) and
/// interpolated with Catmull-Rom bicubics; the velocity is the curl of that interpolant, so it
/// stays exactly divergence-free (div curl = 0) while an evaluation costs 16 node reads instead
/// of a sum over ~36 impulses. Node values are cached for the region the simulator prepares;
/// outside it they are computed on the fly (the same numbers). The interpolation itself is
/// sim/curl_loops.inc (baseline and AVX2 builds, identical bits).
class CurlNoiseFlow final : public Flow {
public:
    static constexpr double kPerCell = 4.0;  // impulses per s x s cell: 4 pi per kernel area
    static constexpr int kNodesPerCell = 8;
    /// Potential lattices larger than this are refused (8 bytes a node: 800 MB).
    static constexpr double kMaxNodes = 1e8;
    CurlNoiseFlow(uint64_t seed, double scale, Keyframed speed,
                  std::optional<std::array<double, 2>> period)
        : m_speed(std::move(speed)) {
        if (!(scale >= kMinCurlScale && scale <= kMaxCurlScale)) {
            std::ostringstream s;
            s << "curl flow: scale = " << scale << ": expected a length in [" << kMinCurlScale
              << ", " << kMaxCurlScale << "] texture units";
            throw ValueError(s.str());
        }
        m_config.seed = seed;
        m_config.layer = 0x40000000u;  // a stream of its own, apart from every layer's births
        m_config.cell_size = scale;
        m_config.period = period;
        m_config.intensity = kPerCell / (scale * scale);
        m_config.amplitude = Amplitude::Normal;
        m_layout = std::make_unique<detail::Layout>(m_config);
        // E|grad psi|^2 = lambda E[a^2] int |grad phi|^2 = lambda * 1.2 pi (independent of s),
        // so unit RMS speed needs amplitudes scaled by 1/sqrt(1.2 pi lambda).
        m_norm = 1.0 / std::sqrt(1.2 * kPi * m_config.intensity);
        m_hx = m_layout->cell_x / kNodesPerCell;
        m_hy = m_layout->cell_y / kNodesPerCell;
    }

    /// Nodes of the lattice that covers `region` (scale / 8 apart, the stencil's border).
    double lattice_nodes(const Box& region) const { return detail::lattice_nodes(region, m_hx, m_hy); }

    double cache_bytes(const Box& region) const override {
        // 8 bytes a node and ~4 for the cells' impulses generated to fill it; a rebuild for a
        // view that moved grows the lattice by a quarter on every side (prepare): 1.5^2.
        return 2.25 * 12.0 * lattice_nodes(region);
    }

    void prepare(const Box& region) override {
        // The lattice covers the region with nodes scale / 8 apart: refuse one too large for
        // memory (a small scale over a perspective view's region) before allocating it.
        const double nodes = lattice_nodes(region);
        if (!(nodes <= kMaxNodes)) {
            std::ostringstream s;
            s << "curl flow: scale = " << m_config.cell_size << " over a region of "
              << region.x1 - region.x0 << " x " << region.y1 - region.y0
              << " texture units needs a potential lattice of " << nodes
              << " nodes, over the limit of " << kMaxNodes << " (raise the scale)";
            throw ValueError(s.str());
        }
        const int64_t i0 = static_cast<int64_t>(std::floor(region.x0 / m_hx)) - 2;
        const int64_t j0 = static_cast<int64_t>(std::floor(region.y0 / m_hy)) - 2;
        const int64_t i1 = static_cast<int64_t>(std::floor(region.x1 / m_hx)) + 3;
        const int64_t j1 = static_cast<int64_t>(std::floor(region.y1 / m_hy)) + 3;
        if (i0 >= m_nx0 && j0 >= m_ny0 && i1 < m_nx0 + m_nw && j1 < m_ny0 + m_nh) return;  // cached
        // A rebuild grows the region by a quarter on every side so a moving view rarely
        // rebuilds again; the first build is exact, as a still view (or a frame rendered alone)
        // never asks for more.
        const bool first = m_nodes.empty();
        const int64_t mx = first ? 0 : (i1 - i0) / 4 + 1, my = first ? 0 : (j1 - j0) / 4 + 1;
        m_nx0 = i0 - mx, m_ny0 = j0 - my;
        m_nw = i1 - i0 + 1 + 2 * mx, m_nh = j1 - j0 + 1 + 2 * my;
        m_nodes.assign(static_cast<size_t>(m_nw * m_nh), 0.0);
        // Splat each cell's impulses into the nodes whose 3 x 3 cell neighbourhood holds it.
        // Every node sums the same terms in the same order as psi_node (cells row by row,
        // impulses in order), so the bits are the same whether cached or not. The cells are
        // generated in parallel, then node rows are filled in parallel, each row visiting the
        // cells in that order.
        const int64_t c0x = detail::floor_div(m_nx0, kNodesPerCell) - 1;
        const int64_t c1x = detail::floor_div(m_nx0 + m_nw - 1, kNodesPerCell) + 1;
        const int64_t c0y = detail::floor_div(m_ny0, kNodesPerCell) - 1;
        const int64_t c1y = detail::floor_div(m_ny0 + m_nh - 1, kNodesPerCell) + 1;
        const int64_t ncx = c1x - c0x + 1, ncy = c1y - c0y + 1;
        std::vector<CellImpulses> cells(static_cast<size_t>(ncx * ncy));
        tbb::parallel_for(int64_t(0), ncx * ncy, [&](int64_t i) {
            detail::generate_cell(m_config, *m_layout, c0x + i % ncx, c0y + i / ncx, 0,
                                  cells[static_cast<size_t>(i)], nullptr);
        });
        const double s2 = m_layout->cell_x * m_layout->cell_y, inv_s2 = 1.0 / s2;
        const double s = std::sqrt(s2);
        tbb::parallel_for(m_ny0, m_ny0 + m_nh, [&](int64_t nj) {
            const double Y = static_cast<double>(nj) * m_hy;
            double* row = m_nodes.data() + (nj - m_ny0) * m_nw;
            const int64_t cj = detail::floor_div(nj, kNodesPerCell);
            for (int64_t cy = std::max(c0y, cj - 1); cy <= std::min(c1y, cj + 1); ++cy)
                for (int64_t cx = c0x; cx <= c1x; ++cx) {
                    const CellImpulses& c = cells[static_cast<size_t>((cy - c0y) * ncx + cx - c0x)];
                    const int64_t ni0 = std::max(m_nx0, (cx - 1) * kNodesPerCell);
                    const int64_t ni1 = std::min(m_nx0 + m_nw - 1, (cx + 2) * kNodesPerCell - 1);
                    for (size_t k = 0; k < c.x.size(); ++k) {
                        // Only the nodes of the impulse's disk q < 1: its chord on this row
                        // widened by a node spacing. A node left out has q >= 1 + 1/64 (the
                        // spacing is s/8), far beyond rounding, so each node still sums
                        // exactly the terms psi_node sums.
                        const double ddy = Y - c.y[k];
                        if (std::abs(ddy) >= s + m_hy) continue;
                        const double chord = std::sqrt(std::max(0.0, s2 - ddy * ddy)) + m_hx;
                        const int64_t q0 = std::max(ni0, static_cast<int64_t>(std::floor((c.x[k] - chord) / m_hx)));
                        const int64_t q1 = std::min(ni1, static_cast<int64_t>(std::ceil((c.x[k] + chord) / m_hx)));
                        for (int64_t ni = q0; ni <= q1; ++ni) {
                            const double X = static_cast<double>(ni) * m_hx;
                            const double ddx = X - c.x[k];
                            const double q = (ddx * ddx + ddy * ddy) * inv_s2;
                            if (q < 1.0) {
                                const double u = 1.0 - q;
                                row[ni - m_nx0] += c.amplitude[k] * u * u * u;
                            }
                        }
                    }
                }
        });
    }

    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy, double*,
             double* curl) const override {
        detail::CurlLattice lattice;
        lattice.nodes = m_nodes.data();
        lattice.i0 = m_nx0, lattice.j0 = m_ny0, lattice.width = m_nw, lattice.height = m_nh;
        lattice.inv_hx = 1.0 / m_hx, lattice.inv_hy = 1.0 / m_hy;
        lattice.fetch = &fetch_nodes;
        lattice.fetch_context = this;
        const double amp = m_speed.value(t) * m_norm;
        if (detail::cpu_has_avx2())
            detail::curl_add_avx2(lattice, amp, n, x, y, vx, vy, curl);
        else
            detail::curl_add_base(lattice, amp, n, x, y, vx, vy, curl);
    }
    bool divergence_free() const override { return true; }

    double max_speed(const Box&) const override {
        // A statistical bound: |v| exceeds 4x its RMS with probability about 3e-4 per point
        // for a Gaussian field; the sparse potential has slightly heavier tails.
        return 4.0 * m_speed.max_abs();
    }

private:
    /// detail::CurlNodeFetch for points whose stencil leaves the cache.
    static void fetch_nodes(const void* self, int64_t i0, int64_t j0, double out[16]) {
        thread_local CellImpulses scratch;
        const auto& flow = *static_cast<const CurlNoiseFlow*>(self);
        for (int b = 0; b < 4; ++b)
            for (int a = 0; a < 4; ++a) out[4 * b + a] = flow.psi_node(i0 + a, j0 + b, scratch);
    }

    /// psi (unscaled) at lattice node (i, j): the exact sum over the 3 x 3 cells around it.
    double psi_node(int64_t i, int64_t j, CellImpulses& c) const {
        const double X = static_cast<double>(i) * m_hx, Y = static_cast<double>(j) * m_hy;
        const int64_t ci = detail::floor_div(i, kNodesPerCell), cj = detail::floor_div(j, kNodesPerCell);
        const double inv_s2 = 1.0 / (m_layout->cell_x * m_layout->cell_y);
        double psi = 0.0;
        for (int64_t b = -1; b <= 1; ++b)
            for (int64_t a = -1; a <= 1; ++a) {
                detail::generate_cell(m_config, *m_layout, ci + a, cj + b, 0, c, nullptr);
                for (size_t k = 0; k < c.x.size(); ++k) {
                    const double ddx = X - c.x[k], ddy = Y - c.y[k];
                    const double q = (ddx * ddx + ddy * ddy) * inv_s2;
                    if (q < 1.0) {
                        const double u = 1.0 - q;
                        psi += c.amplitude[k] * u * u * u;
                    }
                }
            }
        return psi;
    }

    Keyframed m_speed;
    ProcessConfig m_config;
    std::unique_ptr<detail::Layout> m_layout;
    double m_norm = 1.0, m_hx = 1.0, m_hy = 1.0;
    int64_t m_nx0 = 0, m_ny0 = 0, m_nw = 0, m_nh = 0;
    std::vector<double> m_nodes;
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
            if (div) div[i] += gain * lerp(m_div);
            if (curl) curl[i] += gain * lerp(m_curl);
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
bool FlowSum::divergence_free() const {
    for (const auto& f : m_terms)
        if (!f->divergence_free()) return false;
    return true;
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

void FlowSum::prepare_span(double t0_s, double t1_s) {
    for (auto& f : m_terms) f->prepare_span(t0_s, t1_s);
}

double FlowSum::cache_bytes(const Box& region) const {
    double bytes = 0.0;
    for (const auto& f : m_terms) bytes += f->cache_bytes(region);
    return bytes;
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
    const size_t n = size_t(std::max(grid.width, 0)) * size_t(std::max(grid.height, 0));
    if (grid.width < 1 || grid.height < 1 || grid.vx.size() != n || grid.vy.size() != n ||
        !(grid.spacing > 0.0) || !std::isfinite(grid.spacing) || !std::isfinite(grid.origin_x) ||
        !std::isfinite(grid.origin_y))
        throw ValueError(
            "grid flow: expected width, height >= 1, width * height velocities and spacing > 0");
    for (size_t i = 0; i < n; ++i)
        if (!std::isfinite(grid.vx[i]) || !std::isfinite(grid.vy[i])) {
            std::ostringstream s;
            s << "grid flow: expected finite velocities, found (" << grid.vx[i] << ", "
              << grid.vy[i] << ") at pixel (" << i % grid.width << ", " << i / grid.width << ")";
            throw ValueError(s.str());
        }
    return std::make_unique<GridFlow>(std::move(grid), std::move(gain));
}

}  // namespace impulse::sim
