// SPDX-License-Identifier: Apache-2.0
#pragma once
// How a process is cut into seeding cells in space and time (internal to impulse::sim).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

#include "sim/rng.h"
#include "sim/sim.h"

namespace impulse::sim::detail {

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

    explicit Layout(const ProcessConfig& c) {
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

/// The generator keys of cell (cx, cy, ct): wrapped for a periodic domain and a looped time
/// axis, so copies one period apart draw the same numbers.
struct CellKey {
    int64_t kx, ky, kt, loop_index;
    CellKey(const Layout& L, int64_t cx, int64_t cy, int64_t ct)
        : kx(L.period_cells_x ? floor_mod(cx, L.period_cells_x) : cx),
          ky(L.period_cells_y ? floor_mod(cy, L.period_cells_y) : cy),
          kt(L.loop_cells ? floor_mod(ct, L.loop_cells) : ct),
          loop_index(L.loop_cells ? floor_div(ct, L.loop_cells) : 0) {}
};

/// Number of impulses born in a cell (Lewis 1986 §3.1: a Poisson count per numbered cell).
inline int cell_count(const CounterRng& rng, const Layout& L, const CellKey& key) {
    // Large means are split into independent Poisson parts (the sum of Poissons is Poisson)
    // so the inversion stays accurate (exp(-mean) does not underflow).
    const int parts = std::max(static_cast<int>(std::ceil(L.mean_per_cell / 200.0)), 1);
    int count = 0;
    for (int p = 0; p < parts; ++p) {
        const auto u = rng.uniforms(key.kx, key.ky, key.kt, 0xFFFFFFFFu - static_cast<uint32_t>(p));
        count += poisson_inverse(L.mean_per_cell / parts, u[0]);
    }
    return count;
}

/// Impulse k of cell (cx, cy): position (unwrapped cell, so periodic copies are shifted by the
/// period), the uniform that places its birth in the time cell, amplitude and random angle.
struct ImpulseDraw {
    double x, y, birth_u;
    float amplitude, theta0;
};
inline ImpulseDraw draw_impulse(const ProcessConfig& c, const Layout& L, const CounterRng& rng,
                                const CellKey& key, int64_t cx, int64_t cy, int k) {
    const auto r0 = rng.uniforms(key.kx, key.ky, key.kt, 2u * static_cast<uint32_t>(k));
    const auto r1 = rng.uniforms(key.kx, key.ky, key.kt, 2u * static_cast<uint32_t>(k) + 1u);
    ImpulseDraw d;
    d.x = (static_cast<double>(cx) + r0[0]) * L.cell_x;
    d.y = (static_cast<double>(cy) + r0[1]) * L.cell_y;
    d.birth_u = r0[2];
    d.amplitude = 0.0f;
    switch (c.amplitude) {
        case Amplitude::Normal:  // Box–Muller; u in (0, 1] so the log is finite
            d.amplitude = static_cast<float>(std::sqrt(-2.0 * std::log(r0[3])) *
                                             std::cos(2.0 * std::numbers::pi * r1[0]));
            break;
        case Amplitude::Uniform:
            d.amplitude = static_cast<float>(2.0 * r0[3] - 1.0);
            break;
        case Amplitude::Sign:
            d.amplitude = r0[3] < 0.5 ? -1.0f : 1.0f;
            break;
    }
    d.theta0 = static_cast<float>(2.0 * std::numbers::pi * r1[1]);
    return d;
}

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
    bool contains(double x, double y) const {
        if (!(y >= m_y0 && y <= m_y1)) return false;
        const size_t band =
            std::min(m_bands.size() - 1, static_cast<size_t>((y - m_y0) * m_inv_band));
        for (const uint32_t b : m_bands[band]) {
            const Box& r = m_boxes[b];
            if (x >= r.x0 && x <= r.x1 && y >= r.y0 && y <= r.y1) return true;
        }
        return false;
    }

private:
    std::vector<Box> m_boxes;
    double m_y0 = 0, m_y1 = -1, m_inv_band = 1;
    std::vector<std::vector<uint32_t>> m_bands;
};

}  // namespace impulse::sim::detail
