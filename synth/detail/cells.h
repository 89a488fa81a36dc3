// SPDX-License-Identifier: Apache-2.0
#pragma once
// Points grouped by the unit cell they fall in (internal to impulse::synth; shared by the
// sparse-convolution and lattice solid noises): the batch machinery of Lewis 1989 §4.1 ("the
// noise impulses are stored in a cache array ... and reused if the next location falls within
// the same voxel"), made order-independent by sorting on the cell.

#include <array>
#include <cstdint>
#include <vector>

namespace impulse::synth::detail {

/// Points in cell units, grouped by cell. D = 3 or 4 coordinates per point.
template <int D>
struct CellBatch {
    using Cell = std::array<int64_t, D>;
    /// Per point in sorted order: its index in the caller's array and its position in its cell,
    /// in [0, 1), as floats (the same rounding for a point whatever batch holds it).
    std::vector<uint32_t> index;
    std::array<std::vector<float>, D> local;
    /// Group g holds sorted points [start[g], start[g + 1]) of group cell cells[g] (cells of
    /// side 1 / `split`: floor(split w)); cells ascend lexicographically.
    std::vector<Cell> cells;
    std::vector<size_t> start;
};

/// Groups `n` points given in cell units by position(i, w) (fills w[0..D)) into cells of side
/// 1 / split (split 1 or 2); `local` stays relative to the unit cell. Throws ValueError naming
/// the first point that is not finite or lies beyond 2^40 cells.
template <int D, class Position>
CellBatch<D> group_by_cell(size_t n, const Position& position, int split = 1);

/// Cells cell + o, o in {-1, 0, 1}^D, in lexicographic order of o (the canonical order in which
/// every path sums a cell's neighbours).
template <int D>
std::vector<std::array<int64_t, D>> neighbours(const std::array<int64_t, D>& cell);

}  // namespace impulse::synth::detail

#include "synth/cells.inc"
