// SPDX-License-Identifier: Apache-2.0
// Generalized stochastic subdivision: the level-by-level construction (Lewis 1987 eq. 3, 9,
// 10) for extendable regions, periodic fields and the refinement of given data.
// docs/subdivision.md.

#include "synth/subdivision.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <tuple>

#include "sim/normal.h"
#include "numeric/rng.h"
#include "numeric/errors.h"

namespace impulse::synth {
namespace {

/// Stream of the displacement noise ("GSS"), xored with the level.
constexpr uint32_t kGssStream = 0x47535300u;

/// The nodes of one level: indices (i, j) in units of the level's spacing, i in [i0, i0 + w).
struct Grid {
    int64_t i0 = 0, j0 = 0;
    int w = 0, h = 0;
    std::vector<double> v;
    void resize(int64_t a, int64_t b, int ww, int hh) {
        i0 = a, j0 = b, w = ww, h = hh;
        v.assign(size_t(w) * h, 0.0);
    }
    double& at(int64_t i, int64_t j) { return v[size_t(j - j0) * w + size_t(i - i0)]; }
    double at(int64_t i, int64_t j) const { return v[size_t(j - j0) * w + size_t(i - i0)]; }
};

/// Class index of a new node from the parity of its indices: 1-D always 0 ("mid"); 2-D
/// (odd, odd) face 0, (odd, even) edge_x 1, (even, odd) edge_y 2.
int class_of(int dims, int64_t i, int64_t j) {
    if (dims == 1) return 0;
    const bool px = i & 1, py = j & 1;
    return px && py ? 0 : (px ? 1 : 2);
}

/// Where the observations of a new node come from: `interior` says whether the whole
/// neighbourhood exists, `fetch` reads a coarse node by its (possibly out-of-range) index.
struct Boundary {
    enum Kind { Extend, Periodic, Clip } kind = Extend;
    int64_t mx = 0, my = 0;  // coarse nodes per axis (Periodic: the period; Clip: the data)
};

bool is_pow2(int64_t v) { return v >= 1 && (v & (v - 1)) == 0; }

std::string sizes_message(int64_t w, int64_t h, int dims, bool periodic) {
    const std::string got =
        dims == 1 ? std::to_string(w) : std::to_string(w) + "x" + std::to_string(h);
    if (periodic)
        return "--size " + got +
               ": periodic output needs 2^k samples per axis (2, 4, 8, ..., "
               "1024, 4096)";
    return "--size " + got +
           ": subdivision needs 2^k + 1 samples per axis (3, 5, 9, ..., 513, "
           "1025, 4097), or 2^k with --periodic";
}

/// Synthesizes level `level` (1-based) of the plan from the coarse grid `g` into `f` (whose
/// range is set by the caller). Lewis 1987 eq. 3 (1-D), eq. 9, 10 (2-D):
/// x_new = mean + sum_k a_k (x_k - mean) + sqrt(variance) u, u ~ N(0, 1) keyed by the node.
class LevelStep {
public:
    LevelStep(const Acf* acf, const Plan& plan, int level, const GssOptions& o, Boundary b,
              double mean)
        : m_acf(acf),
          m_plan(plan),
          m_lv(plan.levels[level - 1]),
          m_level(level),
          m_o(o),
          m_b(b),
          m_mean(mean) {
        for (const auto& c : m_lv.classes) m_sigma.push_back(std::sqrt(c.variance));
    }

    void run(const Grid& g, Grid& f) {
        if (m_lv.filter.radius >= 0) keyed_normals(f);
        tbb::parallel_for(0, f.h, [&](int row) {
            const int64_t j = f.j0 + row;
            for (int64_t i = f.i0; i < f.i0 + f.w; ++i) {
                double& out = f.at(i, j);
                if (!(i & 1) && !(j & 1)) {
                    out = coarse(g, i >> 1, j >> 1);  // an old node keeps its value
                    continue;
                }
                out = estimate(g, i, j);
            }
        });
    }

private:
    double coarse(const Grid& g, int64_t i, int64_t j) const {
        if (m_b.kind == Boundary::Periodic) {
            i = ((i % m_b.mx) + m_b.mx) % m_b.mx;
            j = m_plan.dims == 1 ? 0 : ((j % m_b.my) + m_b.my) % m_b.my;
        }
        return g.at(i, j);
    }

    double displacement(int64_t i, int64_t j) const {
        const int k = class_of(m_plan.dims, i, j);
        if (m_lv.filter.radius >= 0) return correlated(k, i >> 1, j >> 1);
        const double s = m_sigma[size_t(k)];
        if (s == 0) return 0;
        const int64_t h = m_lv.spacing;
        return s * node_normal(m_o.seed, m_level, i * h, j * h);
    }

    /// The normal of every new node within the filter's reach of the fine range, per class and
    /// cell (the same keys as the independent displacements).
    void keyed_normals(const Grid& f) {
        const int J = m_lv.filter.radius, d1 = m_plan.dims == 1;
        m_cells.resize((f.i0 >> 1) - J, d1 ? 0 : (f.j0 >> 1) - J,
                       int(((f.i0 + f.w - 1) >> 1) - (f.i0 >> 1)) + 1 + 2 * J,
                       d1 ? 1 : int(((f.j0 + f.h - 1) >> 1) - (f.j0 >> 1)) + 1 + 2 * J);
        const size_t K = m_lv.classes.size();
        m_normals.assign(K, std::vector<double>(m_cells.v.size()));
        const int64_t h = m_lv.spacing;
        tbb::parallel_for(0, m_cells.h, [&](int row) {
            for (int col = 0; col < m_cells.w; ++col) {
                int64_t cx = m_cells.i0 + col, cy = m_cells.j0 + row;
                if (m_b.kind == Boundary::Periodic) {
                    cx = ((cx % m_b.mx) + m_b.mx) % m_b.mx;
                    cy = d1 ? 0 : ((cy % m_b.my) + m_b.my) % m_b.my;
                }
                for (size_t k = 0; k < K; ++k) {
                    const auto& c = m_lv.classes[k];
                    m_normals[k][size_t(row) * m_cells.w + size_t(col)] =
                        node_normal(m_o.seed, m_level, (2 * cx + c.tx2) * h, (2 * cy + c.ty2) * h);
                }
            }
        });
    }

    /// u_k(p) = sum_k' sum_j beta_kk'(j) w_k'(p + j) (subdivision_displace.cpp).
    double correlated(int k, int64_t tx, int64_t ty) const {
        const int J = m_lv.filter.radius, side = 2 * J + 1, d1 = m_plan.dims == 1;
        const size_t K = m_lv.classes.size(), box = d1 ? size_t(side) : size_t(side) * side;
        double u = 0;
        for (size_t k2 = 0; k2 < K; ++k2) {
            const double* beta = m_lv.filter.beta.data() + (size_t(k) * K + k2) * box;
            const std::vector<double>& w = m_normals[k2];
            for (int jy = d1 ? 0 : -J; jy <= (d1 ? 0 : J); ++jy) {
                const size_t row = size_t(ty + jy - m_cells.j0) * m_cells.w;
                const double* b = beta + size_t(jy + (d1 ? 0 : J)) * side;
                for (int jx = -J; jx <= J; ++jx)
                    u += b[jx + J] * w[row + size_t(tx + jx - m_cells.i0)];
            }
        }
        return u;
    }

    double estimate(const Grid& g, int64_t i, int64_t j) {
        const int k = class_of(m_plan.dims, i, j);
        const int64_t tx = i >> 1, ty = j >> 1;  // floor: the coarse node before the target
        const ClassCoefficients* c = &m_lv.classes[size_t(k)];
        if (m_b.kind == Boundary::Clip) c = &clipped(k, tx, ty);
        double sum = m_mean;
        for (size_t q = 0; q < c->a.size(); ++q)
            sum +=
                c->a[q] * (coarse(g, tx + c->offsets[q].first, ty + c->offsets[q].second) - m_mean);
        if (c == &m_lv.classes[size_t(k)]) return sum + displacement(i, j);
        // A clipped neighbourhood estimates worse: its own eq. 7 variance, independently (the
        // displacement filter is the interior's).
        const int64_t h = m_lv.spacing;
        return sum + std::sqrt(c->variance) * node_normal(m_o.seed, m_level, i * h, j * h);
    }

    /// Refinement: the coefficients for the part of the neighbourhood inside the data (solved
    /// once per clipping and cached; the interior uses the plan's).
    const ClassCoefficients& clipped(int k, int64_t tx, int64_t ty) {
        const ClassCoefficients& full = m_lv.classes[size_t(k)];
        std::vector<std::pair<int, int>> kept;
        for (const auto& [cx, ry] : full.offsets)
            if (tx + cx >= 0 && tx + cx < m_b.mx && ty + ry >= 0 && ty + ry < m_b.my)
                kept.push_back({cx, ry});
        if (kept.size() == full.offsets.size()) return full;
        const std::lock_guard<std::mutex> lock(m_mutex);
        auto [it, fresh] = m_clipped.try_emplace(std::make_pair(k, kept));
        if (fresh)
            it->second =
                solve_class(*m_acf, 2.0 * m_lv.spacing, full.tx2, full.ty2, kept, m_o.singular);
        return it->second;
    }

    const Acf* m_acf;  // for the clipped solves of a refinement; null otherwise
    const Plan& m_plan;
    const LevelPlan& m_lv;
    int m_level;
    const GssOptions& m_o;
    Boundary m_b;
    double m_mean;
    std::vector<double> m_sigma;
    Grid m_cells;                                // the cell range of m_normals
    std::vector<std::vector<double>> m_normals;  // per class, per cell
    std::mutex m_mutex;
    std::map<std::pair<int, std::vector<std::pair<int, int>>>, ClassCoefficients> m_clipped;
};

Field to_field(Grid&& g, Plan&& plan) {
    Field f;
    f.x0 = g.i0, f.y0 = g.j0, f.width = g.w, f.height = g.h;
    f.values = std::move(g.v);
    f.plan = std::move(plan);
    return f;
}

/// Refuses sizes subdivision cannot make (and an origin for a periodic field).
void check_size(const GssOptions& o, int64_t x0, int64_t y0, int width, int height, bool periodic) {
    validate(o);
    const bool ok = o.dims == 1 ? height == 1 : true;
    if (periodic) {
        if (!ok || !is_pow2(width) || width < 2 ||
            (o.dims == 2 && (!is_pow2(height) || height < 2)))
            throw ValueError(sizes_message(width, height, o.dims, true));
        if (x0 != 0 || y0 != 0)
            throw ValueError("--origin: a periodic field has no origin (it repeats every period)");
    } else if (!ok || !is_pow2(width - 1) || width < 3 ||
               (o.dims == 2 && (!is_pow2(height - 1) || height < 3))) {
        throw ValueError(sizes_message(width, height, o.dims, false));
    }
}

}  // namespace

double node_normal(uint64_t seed, int level, int64_t x, int64_t y) {
    const numeric::CounterRng rng(seed, kGssStream ^ uint32_t(level));
    const auto u = rng.uniforms(x, y, 0, 0);
    return sim::detail::normal_from_uniforms(u[0], u[1]);
}

Field synthesize(const Acf& acf, const GssOptions& o, int64_t x0, int64_t y0, int width, int height,
                 bool periodic) {
    check_size(o, x0, y0, width, height, periodic);
    int top = 0;
    if (periodic) {  // the coarsest spacing must divide the period
        const int period = std::min(width, o.dims == 2 ? height : width);
        top = std::min(auto_top_spacing(acf, o, period), o.top_spacing ? o.top_spacing : 1 << 30);
        top = std::min({top, width, o.dims == 2 ? height : width});
    }
    return synthesize(plan_subdivision(acf, o, top), o, x0, y0, width, height, periodic);
}

Field synthesize(Plan plan, const GssOptions& o, int64_t x0, int64_t y0, int width, int height,
                 bool periodic) {
    check_size(o, x0, y0, width, height, periodic);
    if (plan.dims != o.dims)
        throw ValueError("synthesize: the plan's dims differ from the options'");
    if (periodic && (width % plan.top_spacing || (o.dims == 2 && height % plan.top_spacing)))
        throw ValueError("synthesize: the period is not a multiple of the plan's top spacing");
    const int levels = static_cast<int>(plan.levels.size());
    const double r0 = plan.variance;
    Boundary b;
    // Index ranges per level (extendable: each coarse range covers the neighbourhoods of the
    // finer one's nodes, so the region needs nothing beyond itself, Lewis 1987 §4.2).
    std::vector<std::array<int64_t, 4>> range(size_t(levels) + 1);  // i_lo, i_hi, j_lo, j_hi
    range[size_t(levels)] = {x0, x0 + width - 1, y0, y0 + height - 1};
    for (int l = levels; l >= 1; --l) {
        const auto& r = range[size_t(l)];
        if (periodic) {
            range[size_t(l) - 1] = {0, (r[1] + 1) / 2 - 1, 0, o.dims == 1 ? 0 : (r[3] + 1) / 2 - 1};
            continue;
        }
        const int64_t m = plan.levels[size_t(l) - 1].max_n() - 1;
        const auto fl = [](int64_t v) { return v >> 1; };
        const auto ce = [](int64_t v) { return (v + 1) >> 1; };
        range[size_t(l) - 1] = {fl(r[0]) - m, ce(r[1]) + m, o.dims == 1 ? 0 : fl(r[2]) - m,
                                o.dims == 1 ? 0 : ce(r[3]) + m};
    }
    Grid g;
    const auto& r = range[0];
    g.resize(r[0], r[2], int(r[1] - r[0] + 1), int(r[3] - r[2] + 1));
    // The coarsest nodes: independent, R(top) being negligible (Lewis 1987 §4.2 "invented using
    // uncorrelated random numbers").
    const double sd = std::sqrt(r0);
    const int64_t top_h = plan.top_spacing;
    for (int64_t j = g.j0; j < g.j0 + g.h; ++j)
        for (int64_t i = g.i0; i < g.i0 + g.w; ++i)
            g.at(i, j) = sd * node_normal(o.seed, 0, i * top_h, j * top_h);
    for (int l = 1; l <= levels; ++l) {
        const auto& q = range[size_t(l)];
        if (periodic) b = {Boundary::Periodic, g.w, g.h};
        Grid f;
        f.resize(q[0], q[2], int(q[1] - q[0] + 1), int(q[3] - q[2] + 1));
        LevelStep(nullptr, plan, l, o, b, 0.0).run(g, f);
        g = std::move(f);
    }
    return to_field(std::move(g), std::move(plan));
}

Field refine(const std::vector<double>& data, int w, int h, int factor, const Acf& acf,
             const GssOptions& o) {
    validate(o);
    if (factor < 2 || !is_pow2(factor))
        throw ValueError("--factor " + std::to_string(factor) +
                         ": expected a power of two >= 2 (2, 4, 8, ...)");
    if (w < 2 || (o.dims == 2 && h < 2) || (o.dims == 1 && h != 1))
        throw ValueError("refine: expected at least 2 samples per axis, found " +
                         std::to_string(w) + "x" + std::to_string(h));
    if (size_t(w) * h != data.size()) throw ValueError("refine: data size does not match w x h");
    double mean = 0;
    for (double v : data) mean += v;
    mean /= double(data.size());
    Plan plan = plan_subdivision(acf, o, factor);
    Grid g;
    g.resize(0, 0, w, h);
    g.v = data;
    for (int l = 1; l <= int(plan.levels.size()); ++l) {
        const Boundary b{Boundary::Clip, g.w, g.h};
        Grid f;
        f.resize(0, 0, 2 * (g.w - 1) + 1, o.dims == 1 ? 1 : 2 * (g.h - 1) + 1);
        LevelStep(&acf, plan, l, o, b, mean).run(g, f);
        g = std::move(f);
    }
    return to_field(std::move(g), std::move(plan));
}

}  // namespace impulse::synth
