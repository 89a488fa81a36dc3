// SPDX-License-Identifier: Apache-2.0
// Sparse-convolution solid noise at 3-D points that fill their bounding box (docs/solid.md
// "Batches"): a counting sort groups the points by cell in parallel (no comparison sort), a
// dense table holds every cell's impulses (L89 §4.1's cache, generated once per batch), and each
// cell's points are evaluated against the impulses gathered for the box they occupy. The value
// of a point is its impulses' sum in the canonical order whatever its group: the bits of the
// general path.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>

#include "synth/solid.h"
#include "synth/detail/solid_cells.h"
#include "synth/detail/solid_loops.h"

namespace impulse::synth::detail {
namespace {

constexpr size_t kHistogramBudget = size_t(1) << 23;  // counters over all chunks

/// Points to cell units: w = (M / R) p, exactly as SolidNoise's general path computes it.
struct Warp {
    std::array<double, 9> w;
    void operator()(const SolidPoint& q, double* o) const {
        for (int r = 0; r < 3; ++r) o[r] = w[3 * r] * q.x + w[3 * r + 1] * q.y + w[3 * r + 2] * q.z;
    }
};

/// floor(w) for |w| < 2^31 without a library call (x86-64's baseline has no rounding
/// instruction). For w = -0 it gives +0 where std::floor gives -0: the local position is then
/// -0 instead of +0, which no difference t - v, square or bound sees.
inline double floor_small(double w) {
    const double t = static_cast<double>(static_cast<int64_t>(w));  // toward zero
    return t > w ? t - 1.0 : t;
}

/// The box of cells the points fall in (ok false when a point is out of range); the warp is
/// computed again where the keys are made rather than stored (less memory to fault in).
struct CellBox {
    std::array<int64_t, 3> lo{INT64_MAX, INT64_MAX, INT64_MAX}, hi{INT64_MIN, INT64_MIN, INT64_MIN};
    bool ok = true;
};

constexpr size_t kChunks = 64;  // fixed: the same work split whatever the thread count

CellBox cell_box(const std::vector<SolidPoint>& points, const Warp& warp) {
    const size_t count = points.size(), per = (count + kChunks - 1) / kChunks;
    std::vector<CellBox> part(kChunks);
    tbb::parallel_for(size_t(0), kChunks, [&](size_t k) {
        CellBox& b = part[k];
        for (size_t i = k * per; i < std::min(count, (k + 1) * per); ++i) {
            double w[3];
            warp(points[i], w);
            for (int d = 0; d < 3; ++d) {
                b.ok = b.ok && std::abs(w[d]) < double(INT32_MAX);
                const int64_t c = b.ok ? static_cast<int64_t>(floor_small(w[d])) : 0;
                b.lo[d] = std::min(b.lo[d], c), b.hi[d] = std::max(b.hi[d], c);
            }
        }
    });
    CellBox box;
    for (const CellBox& b : part) {
        for (int d = 0; d < 3; ++d) box.lo[d] = std::min(box.lo[d], b.lo[d]), box.hi[d] = std::max(box.hi[d], b.hi[d]);
        box.ok = box.ok && b.ok;
    }
    return box;
}

/// A point of a group: its position in its cell (cell units) and the caller's index; one
/// 16-byte record, so the sort's scatter touches one cache line per point.
struct GroupPoint {
    std::array<float, 3> t;
    uint32_t index;
};

/// Points sorted by cell: cell c (linear in the box) holds [start[c], start[c + 1]).
struct SortedPoints {
    std::vector<GroupPoint> point;
    std::vector<uint32_t> start;
};

/// A counting sort on the cell, in parallel: chunk k counts its points per cell, the counts
/// give each (cell, chunk) its place, and the chunks scatter their points there.
SortedPoints sort_by_cell(const std::vector<SolidPoint>& points, const Warp& warp,
                          const std::array<int64_t, 3>& lo, const std::array<int64_t, 3>& n) {
    const size_t count = points.size(), cells = size_t(n[0] * n[1] * n[2]);
    const size_t chunks = std::clamp<size_t>(kHistogramBudget / cells, 1, 16);
    const size_t per = (count + chunks - 1) / chunks;
    std::vector<uint32_t> key(count), histogram(chunks * cells, 0);
    std::vector<GroupPoint> local(count);
    tbb::parallel_for(size_t(0), chunks, [&](size_t k) {
        uint32_t* h = histogram.data() + k * cells;
        for (size_t i = k * per; i < std::min(count, (k + 1) * per); ++i) {
            double w[3];
            warp(points[i], w);
            int64_t linear = 0;
            for (int d = 0; d < 3; ++d) {
                const double f = floor_small(w[d]);
                linear = linear * n[d] + (static_cast<int64_t>(f) - lo[d]);
                // Clamp: w - floor(w) can round up to 1 for tiny negative w (group_by_cell).
                local[i].t[d] = std::min(static_cast<float>(w[d] - f), 0x1.fffffep-1f);
            }
            local[i].index = static_cast<uint32_t>(i);
            key[i] = static_cast<uint32_t>(linear);
            ++h[key[i]];
        }
    });
    SortedPoints s;
    s.start.resize(cells + 1);
    uint32_t at = 0;
    for (size_t c = 0; c < cells; ++c) {
        s.start[c] = at;
        for (size_t k = 0; k < chunks; ++k) {
            const uint32_t h = histogram[k * cells + c];
            histogram[k * cells + c] = at;
            at += h;
        }
    }
    s.start[cells] = at;
    s.point.resize(count);
    tbb::parallel_for(size_t(0), chunks, [&](size_t k) {
        uint32_t* place = histogram.data() + k * cells;
        for (size_t i = k * per; i < std::min(count, (k + 1) * per); ++i) s.point[place[key[i]]++] = local[i];
    });
    return s;
}

constexpr size_t kSplitPoints = 64;  // a box with this many points is cut in octants
constexpr int kMaxDepth = 3;

/// Points of one box.
struct Group {
    const GroupPoint* point;
    size_t n;
};

/// Scratch of one task: the gathered impulses, the points padded to whole vectors, and the
/// octants' points at each depth.
struct Scratch {
    Gathered<3> gathered;
    std::array<std::vector<float>, 3> t;
    std::vector<float> acc;
    std::array<std::vector<GroupPoint>, kMaxDepth> level;
};

/// The points of g against the impulses gathered for their bounding box.
void evaluate_leaf(const LoopKernel& lk, const DenseCells& table, const std::array<int64_t, 3>& cell,
                   const Group& g, Scratch& w, float* values) {
    // The box of the points, and the points as the loop reads them (structure of arrays).
    const size_t lanes = loop_lanes();
    const size_t padded = g.n < 8 ? g.n : (g.n + lanes - 1) / lanes * lanes;
    float lo[3] = {1.0f, 1.0f, 1.0f}, hi[3] = {0.0f, 0.0f, 0.0f};
    for (int d = 0; d < 3; ++d) w.t[d].resize(padded);
    for (size_t i = 0; i < padded; ++i) {
        const GroupPoint& q = g.point[std::min(i, g.n - 1)];  // lanes past n repeat the last
        for (int d = 0; d < 3; ++d) {
            w.t[d][i] = q.t[d];
            lo[d] = std::min(lo[d], q.t[d]), hi[d] = std::max(hi[d], q.t[d]);
        }
    }
    gather_box(table, cell, lo, hi, w.gathered);
    w.acc.assign(padded, 0.0f);
    accumulate<3>(lk, w.gathered, {w.t[0].data(), w.t[1].data(), w.t[2].data()}, padded, w.acc.data());
    for (size_t i = 0; i < g.n; ++i) values[g.point[i].index] = w.acc[i];
}

/// The points of g, in the box corner + [0, side)^3 of their cell: cut in octants while they are
/// many (the impulses within reach of an octant are about half those of its parent box: Steiner's
/// formula, 10.5 against 20.6 R^3 for a half cell), else a leaf.
void evaluate_group(const LoopKernel& lk, const DenseCells& table, const std::array<int64_t, 3>& cell,
                    const Group& g, const std::array<float, 3>& corner, float side, int depth,
                    Scratch& w, float* values) {
    if (g.n < kSplitPoints || depth == kMaxDepth) {
        evaluate_leaf(lk, table, cell, g, w, values);
        return;
    }
    const float half = 0.5f * side;
    auto octant = [&](size_t i) {
        int o = 0;
        for (int d = 0; d < 3; ++d) o = 2 * o + (g.point[i].t[d] >= corner[d] + half);
        return o;
    };
    std::array<size_t, 9> start{};
    for (size_t i = 0; i < g.n; ++i) ++start[octant(i) + 1];
    for (int o = 0; o < 8; ++o) start[o + 1] += start[o];
    std::vector<GroupPoint>& l = w.level[depth];
    l.resize(g.n);
    std::array<size_t, 8> at;
    std::copy_n(start.begin(), 8, at.begin());
    for (size_t i = 0; i < g.n; ++i) l[at[octant(i)]++] = g.point[i];
    for (int o = 0; o < 8; ++o) {
        if (start[o + 1] == start[o]) continue;
        const Group child{l.data() + start[o], start[o + 1] - start[o]};
        std::array<float, 3> c = corner;
        for (int d = 0; d < 3; ++d) c[d] += (o >> (2 - d) & 1) ? half : 0.0f;
        evaluate_group(lk, table, cell, child, c, half, depth + 1, w, values);
    }
}

}  // namespace

bool evaluate_dense(const SolidNoise& noise, const std::vector<SolidPoint>& points, int component,
                    float* values) {
    const SolidParams& p = noise.params();
    if (p.dims != 3 || points.empty() || points.size() > 0xFFFFFFFFull) return false;
    Warp warp;
    for (int i = 0; i < 9; ++i) warp.w[i] = p.metric[i] / noise.kernel().radius();
    const CellBox box = cell_box(points, warp);
    if (!box.ok) return false;  // the general path names the point or takes the far cells
    std::array<int64_t, 3> n;
    double cells = 1.0;
    for (int d = 0; d < 3; ++d) {
        n[d] = box.hi[d] - box.lo[d] + 1;
        cells *= double(n[d] + 2);
    }
    // The table costs a few draws per cell: worth it while cells are not many more than points.
    if (cells > 4.0 * double(points.size()) + 65536.0 || cells > double(1 << 26)) return false;
    const SortedPoints s = sort_by_cell(points, warp, box.lo, n);
    const numeric::CounterRng rng = numeric::CounterRng(p.seed, kSolidStream).keyed(component);
    const double m = p.density / (4.0 / 3.0 * std::numbers::pi);  // per cell of side R, as run_batch
    const DenseCells table(rng, m, {box.lo[0] - 1, box.lo[1] - 1, box.lo[2] - 1},
                           {n[0] + 2, n[1] + 2, n[2] + 2}, p.period_cells);
    const LoopKernel lk = loop_kernel(noise.kernel());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, s.start.size() - 1, 16), [&](const auto& r) {
        Scratch w;
        for (size_t c = r.begin(); c != r.end(); ++c) {
            const size_t s0 = s.start[c], count = s.start[c + 1] - s0;
            if (count == 0) continue;
            const std::array<int64_t, 3> cell = {box.lo[0] + int64_t(c / size_t(n[1] * n[2])),
                                                 box.lo[1] + int64_t(c / size_t(n[2]) % size_t(n[1])),
                                                 box.lo[2] + int64_t(c % size_t(n[2]))};
            const Group g{s.point.data() + s0, count};
            evaluate_group(lk, table, cell, g, {0.0f, 0.0f, 0.0f}, 1.0f, 0, w, values);
        }
    });
    return true;
}

}  // namespace impulse::synth::detail
