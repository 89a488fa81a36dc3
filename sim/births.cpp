// SPDX-License-Identifier: Apache-2.0
// Cell-seeded Poisson births (Lewis 1986 §3.1 "numbered cells", here in space and time).

#include <cmath>
#include <numbers>

#include "sim/layout.h"
#include "sim/rng.h"

namespace impulse::sim {
namespace detail {

int poisson_inverse(double mean, double u) {
    // Walk the CDF from k = 0; terminates because u <= 1 and the CDF reaches 1 - eps. The
    // cap guards against rounding leaving the CDF just below u.
    double p = std::exp(-mean), cdf = p;
    int k = 0;
    const int cap = static_cast<int>(mean + 40.0 * std::sqrt(mean) + 40.0);
    while (u > cdf && k < cap) {
        ++k;
        p *= mean / k;
        cdf += p;
    }
    return k;
}

namespace {

/// The key of a cell: wrapped (periodic domain, looped time), with the loop index of ct.
struct CellKey {
    int64_t kx, ky, kt, loop_index;
};
CellKey cell_key(const Layout& L, int64_t cx, int64_t cy, int64_t ct) {
    // The key uses the wrapped cell (periodic domain, looped time); positions and birth times
    // use the unwrapped ones, so copies are the same impulses shifted by a period.
    return {L.period_cells_x ? floor_mod(cx, L.period_cells_x) : cx,
            L.period_cells_y ? floor_mod(cy, L.period_cells_y) : cy,
            L.loop_cells ? floor_mod(ct, L.loop_cells) : ct,
            L.loop_cells ? floor_div(ct, L.loop_cells) : 0};
}

}  // namespace

int cell_count(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct) {
    const CellKey key = cell_key(L, cx, cy, ct);
    const CounterRng rng(c.seed, c.layer);
    // Large means are split into independent Poisson parts (the sum of Poissons is Poisson)
    // so the inversion stays accurate (exp(-mean) does not underflow).
    const int parts = static_cast<int>(std::ceil(L.mean_per_cell / 200.0));
    int count = 0;
    for (int p = 0; p < std::max(parts, 1); ++p) {
        const auto u = rng.uniforms(key.kx, key.ky, key.kt, 0xFFFFFFFFu - static_cast<uint32_t>(p));
        count += poisson_inverse(L.mean_per_cell / std::max(parts, 1), u[0]);
    }
    return count;
}

CellBirth cell_birth(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct,
                     int k) {
    const CellKey key = cell_key(L, cx, cy, ct);
    const CounterRng rng(c.seed, c.layer);
    const auto r0 = rng.uniforms(key.kx, key.ky, key.kt, 2u * k);
    const auto r1 = rng.uniforms(key.kx, key.ky, key.kt, 2u * k + 1u);
    CellBirth b;
    b.x = (static_cast<double>(cx) + r0[0]) * L.cell_x;
    b.y = (static_cast<double>(cy) + r0[1]) * L.cell_y;
    if (L.time_cell_s > 0) b.time = {(static_cast<double>(key.kt) + r0[2]) * L.time_cell_s, key.loop_index};
    switch (c.amplitude) {
        case Amplitude::Normal:  // Box–Muller; u in (0, 1] so the log is finite
            b.amplitude = static_cast<float>(std::sqrt(-2.0 * std::log(r0[3])) *
                                             std::cos(2.0 * std::numbers::pi * r1[0]));
            break;
        case Amplitude::Uniform: b.amplitude = static_cast<float>(2.0 * r0[3] - 1.0); break;
        case Amplitude::Sign: b.amplitude = r0[3] < 0.5 ? -1.0f : 1.0f; break;
    }
    b.theta0 = static_cast<float>(2.0 * std::numbers::pi * r1[1]);
    return b;
}

void generate_cell(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out, std::vector<BirthTime>* births) {
    out.x.clear();
    out.y.clear();
    out.birth_s.clear();
    out.amplitude.clear();
    out.theta0.clear();
    if (births) births->clear();
    const int count = cell_count(c, L, cx, cy, ct);
    for (int k = 0; k < count; ++k) {
        const CellBirth b = cell_birth(c, L, cx, cy, ct, k);
        out.x.push_back(b.x);
        out.y.push_back(b.y);
        out.birth_s.push_back(b.time.phase_s + static_cast<double>(b.time.loop_index) * c.loop_s);
        if (births) births->push_back(b.time);
        out.amplitude.push_back(b.amplitude);
        out.theta0.push_back(b.theta0);
    }
}

}  // namespace detail

void cell_impulses(const ProcessConfig& config, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out) {
    detail::generate_cell(config, detail::Layout(config), cx, cy, ct, out, nullptr);
}

double expected_impulses(const ProcessConfig& config, const Box& region) {
    // Live impulses in the region, plus the not-yet-dead part of the time cells kept around
    // them (the simulator holds about (T + 3 dt_cell) / T of the live count).
    double n = config.intensity * region.area();
    if (config.lifetime_s > 0) n *= 1.75;
    return n;
}

}  // namespace impulse::sim
