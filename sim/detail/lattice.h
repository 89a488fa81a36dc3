// SPDX-License-Identifier: Apache-2.0
#pragma once
// A scalar potential psi of a still point process sampled on a fixed lattice and interpolated
// with Catmull-Rom bicubics: the machinery shared by the stream-function flows (curl noise, a
// layer's field as stream function). Internal to impulse::sim.
//
// Nodes sit at whole multiples (i hx, j hy) of the spacing, `nodes_per_cell` to a seeding cell,
// so any region and any periodic copy sees the same node values. A node sums the impulses of
// the 3 x 3 cells around its own (the potential's kernel must reach no further than one cell),
// cell by cell in row order and impulses in order, whether it is cached or computed on the fly:
// identical bits either way.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "numeric/spline.h"
#include "sim/layout.h"

namespace impulse::sim::detail {

/// Nodes of a lattice of spacing (hx, hy) covering `region` with a bicubic stencil's border
/// (the count the potential lattices allocate and the memory budget counts).
inline double lattice_nodes(const Box& region, double hx, double hy) {
    return ((region.x1 - region.x0) / hx + 6.0) * ((region.y1 - region.y0) / hy + 6.0);
}

using numeric::catmull_rom;

/// The gradient and Laplacian of the interpolated potential at a point.
struct PotentialSample {
    double px = 0, py = 0, lap = 0;  ///< d psi/dx, d psi/dy, lap psi
};

/// psi on the lattice of a still process. `Contribution` is called as
/// `f(X, Y, cell_impulses, psi)` and adds the cell's impulses' terms at node (X, Y) to psi.
class PotentialLattice {
public:
    PotentialLattice(const ProcessConfig& config, int nodes_per_cell)
        : m_config(config), m_layout(config), m_nodes_per_cell(nodes_per_cell) {
        m_hx = m_layout.cell_x / nodes_per_cell;
        m_hy = m_layout.cell_y / nodes_per_cell;
    }
    const ProcessConfig& config() const { return m_config; }
    const Layout& layout() const { return m_layout; }
    double hx() const { return m_hx; }
    double hy() const { return m_hy; }
    /// Bytes prepare(region) allocates: 8 a node over the region grown by a quarter on every
    /// side (1.5^2), with the stencil's border.
    double cache_bytes(const Box& region) const {
        return 2.25 * 8.0 * lattice_nodes(region, m_hx, m_hy);
    }

    /// Caches the nodes an evaluation anywhere in `region` reads (grown by a quarter on every
    /// side, so a slowly moving view rarely rebuilds). Single-threaded.
    template <class Contribution>
    void prepare(const Box& region, Contribution&& contribution) {
        const int64_t i0 = static_cast<int64_t>(std::floor(region.x0 / m_hx)) - 2;
        const int64_t j0 = static_cast<int64_t>(std::floor(region.y0 / m_hy)) - 2;
        const int64_t i1 = static_cast<int64_t>(std::floor(region.x1 / m_hx)) + 3;
        const int64_t j1 = static_cast<int64_t>(std::floor(region.y1 / m_hy)) + 3;
        if (i0 >= m_nx0 && j0 >= m_ny0 && i1 < m_nx0 + m_nw && j1 < m_ny0 + m_nh) return;  // cached
        const int64_t mx = (i1 - i0) / 4 + 1, my = (j1 - j0) / 4 + 1;
        m_nx0 = i0 - mx, m_ny0 = j0 - my;
        m_nw = i1 - i0 + 1 + 2 * mx, m_nh = j1 - j0 + 1 + 2 * my;
        m_nodes.assign(static_cast<size_t>(m_nw * m_nh), 0.0);
        // Splat each cell's impulses into the nodes whose 3 x 3 cell neighbourhood holds it.
        // Cells are visited row by row and impulses in order, so every node sums the same terms
        // in the same order as node() (identical bits whether cached or not).
        const int64_t n = m_nodes_per_cell;
        const int64_t c0x = floor_div(m_nx0, n) - 1, c1x = floor_div(m_nx0 + m_nw - 1, n) + 1;
        const int64_t c0y = floor_div(m_ny0, n) - 1, c1y = floor_div(m_ny0 + m_nh - 1, n) + 1;
        CellImpulses c;
        for (int64_t cy = c0y; cy <= c1y; ++cy)
            for (int64_t cx = c0x; cx <= c1x; ++cx) {
                generate_cell(m_config, m_layout, cx, cy, 0, c, nullptr);
                if (c.x.empty()) continue;
                const int64_t ni0 = std::max(m_nx0, (cx - 1) * n);
                const int64_t ni1 = std::min(m_nx0 + m_nw - 1, (cx + 2) * n - 1);
                const int64_t nj0 = std::max(m_ny0, (cy - 1) * n);
                const int64_t nj1 = std::min(m_ny0 + m_nh - 1, (cy + 2) * n - 1);
                for (int64_t nj = nj0; nj <= nj1; ++nj)
                    for (int64_t ni = ni0; ni <= ni1; ++ni) {
                        const double X = static_cast<double>(ni) * m_hx, Y = static_cast<double>(nj) * m_hy;
                        contribution(X, Y, c,
                                     m_nodes[static_cast<size_t>((nj - m_ny0) * m_nw + (ni - m_nx0))]);
                    }
            }
    }

    /// psi at node (i, j): the exact sum over the 3 x 3 cells around it (the cache's numbers).
    template <class Contribution>
    double node(int64_t i, int64_t j, Contribution&& contribution, CellImpulses& c) const {
        const double X = static_cast<double>(i) * m_hx, Y = static_cast<double>(j) * m_hy;
        const int64_t ci = floor_div(i, m_nodes_per_cell), cj = floor_div(j, m_nodes_per_cell);
        double psi = 0.0;
        for (int64_t b = -1; b <= 1; ++b)
            for (int64_t a = -1; a <= 1; ++a) {
                generate_cell(m_config, m_layout, ci + a, cj + b, 0, c, nullptr);
                contribution(X, Y, c, psi);
            }
        return psi;
    }

    /// Gradient and Laplacian of the Catmull-Rom interpolant of the nodes at (x, y): cached
    /// nodes where the cache holds the 4 x 4 stencil, computed ones elsewhere. Thread-safe.
    template <class Contribution>
    PotentialSample sample(double x, double y, Contribution&& contribution) const {
        thread_local CellImpulses scratch;
        const double fx = x / m_hx, fy = y / m_hy;
        const double flx = std::floor(fx), fly = std::floor(fy);
        const int64_t i = static_cast<int64_t>(flx), j = static_cast<int64_t>(fly);
        const double tx = fx - flx, ty = fy - fly;
        double wx[4], dx[4], ddx[4], wy[4], dy[4], ddy[4];
        catmull_rom(tx, wx, dx, ddx);
        catmull_rom(ty, wy, dy, ddy);
        double node_values[4][4];
        const int64_t gi = i - 1 - m_nx0, gj = j - 1 - m_ny0;
        if (gi >= 0 && gj >= 0 && gi + 3 < m_nw && gj + 3 < m_nh) {
            for (int b = 0; b < 4; ++b)
                for (int a = 0; a < 4; ++a)
                    node_values[b][a] = m_nodes[static_cast<size_t>((gj + b) * m_nw + gi + a)];
        } else {
            for (int b = 0; b < 4; ++b)
                for (int a = 0; a < 4; ++a)
                    node_values[b][a] = node(i - 1 + a, j - 1 + b, contribution, scratch);
        }
        PotentialSample s;
        for (int b = 0; b < 4; ++b) {
            double rx = 0, rdx = 0, rddx = 0;
            for (int a = 0; a < 4; ++a) {
                rx += wx[a] * node_values[b][a];
                rdx += dx[a] * node_values[b][a];
                rddx += ddx[a] * node_values[b][a];
            }
            s.px += wy[b] * rdx;
            s.py += dy[b] * rx;
            s.lap += wy[b] * rddx / (m_hx * m_hx) + ddy[b] * rx / (m_hy * m_hy);
        }
        s.px /= m_hx, s.py /= m_hy;
        return s;
    }

private:
    ProcessConfig m_config;
    Layout m_layout;
    int m_nodes_per_cell;
    double m_hx = 1.0, m_hy = 1.0;
    int64_t m_nx0 = 0, m_ny0 = 0, m_nw = 0, m_nh = 0;
    std::vector<double> m_nodes;
};

/// The flow v = speed(t) norm (d psi/dy, -d psi/dx), curl v = -speed norm lap psi, of the
/// lattice-interpolated potential of a still process: exactly divergence-free (div curl = 0).
/// Derived classes set the contribution and the normalisation in their constructors.
template <class Contribution>
class LatticeStreamFlow : public Flow {
public:
    void prepare(const Box& region) override { m_lattice.prepare(region, m_contribution); }
    double cache_bytes(const Box& region) const override { return m_lattice.cache_bytes(region); }

    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy, double*,
             double* curl) const override {
        const double amp = m_speed.value(t) * m_norm;
        for (size_t p = 0; p < n; ++p) {
            const PotentialSample s = m_lattice.sample(x[p], y[p], m_contribution);
            vx[p] += amp * s.py;
            vy[p] -= amp * s.px;
            if (curl) curl[p] -= amp * s.lap;
        }
    }
    bool divergence_free() const override { return true; }

    double max_speed(const Box&) const override {
        // A statistical bound: for a Gaussian field with an isotropic kernel |v|^2 / E|v|^2 is
        // exponential, so |v| exceeds 4x its RMS with probability exp(-16) ~ 1e-7 per point;
        // sparse potentials and anisotropic kernels of fixed orientation have heavier tails.
        return 4.0 * m_speed.max_abs();
    }

protected:
    LatticeStreamFlow(const ProcessConfig& config, int nodes_per_cell, Keyframed speed)
        : m_lattice(config, nodes_per_cell), m_speed(std::move(speed)) {}

    PotentialLattice m_lattice;
    Keyframed m_speed;
    Contribution m_contribution{};
    double m_norm = 1.0;  ///< per unit RMS speed
};

}  // namespace impulse::sim::detail
