// SPDX-License-Identifier: Apache-2.0
#pragma once
// How a process is cut into seeding cells in space and time (internal to impulse::sim).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "numeric/rng.h"
#include "numeric/box.h"
#include "sim/simulator.h"

namespace impulse::sim::detail {

using numeric::CounterRng;
using numeric::DrawBatch;
using numeric::cpu_has_avx2;

/// Stream tag (xored into the layer) of the birth-region thinning uniforms ("REGN").
inline constexpr uint32_t kRegionStream = 0x5245474Eu;

/// Poisson(mean) by inversion of one uniform u in (0, 1] (deterministic, no rejection loop).
int poisson_inverse(double mean, double u);

inline int64_t floor_div(int64_t a, int64_t b) {
    const int64_t q = a / b;
    return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}
inline int64_t floor_mod(int64_t a, int64_t b) { return a - floor_div(a, b) * b; }

/// Cell sizes, periods in cells and the expected count per space-time cell.
struct Layout {
    double cell_x = 1, cell_y = 1;
    int64_t period_cells_x = 0, period_cells_y = 0;  ///< 0: not periodic
    double time_cell_s = 0;                          ///< 0: still process
    int64_t loop_cells = 0;                          ///< time cells per loop, 0: no loop
    double mean_per_cell = 0;
    /// The birth region's support (null: births anywhere), taken once: cells outside it hold
    /// no impulse and are never generated.
    std::optional<Box> region_support;
    /// The Poisson CDF of one part of a cell's count, as poisson_inverse sums it (filled by
    /// tabulate_poisson for callers that draw many cells; empty: summed per cell).
    std::vector<double> poisson_cdf;

    explicit Layout(const ProcessConfig& c) {
        if (c.region) region_support = c.region->support();
        cell_x = cell_y = c.cell_size;
        if (c.period) {
            period_cells_x = std::max<int64_t>(1, static_cast<int64_t>((*c.period)[0] / c.cell_size));
            period_cells_y = std::max<int64_t>(1, static_cast<int64_t>((*c.period)[1] / c.cell_size));
            cell_x = (*c.period)[0] / period_cells_x;
            cell_y = (*c.period)[1] / period_cells_y;
        }
        mean_per_cell = c.intensity * cell_x * cell_y;
        if (c.lifetime_s > 0) {
            // Four time cells per lifetime keeps the live set close to what is alive; a loop
            // needs a whole number of time cells per period.
            time_cell_s = c.lifetime_s / 4.0;
            if (c.loop_s > 0) {
                loop_cells = std::max<int64_t>(1, std::llround(c.loop_s / time_cell_s));
                time_cell_s = c.loop_s / loop_cells;
            }
            // births per unit area per second beta = lambda / T (expected live = beta T)
            mean_per_cell *= time_cell_s / c.lifetime_s;
        }
    }
};

/// A birth time kept in loop-reduced form so looped copies have bit-identical arithmetic:
/// time = phase_s + loop_index * loop_s.
struct BirthTime {
    double phase_s = 0;
    int64_t loop_index = 0;
};

/// Impulse k of a cell: a pure function of (config, cell, k), so cells can be generated in
/// pieces and in parallel (the simulator writes each straight into its particle arrays).
struct CellBirth {
    double x = 0, y = 0;
    BirthTime time;
    float amplitude = 0, theta0 = 0;
};
/// How many candidate births cell (cx, cy, ct) holds (Poisson at the process's maximum rate).
int cell_candidates(const ProcessConfig& config, const Layout& layout, int64_t cx, int64_t cy,
                    int64_t ct);
/// Fill layout.poisson_cdf: cell_candidates then looks the count up instead of summing it.
void tabulate_poisson(Layout& layout);
/// Whether births are thinned (a birth region, or a keyframed density).
bool thins(const ProcessConfig& config, const Layout& layout);
/// Whether the cell lies outside the birth region's support (it then holds no impulse).
bool outside_region(const Layout& layout, int64_t cx, int64_t cy);
/// How many impulses cell (cx, cy, ct) holds: its candidates that survive the thinning.
int cell_count(const ProcessConfig& config, const Layout& layout, int64_t cx, int64_t cy,
               int64_t ct);
/// Candidate k of a cell into `b`; false when the thinning removes it (b is then partly set).
bool cell_birth(const ProcessConfig& config, const Layout& layout, int64_t cx, int64_t cy,
                int64_t ct, int k, CellBirth& b);

/// cell_impulses with the birth times in reduced form (used by the simulator).
void generate_cell(const ProcessConfig& config, const Layout& layout, int64_t cx, int64_t cy,
                   int64_t ct, CellImpulses& out, std::vector<BirthTime>* births);

/// The cells to generate for a region: per row of cells cy in [cy0, cy1], the merged ranges
/// [cx_first, cx_last] of cells that meet a box, in increasing order (canonical order).
struct CellCover {
    int64_t cy0 = 0, cy1 = -1;
    std::vector<std::vector<std::pair<int64_t, int64_t>>> rows;  ///< rows[cy - cy0]
};
CellCover cell_cover(const Region& region, const Layout& layout);

/// Whether a point lies in a union of boxes (closed boxes), indexed by horizontal bands.
class BoxIndex {
public:
    explicit BoxIndex(const Region& region);
    bool contains(double x, double y) const { return contains_box(x, y, x, y); }
    /// Whether one of the boxes holds the whole box [x0, x1] x [y0, y1] (a union may hold it
    /// when no single box does: the answer is then false).
    bool contains_box(double x0, double y0, double x1, double y1) const {
        if (!(y0 >= m_y0 && y0 <= m_y1)) return false;
        // A box holding y0 is listed in y0's band (the band of a value grows with it).
        const size_t band =
            std::min(m_bands.size() - 1, static_cast<size_t>((y0 - m_y0) * m_inv_band));
        for (const uint32_t b : m_bands[band]) {
            const Box& r = m_boxes[b];
            if (x0 >= r.x0 && x1 <= r.x1 && y0 >= r.y0 && y1 <= r.y1) return true;
        }
        return false;
    }

private:
    std::vector<Box> m_boxes;
    double m_y0 = 0, m_y1 = -1, m_inv_band = 1;
    std::vector<std::vector<uint32_t>> m_bands;
};

/// A still cell's plan for the fast path (LayerSimulator::impulses_at): its candidates and
/// which of them survive the birth region and fall in the kept boxes. `All`: every candidate;
/// `Mask`: bit k of `mask` (cells of at most 64 candidates); `Test`: test each again.
struct StillCell {
    enum Kept : uint8_t { All, Mask, Test };
    int candidates = 0;
    Kept kept = All;
    uint64_t mask = 0;
};
class NormalBatch;
/// Plan the cells [cx0, cx1] of row cy of a still process against `keep` into plans[0, ...];
/// returns how many of their impulses fall in `keep`. `draws` is scratch.
size_t still_piece_plan(const ProcessConfig& config, const Layout& layout, const BoxIndex& keep,
                        int64_t cy, int64_t cx0, int64_t cx1, StillCell* plans, DrawBatch& draws);
/// Write those impulses, cell by cell and in candidate order, to out[i], out[i + 1], ...: the
/// weight is the amplitude, theta is theta0 when `theta0`, else 0. Returns the next index.
/// `draws` and `normals` are scratch.
size_t still_piece_write(const ProcessConfig& config, const Layout& layout, const BoxIndex& keep,
                         int64_t cy, int64_t cx0, int64_t cx1, const StillCell* plans, bool theta0,
                         DrawBatch& draws, NormalBatch& normals, Impulses& out, size_t i);

}  // namespace impulse::sim::detail
