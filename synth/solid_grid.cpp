// SPDX-License-Identifier: Apache-2.0
// The dense grid of sparse-convolution solid noise by bricks (docs/solid.md "Grids"): the
// samples of one cell form a box of grid indices when the metric is diagonal, so a brick's
// points need no grouping and its impulses are splatted into it row by row (as the 2-D
// renderer splats into tiles), skipping the rows an impulse cannot reach. Every sample still
// adds its impulses in the canonical order with the point path's arithmetic: the same bits.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "synth/solid.h"
#include "synth/detail/solid_cells.h"
#include "synth/detail/solid_loops.h"

namespace impulse::synth::detail {

DenseCells::DenseCells(const numeric::CounterRng& rng, double m, const std::array<int64_t, 3>& box_lo,
                       const std::array<int64_t, 3>& box_n, const CellPeriod& period)
    : lo(box_lo), n(box_n) {
    const size_t cells = size_t(n[0] * n[1] * n[2]);
    std::vector<uint32_t> count(cells);
    auto cell_of = [&](size_t i) {
        return std::array<int64_t, 3>{lo[0] + int64_t(i / size_t(n[1] * n[2])),
                                      lo[1] + int64_t(i / size_t(n[2]) % size_t(n[1])),
                                      lo[2] + int64_t(i % size_t(n[2]))};
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, 256), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const auto c = cell_of(i);
            count[i] = uint32_t(cell_count(rng, c[0], c[1], c[2], m, period));
        }
    });
    offset.assign(cells + 1, 0);
    for (size_t i = 0; i < cells; ++i) offset[i + 1] = offset[i] + count[i];
    for (auto& v : u) v.resize(offset[cells]);
    a.resize(offset[cells]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, 256), [&](const auto& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const auto c = cell_of(i);
            for (uint32_t j = 0; j < count[i]; ++j) {
                float w[3];
                const size_t k = offset[i] + j;
                cell_impulse(rng, c[0], c[1], c[2], int(j), period, w, a[k]);
                for (int d = 0; d < 3; ++d) u[d][k] = w[d];
            }
        }
    });
}

/// The impulses of the 3^3 cells around `c` in the canonical order (lexicographic offsets, draw
/// order), relative to c, without those farther than one radius from the box [lo, hi].
void gather_box(const DenseCells& table, const std::array<int64_t, 3>& c, const float* lo,
                const float* hi, Gathered<3>& out) {
    std::array<size_t, 9> row;  // linear index of the cell (c0 + o0, c1 + o1, c2)
    size_t total = 0;
    for (int r = 0; r < 9; ++r) {
        row[r] = table.linear(c[0] + r / 3 - 1, c[1] + r % 3 - 1, c[2]);
        total += table.offset[row[r] + 2] - table.offset[row[r] - 1];
    }
    for (auto& v : out.v) v.resize(total);
    out.a.resize(total);
    float* __restrict v0 = out.v[0].data();
    float* __restrict v1 = out.v[1].data();
    float* __restrict v2 = out.v[2].data();
    float* __restrict amp = out.a.data();
    const float* u0 = table.u[0].data();
    const float* u1 = table.u[1].data();
    const float* u2 = table.u[2].data();
    const float* a = table.a.data();
    const float lx = lo[0], ly = lo[1], lz = lo[2], hx = hi[0], hy = hi[1], hz = hi[2];
    size_t kept = 0;
    for (int r = 0; r < 9; ++r) {
        const float o0 = float(r / 3 - 1), o1 = float(r % 3 - 1);
        // Branch-free: each impulse is written, then kept or overwritten. (float) o + u is the
        // exact sum rounded once, as the general path's double sum cast to float.
        for (int o2 = -1; o2 <= 1; ++o2) {
            const float o2f = float(o2);
            const uint32_t end = table.offset[row[r] + o2 + 1];
            for (uint32_t k = table.offset[row[r] + o2]; k < end; ++k) {
                const float x = o0 + u0[k], y = o1 + u1[k], z = o2f + u2[k];
                const float ex = std::max(std::max(lx - x, x - hx), 0.0f);
                const float ey = std::max(std::max(ly - y, y - hy), 0.0f);
                const float ez = std::max(std::max(lz - z, z - hz), 0.0f);
                v0[kept] = x, v1[kept] = y, v2[kept] = z, amp[kept] = a[k];
                kept += (ex * ex + ey * ey) + ez * ez < 1.001f;  // else 0 at every point of the box
            }
        }
    }
    for (auto& v : out.v) v.resize(kept);
    out.a.resize(kept);
}

namespace {

constexpr int kPieceX = 32, kPieceYZ = 8;  // brick sides in samples: acc stays in L1
constexpr double kMaxTableCells = 1 << 20;  // per slab of bricks

/// One axis of the grid in cell units: each sample's cell and its position in it (as
/// group_by_cell computes them), and pieces [begin[p], begin[p + 1]) of at most `limit` samples
/// within one cell.
struct Axis {
    std::vector<int64_t> cell;
    std::vector<float> local;
    std::vector<int> begin;
};

/// False when a coordinate is beyond what the point path accepts (it then reports it).
bool make_axis(int n, double origin, double spacing, double warp, int limit, Axis& axis) {
    constexpr double kLimit = 1099511627776.0;  // 2^40 cells, as group_by_cell
    axis.cell.resize(n);
    axis.local.resize(n);
    for (int i = 0; i < n; ++i) {
        // The point path's warp: warp x + 0 y + 0 z, the zeros changing at most a zero's sign,
        // which neither floor nor the local position sees.
        const double w = warp * (origin + i * spacing);
        if (!(std::abs(w) < kLimit)) return false;
        const double f = std::floor(w);
        axis.cell[i] = static_cast<int64_t>(f);
        axis.local[i] = std::min(static_cast<float>(w - f), 0x1.fffffep-1f);
    }
    for (int i = 0; i < n; ++i)
        if (i == 0 || axis.cell[i] != axis.cell[i - 1] || i - axis.begin.back() >= limit)
            axis.begin.push_back(i);
    axis.begin.push_back(n);
    return true;
}

}  // namespace

bool grid_by_bricks(const SolidNoise& noise, const std::array<int, 3>& size, const SolidPoint& origin,
                    double spacing, int component, float* out) {
    const SolidParams& p = noise.params();
    const LoopKernel lk = loop_kernel(noise.kernel());
    const BrickFn brick = brick_loop(lk);
    if (p.dims != 3 || !brick || !(spacing > 0.0)) return false;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            if ((r == c) != (p.metric[3 * r + c] != 0.0) || p.metric[3 * r + c] < 0.0) return false;
    const double R = noise.kernel().radius();
    const double o[3] = {origin.x, origin.y, origin.z};
    Axis axes[3];
    for (int d = 0; d < 3; ++d)
        if (!make_axis(size[d], o[d], spacing, p.metric[4 * d] / R, d == 0 ? kPieceX : kPieceYZ, axes[d]))
            return false;
    const std::array<int64_t, 3> lo = {axes[0].cell.front() - 1, axes[1].cell.front() - 1, 0};
    const int64_t nx = axes[0].cell.back() - lo[0] + 2, ny = axes[1].cell.back() - lo[1] + 2;
    if (double(nx) * double(ny) * 3.0 > kMaxTableCells) return false;
    const numeric::CounterRng rng = numeric::CounterRng(p.seed, kSolidStream).keyed(component);
    const double m = p.density / (4.0 / 3.0 * std::numbers::pi);  // per cell of side R, as run_batch
    const Axis& az = axes[2];
    const int pieces_x = int(axes[0].begin.size()) - 1, pieces_y = int(axes[1].begin.size()) - 1;
    const int pieces_z = int(az.begin.size()) - 1;
    const size_t plane = size_t(size[0]) * size[1];
    // Slabs of z pieces whose cells (and one more on each side) fit the table budget.
    const int slab = std::max(1, int(kMaxTableCells / double(nx * ny)) - 2);
    for (int z0 = 0; z0 < pieces_z;) {
        int z1 = z0;
        while (z1 < pieces_z && az.cell[az.begin[z1]] - az.cell[az.begin[z0]] < slab) ++z1;
        const int64_t cz0 = az.cell[az.begin[z0]] - 1, cz1 = az.cell[az.begin[z1] - 1] + 1;
        const DenseCells table(rng, m, {lo[0], lo[1], cz0}, {nx, ny, cz1 - cz0 + 1}, p.period_cells);
        const size_t bricks = size_t(z1 - z0) * pieces_y * pieces_x;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, bricks, 4), [&](const auto& r) {
            Gathered<3> g;
            std::vector<float> acc;
            alignas(32) float tx[kBrickRow];
            for (size_t b = r.begin(); b != r.end(); ++b) {
                const int px = int(b % pieces_x), py = int(b / pieces_x % pieces_y);
                const int pz = z0 + int(b / (size_t(pieces_x) * pieces_y));
                const Axis* ax[3] = {&axes[0], &axes[1], &az};
                const int piece[3] = {px, py, pz};
                std::array<int, 3> first, count;
                std::array<int64_t, 3> cell;
                float box_lo[3], box_hi[3];
                for (int d = 0; d < 3; ++d) {
                    first[d] = ax[d]->begin[piece[d]];
                    count[d] = ax[d]->begin[piece[d] + 1] - first[d];
                    cell[d] = ax[d]->cell[first[d]];
                    box_lo[d] = ax[d]->local[first[d]];
                    box_hi[d] = ax[d]->local[first[d] + count[d] - 1];
                }
                gather_box(table, cell, box_lo, box_hi, g);
                const int wx = (count[0] + 7) & ~7;  // whole vectors: no scalar remainder
                for (int i = 0; i < wx; ++i) tx[i] = axes[0].local[first[0] + std::min(i, count[0] - 1)];
                acc.assign(size_t(wx) * count[1] * count[2], 0.0f);
                brick(lk, g, {tx, &axes[1].local[first[1]], &az.local[first[2]]}, {wx, count[1], count[2]},
                      acc.data());
                for (int z = 0; z < count[2]; ++z)
                    for (int y = 0; y < count[1]; ++y)
                        std::copy_n(acc.data() + (size_t(z) * count[1] + y) * wx, count[0],
                                    out + size_t(first[2] + z) * plane + size_t(first[1] + y) * size[0] + first[0]);
            }
        });
        z0 = z1;
    }
    return true;
}

}  // namespace impulse::synth::detail
