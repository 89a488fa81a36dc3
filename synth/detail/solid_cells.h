// SPDX-License-Identifier: Apache-2.0
#pragma once
// The Poisson impulses of sparse-convolution solid noise's cells (internal to impulse::synth):
// the draws that define them (L89 §4.1: "N Poisson-distributed impulses in each voxel", drawn
// from the counter RNG keyed by the cell, so every path sees the same impulses) and a dense
// table of a box of 3-D cells, generated in parallel without sorting (the batch's cache).

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "numeric/rng.h"
#include "synth/detail/solid_loops.h"

namespace impulse::synth {
class SolidNoise;
struct SolidPoint;
}  // namespace impulse::synth

namespace impulse::synth::detail {

constexpr uint32_t kSolidStream = 0x534F4C44u;  // "SOLD": the solid noise's counter stream

/// Poisson count of mean m from one uniform u in (0, 1] by the inverse CDF. m <= 750, so
/// e^{-m} stays normal.
inline int poisson(double u, double m) {
    double p = std::exp(-m), F = p;
    int k = 0;
    const int cap = static_cast<int>(m + 20.0 * std::sqrt(m) + 40.0);
    while (u > F && k < cap) {
        ++k;
        p *= m / k;
        F += p;
    }
    return k;
}

/// Cells per period along x, y, z (SolidParams::period_cells; 0: that axis is not periodic).
using CellPeriod = std::array<int64_t, 3>;

/// The key of cell index c on an axis of n cells a period: c reduced into [0, n) (c when n is
/// 0), so cell c + n draws the impulses of cell c and the noise repeats (Lewis 1986 §3.2).
inline int64_t wrap_cell(int64_t c, int64_t n) { return n > 0 ? (c % n + n) % n : c; }

/// Number of impulses of cell (x, y, z) under `rng`: draw 0.
inline int cell_count(const numeric::CounterRng& rng, int64_t x, int64_t y, int64_t z, double m,
                      const CellPeriod& period) {
    return poisson(rng.uniforms(wrap_cell(x, period[0]), wrap_cell(y, period[1]), wrap_cell(z, period[2]), 0)[0], m);
}

/// Impulse j of cell (x, y, z): draw j + 1 gives its position in the cell, in (0, 1]^3 (cell
/// units; 1 is the far face, still within reach of the 3^3 neighbourhood), and amplitude.
inline void cell_impulse(const numeric::CounterRng& rng, int64_t x, int64_t y, int64_t z, int j,
                         const CellPeriod& period, float* u, float& a) {
    const auto r = rng.uniforms(wrap_cell(x, period[0]), wrap_cell(y, period[1]), wrap_cell(z, period[2]), uint32_t(j + 1));
    for (int d = 0; d < 3; ++d) u[d] = static_cast<float>(r[d]);
    a = static_cast<float>(2.0 * r[3] - 1.0);
}

/// The impulses of every cell of the box lo + [0, n) (3-D), structure of arrays, cell by cell in
/// linear order (x slowest, as the neighbour order), each cell's in draw order.
struct DenseCells {
    std::array<int64_t, 3> lo{}, n{};
    std::vector<uint32_t> offset;  ///< impulses of linear cell i: [offset[i], offset[i + 1])
    std::array<std::vector<float>, 3> u;
    std::vector<float> a;

    /// Generates them (TBB-parallel; the same table for any thread count).
    DenseCells(const numeric::CounterRng& rng, double m, const std::array<int64_t, 3>& lo,
               const std::array<int64_t, 3>& n, const CellPeriod& period);
    size_t linear(int64_t x, int64_t y, int64_t z) const {
        return size_t(((x - lo[0]) * n[1] + (y - lo[1])) * n[2] + (z - lo[2]));
    }
};

/// The impulses of the 3^3 cells around `c` in the canonical order (lexicographic offsets, draw
/// order), relative to c, without those farther than one radius from the box [lo, hi] (cell
/// units; they add exactly 0 to every point in it).
void gather_box(const DenseCells& table, const std::array<int64_t, 3>& c, const float* lo,
                const float* hi, Gathered<3>& out);

/// SolidNoise::grid by bricks (synth/solid_grid.cpp): when the noise is 3-D with a diagonal
/// metric of positive entries, spacing > 0 and a polynomial kernel, writes the grid into out
/// (width * height * depth floats, x fastest) with the bits of the point path and returns true;
/// otherwise (or for coordinates the point path must refuse) returns false and writes nothing.
bool grid_by_bricks(const SolidNoise& noise, const std::array<int, 3>& size, const SolidPoint& origin,
                    double spacing, int component, float* out);

/// SolidNoise::evaluate for 3-D points whose cells fill their bounding box densely enough
/// (synth/solid_points.cpp): impulses from a DenseCells table, points grouped by a counting sort
/// on the cell, the same bits as any other path. False (nothing written) for 4-D noise, a span
/// too sparse for the table, or a point the general path must refuse.
bool evaluate_dense(const SolidNoise& noise, const std::vector<SolidPoint>& points, int component,
                    float* values);

}  // namespace impulse::synth::detail
