// SPDX-License-Identifier: Apache-2.0
// Sparse-convolution solid noise (Lewis 1989 §4): the Poisson impulses of each cell, the
// batched evaluation over cells and the dense grid (docs/solid.md).

#include "synth/solid.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include "numeric/errors.h"
#include "numeric/rng.h"
#include "synth/detail/cells.h"
#include "synth/detail/solid_cells.h"
#include "synth/detail/solid_loops.h"

namespace impulse::synth {
namespace {

using detail::kSolidStream;
constexpr double kPi = std::numbers::pi;
constexpr size_t kChunkGroups = 8192;  // groups whose impulses are generated together
constexpr int kSplit = 2;              // group cells per impulse cell along each axis

/// The impulses of one cell: position in the cell in [0, 1)^D (cell units) and amplitude.
template <int D>
struct CellImpulses {
    std::array<std::vector<float>, D> u;
    std::vector<float> a;
};

/// Impulses of cell c under `rng` (seed, component): count from draw 0, impulse j from draw
/// j + 1 (x, y, z, amplitude) and, in 4-D, t from draw 2^31 + j + 1; the 4-D cell's t index
/// keys the stream (CounterRng::keyed).
template <int D>
void generate_cell(const numeric::CounterRng& base, const std::array<int64_t, D>& c, double m,
                   const detail::CellPeriod& period, std::array<std::vector<float>, D>& u,
                   std::vector<float>& a) {
    const numeric::CounterRng rng = D == 4 ? base.keyed(c[D - 1]) : base;
    const int n = detail::cell_count(rng, c[0], c[1], c[2], m, period);
    for (int j = 0; j < n; ++j) {
        float w[3], amplitude;
        detail::cell_impulse(rng, c[0], c[1], c[2], j, period, w, amplitude);
        for (int d = 0; d < 3; ++d) u[d].push_back(w[d]);
        a.push_back(amplitude);
        if constexpr (D == 4)
            u[3].push_back(static_cast<float>(rng.uniforms(c[0], c[1], c[2], 0x80000000u + uint32_t(j + 1))[0]));
    }
}

/// The impulses of every cell a chunk of groups needs, generated once (L89 §4.1's cache).
template <int D>
struct CellTable {
    using Cell = std::array<int64_t, D>;
    std::vector<Cell> cells;      // sorted, unique
    std::vector<size_t> offset;   // impulses of cells[i]: [offset[i], offset[i + 1])
    std::array<std::vector<float>, D> u;
    std::vector<float> a;

    CellTable(const numeric::CounterRng& rng, double m, const detail::CellPeriod& period,
              const std::vector<Cell>& groups) {
        for (const Cell& g : groups)
            for (const Cell& c : detail::neighbours<D>(g)) cells.push_back(c);
        tbb::parallel_sort(cells.begin(), cells.end());
        cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
        std::vector<CellImpulses<D>> per(cells.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, cells.size(), 64), [&](const auto& r) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                generate_cell<D>(rng, cells[i], m, period, per[i].u, per[i].a);
        });
        offset.assign(1, 0);
        for (const auto& p : per) {
            for (int d = 0; d < D; ++d) u[d].insert(u[d].end(), p.u[d].begin(), p.u[d].end());
            a.insert(a.end(), p.a.begin(), p.a.end());
            offset.push_back(a.size());
        }
    }
    size_t find(const Cell& c) const {
        return size_t(std::lower_bound(cells.begin(), cells.end(), c) - cells.begin());
    }
};

/// The impulses that can reach the box [lo, lo + side]^D of cell g: g's 3^D neighbours in
/// lexicographic order, each cell's impulses in draw order (the canonical summation order of
/// every path), positions relative to g, those farther than one radius from the box dropped
/// (they add exactly zero to every point in it, so the box changes no value).
template <int D>
void gather(const CellTable<D>& table, const std::array<int64_t, D>& g,
            const std::array<float, D>& lo, float side, detail::Gathered<D>& out) {
    for (auto& v : out.v) v.clear();
    out.a.clear();
    const auto cells = detail::neighbours<D>(g);
    size_t i = 0;
    for (size_t n = 0; n < cells.size(); ++n) {
        const auto& c = cells[n];
        // Every neighbour is in the table, so the three along the last axis are consecutive
        // entries: one search per row.
        i = n % 3 == 0 ? table.find(c) : i + 1;
        for (size_t k = table.offset[i]; k < table.offset[i + 1]; ++k) {
            std::array<float, D> v;
            float dist2 = 0.0f;
            for (int d = 0; d < D; ++d) {
                v[d] = static_cast<float>(double(c[d] - g[d]) + double(table.u[d][k]));
                const float out_of = std::max({0.0f, lo[d] - v[d], v[d] - lo[d] - side});
                dist2 += out_of * out_of;
            }
            if (dist2 >= 1.001f) continue;  // conservative: a kept impulse may still add 0
            for (int d = 0; d < D; ++d) out.v[d].push_back(v[d]);
            out.a.push_back(table.a[k]);
        }
    }
}

double unit_ball_volume(int dims) { return dims == 3 ? 4.0 / 3.0 * kPi : 0.5 * kPi * kPi; }

double det3(const std::array<double, 9>& m) {
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
           m[2] * (m[3] * m[7] - m[4] * m[6]);
}

void validate(const SolidParams& p) {
    if (!(p.density > 0.0 && p.density <= 1000.0)) {
        std::ostringstream s;
        s << "density = " << p.density << ": expected impulses per kernel volume in (0, 1000]";
        throw ValueError(s.str());
    }
    for (double v : p.metric)
        if (!std::isfinite(v)) throw ValueError("metric: expected finite entries");
    const double det = det3(p.metric);
    double norm = 0.0;
    for (double v : p.metric) norm = std::max(norm, std::abs(v));
    if (!(std::abs(det) > 1e-9 * norm * norm * norm))
        throw ValueError("metric: singular (det = " + std::to_string(det) +
                         "); expected an invertible 3x3 matrix");
    const bool periodic = p.period_cells != detail::CellPeriod{0, 0, 0};
    for (const int64_t n : p.period_cells)
        if (n < 0 || n > (int64_t(1) << 40))
            throw ValueError("period_cells: expected cells per period in [0, 2^40] (0: not periodic)");
    if (periodic && p.metric != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1})
        throw ValueError("period_cells: a periodic noise takes the identity metric only");
}

}  // namespace

SolidNoise::SolidNoise(const SolidParams& params)
    : m_params((validate(params), params)), m_kernel(params.kernel, params.dims) {
    const double R = m_kernel.radius();
    for (int i = 0; i < 9; ++i) m_warp[i] = params.metric[i] / R;
}

SolidTheory SolidNoise::theory() const {
    SolidTheory t;
    // lambda in the warped space g lives in; f(x) = g(M x) has the same one-point statistics.
    t.lambda = m_params.density / m_kernel.support_volume();
    t.mean = t.lambda * 0.0 * m_kernel.integral();  // E[a] = 0 (Campbell: lambda E[a] int h)
    t.variance = t.lambda * t.amplitude_moment2 * m_kernel.integral_sq();
    return t;
}

double SolidNoise::power_spectrum(double kx, double ky, double kz) const {
    // g's spectrum at M^-T k, divided by |det M| (f(x) = g(M x)). M^-T k solves M^T w = k.
    const auto& m = m_params.metric;
    const double det = det3(m);
    // Cofactor matrix of M over det is M^-T.
    const double w0 = ((m[4] * m[8] - m[5] * m[7]) * kx - (m[3] * m[8] - m[5] * m[6]) * ky +
                       (m[3] * m[7] - m[4] * m[6]) * kz) / det;
    const double w1 = (-(m[1] * m[8] - m[2] * m[7]) * kx + (m[0] * m[8] - m[2] * m[6]) * ky -
                       (m[0] * m[7] - m[1] * m[6]) * kz) / det;
    const double w2 = ((m[1] * m[5] - m[2] * m[4]) * kx - (m[0] * m[5] - m[2] * m[3]) * ky +
                       (m[0] * m[4] - m[1] * m[3]) * kz) / det;
    const SolidTheory t = theory();
    return t.lambda * t.amplitude_moment2 * m_kernel.power_spectrum(w0, w1, w2) / std::abs(det);
}

double SolidNoise::radial_power_spectrum(double k) const {
    const auto& m = m_params.metric;
    const bool identity = m == std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1};
    if (identity) {
        const SolidTheory t = theory();
        return t.lambda * t.amplitude_moment2 * m_kernel.radial_power_spectrum(k);
    }
    const int n = 64;
    double sum = 0.0;
    for (int i = 0; i < 2 * n; ++i)
        for (int j = 0; j < n; ++j) {
            const double mu = -1.0 + (j + 0.5) * 2.0 / n, phi = kPi * (i + 0.5) / n;
            const double s = std::sqrt(1.0 - mu * mu);
            sum += power_spectrum(k * s * std::cos(phi), k * s * std::sin(phi), k * mu);
        }
    return sum / (2.0 * n * n);
}

double SolidNoise::batch_bytes(double n) {
    // Sort keys (cell + index), local coordinates, order and the values.
    return n * (40.0 + 16.0 + 4.0 + 4.0);
}

namespace {

/// Evaluates the groups of `b` for noise component `component` into out[index].
template <int D>
void run_batch(const SolidNoise& noise, const detail::CellBatch<D>& b, int split, int component,
               float* out) {
    const auto& p = noise.params();
    const numeric::CounterRng rng = numeric::CounterRng(p.seed, kSolidStream).keyed(component);
    const double m = p.density / unit_ball_volume(D);  // impulses per cell of side R
    const detail::LoopKernel lk = detail::loop_kernel(noise.kernel());
    // Group cells of side 1 / split: the impulses within one radius of a half cell are 2.5 times
    // fewer than those of a whole one (Steiner's formula: 8.2 against 20.6 R^3).
    auto impulse_cell = [split](const std::array<int64_t, D>& s) {
        std::array<int64_t, D> c;
        for (int d = 0; d < D; ++d) c[d] = s[d] >= 0 ? s[d] / split : -((-s[d] + split - 1) / split);
        return c;
    };
    for (size_t g0 = 0; g0 < b.cells.size(); g0 += kChunkGroups) {
        const size_t g1 = std::min(b.cells.size(), g0 + kChunkGroups);
        std::vector<std::array<int64_t, D>> cells;
        for (size_t g = g0; g < g1; ++g) cells.push_back(impulse_cell(b.cells[g]));
        cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
        const CellTable<D> table(rng, m, p.period_cells, cells);
        tbb::parallel_for(tbb::blocked_range<size_t>(g0, g1, 1), [&](const auto& r) {
            detail::Gathered<D> gathered;
            std::vector<float> acc;
            for (size_t g = r.begin(); g != r.end(); ++g) {
                const auto c = impulse_cell(b.cells[g]);
                std::array<float, D> lo;
                for (int d = 0; d < D; ++d) lo[d] = float(b.cells[g][d] - split * c[d]) / split;
                gather<D>(table, c, lo, 1.0f / split, gathered);
                const size_t s0 = b.start[g], n = b.start[g + 1] - s0;
                acc.assign(n, 0.0f);
                std::array<const float*, D> t;
                for (int d = 0; d < D; ++d) t[d] = b.local[d].data() + s0;
                detail::accumulate<D>(lk, gathered, t, n, acc.data());
                for (size_t s = 0; s < n; ++s) out[b.index[s0 + s]] = acc[s];
            }
        });
    }
}

}  // namespace

void SolidNoise::evaluate(const std::vector<SolidPoint>& points, std::vector<float>& values,
                          int component) const {
    if (component < 0 || component > 2)
        throw ValueError("component = " + std::to_string(component) + ": expected 0, 1 or 2");
    values.assign(points.size(), 0.0f);
    if (detail::evaluate_dense(*this, points, component, values.data())) return;
    const auto& w = m_warp;
    const double inv_r = 1.0 / m_kernel.radius();
    auto warp = [&](size_t i, double* o) {
        const SolidPoint& q = points[i];
        for (int r = 0; r < 3; ++r) o[r] = w[3 * r] * q.x + w[3 * r + 1] * q.y + w[3 * r + 2] * q.z;
    };
    // Half cells pay when they hold several points (the loop vectorises over a group's points);
    // for scattered points whole cells gather fewer times. The bits are the same either way.
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (size_t i = 0; i < points.size(); ++i) {
        double o[3];
        warp(i, o);
        for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], o[d]), hi[d] = std::max(hi[d], o[d]);
    }
    double cells = 1.0;
    for (int d = 0; d < 3; ++d) cells *= std::max(1.0, hi[d] - lo[d] + 1.0);
    const int split = double(points.size()) >= 64.0 * cells ? kSplit : 1;
    if (m_params.dims == 3) {
        run_batch<3>(*this, detail::group_by_cell<3>(points.size(), warp, split), split, component,
                     values.data());
    } else {
        auto warp4 = [&](size_t i, double* o) {
            warp(i, o);
            o[3] = points[i].t * inv_r;
        };
        run_batch<4>(*this, detail::group_by_cell<4>(points.size(), warp4, split), split, component,
                     values.data());
    }
}

float SolidNoise::evaluate(const SolidPoint& p, int component) const {
    std::vector<float> v;
    evaluate(std::vector<SolidPoint>{p}, v, component);
    return v[0];
}

std::vector<float> SolidNoise::grid(int width, int height, int depth, const SolidPoint& origin,
                                    double spacing, int component) const {
    if (width <= 0 || height <= 0 || depth <= 0)
        throw ValueError("grid size " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                         std::to_string(depth) + ": expected positive sizes");
    const size_t plane = size_t(width) * height;
    std::vector<float> out(plane * depth);
    if (component < 0 || component > 2)
        throw ValueError("component = " + std::to_string(component) + ": expected 0, 1 or 2");
    if (detail::grid_by_bricks(*this, {width, height, depth}, origin, spacing, component, out.data()))
        return out;
    // Otherwise slabs of planes through the batch path: bounded memory, the same bits as points.
    const int slab = std::max(1, static_cast<int>(std::min<size_t>(depth, (size_t(1) << 22) / plane)));
    std::vector<SolidPoint> pts;
    std::vector<float> vals;
    for (int k0 = 0; k0 < depth; k0 += slab) {
        const int k1 = std::min(depth, k0 + slab);
        pts.resize(plane * (k1 - k0));
        tbb::parallel_for(tbb::blocked_range<int>(k0, k1), [&](const auto& r) {
            for (int k = r.begin(); k != r.end(); ++k)
                for (int j = 0; j < height; ++j)
                    for (int i = 0; i < width; ++i)
                        pts[size_t(k - k0) * plane + size_t(j) * width + i] = {
                            origin.x + i * spacing, origin.y + j * spacing, origin.z + k * spacing,
                            origin.t};
        });
        evaluate(pts, vals, component);
        std::copy(vals.begin(), vals.end(), out.begin() + ptrdiff_t(plane) * k0);
    }
    return out;
}

}  // namespace impulse::synth

namespace impulse::synth {
namespace {

constexpr size_t kSliceColumns = 256;  // columns whose impulses one task generates

/// The impulses of column (cx, cy) within one radius of the plane at (zc, tc) (cell units):
/// cells cz = floor(zc) - 1 .. floor(zc) + 1 (and ct alike) are the only ones that reach it.
template <int D>
void slice_column(const numeric::CounterRng& rng, double m, const detail::CellPeriod& period,
                  const std::array<int64_t, 2>& col, double zc, double tc, double R, SliceImpulses& out) {
    const int64_t z0 = int64_t(std::floor(zc)), t0 = int64_t(std::floor(tc));
    std::array<std::vector<float>, D> u;
    std::vector<float> a;
    for (int64_t cz = z0 - 1; cz <= z0 + 1; ++cz)
        for (int64_t ct = t0 - 1; ct <= (D == 4 ? t0 + 1 : t0 - 1); ++ct) {
            for (auto& v : u) v.clear();
            a.clear();
            std::array<int64_t, D> cell;
            cell[0] = col[0], cell[1] = col[1], cell[2] = cz;
            if constexpr (D == 4) cell[3] = ct;
            generate_cell<D>(rng, cell, m, period, u, a);
            for (size_t j = 0; j < a.size(); ++j) {
                const double dz = (double(cz) - zc) + double(u[2][j]);
                double d2 = dz * dz;
                if constexpr (D == 4) {
                    const double dt = (double(ct) - tc) + double(u[3][j]);
                    d2 += dt * dt;
                }
                if (!(d2 < 1.0)) continue;  // h(r) = 0 for r >= R: it adds nothing to the plane
                out.x.push_back((double(col[0]) + double(u[0][j])) * R);
                out.y.push_back((double(col[1]) + double(u[1][j])) * R);
                out.a.push_back(a[j]);
                out.d2.push_back(static_cast<float>(d2 * R * R));
            }
        }
}

}  // namespace

void SolidNoise::slice_impulses(const std::vector<std::array<int64_t, 2>>& columns, double z,
                                double t, SliceImpulses& out, int component) const {
    if (m_params.metric != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1})
        throw ValueError("slice_impulses: expected the identity metric");
    if (component < 0 || component > 2)
        throw ValueError("component = " + std::to_string(component) + ": expected 0, 1 or 2");
    const double R = m_kernel.radius(), zc = z / R, tc = t / R;
    if (!(std::abs(zc) < 1e15 && std::abs(tc) < 1e15))
        throw ValueError("slice_impulses: z or t beyond 1e15 cells");
    const numeric::CounterRng rng =
        numeric::CounterRng(m_params.seed, kSolidStream).keyed(component);
    const double m = m_params.density / unit_ball_volume(m_params.dims);
    // Chunks of columns in parallel, joined in column order: the same list for any thread count.
    std::vector<SliceImpulses> parts((columns.size() + kSliceColumns - 1) / kSliceColumns);
    tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
        const size_t end = std::min(columns.size(), (k + 1) * kSliceColumns);
        for (size_t c = k * kSliceColumns; c < end; ++c) {
            if (m_params.dims == 3) slice_column<3>(rng, m, m_params.period_cells, columns[c], zc, tc, R, parts[k]);
            else slice_column<4>(rng, m, m_params.period_cells, columns[c], zc, tc, R, parts[k]);
        }
    });
    out = SliceImpulses{};
    for (const SliceImpulses& p : parts) {
        out.x.insert(out.x.end(), p.x.begin(), p.x.end());
        out.y.insert(out.y.end(), p.y.begin(), p.y.end());
        out.a.insert(out.a.end(), p.a.begin(), p.a.end());
        out.d2.insert(out.d2.end(), p.d2.begin(), p.d2.end());
    }
}

}  // namespace impulse::synth
