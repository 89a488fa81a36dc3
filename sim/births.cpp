// SPDX-License-Identifier: Apache-2.0
// Cell-seeded Poisson births (Lewis 1986 §3.1 "numbered cells", here in space and time).

#include <cmath>

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

void generate_cell(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out, std::vector<BirthTime>* births) {
    out.x.clear();
    out.y.clear();
    out.birth_s.clear();
    out.amplitude.clear();
    out.theta0.clear();
    if (births) births->clear();

    // The key uses the wrapped cell (periodic domain, looped time); positions and birth times
    // use the unwrapped ones, so copies are the same impulses shifted by a period.
    const CellKey key(L, cx, cy, ct);
    const CounterRng rng(c.seed, c.layer);
    const int count = cell_count(rng, L, key);
    for (int k = 0; k < count; ++k) {
        const ImpulseDraw d = draw_impulse(c, L, rng, key, cx, cy, k);
        out.x.push_back(d.x);
        out.y.push_back(d.y);
        BirthTime b;
        if (L.time_cell_s > 0)
            b = {(static_cast<double>(key.kt) + d.birth_u) * L.time_cell_s, key.loop_index};
        out.birth_s.push_back(b.phase_s + static_cast<double>(b.loop_index) * c.loop_s);
        if (births) births->push_back(b);
        out.amplitude.push_back(d.amplitude);
        out.theta0.push_back(d.theta0);
    }
}

}  // namespace detail

void cell_impulses(const ProcessConfig& config, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out) {
    detail::generate_cell(config, detail::Layout(config), cx, cy, ct, out, nullptr);
}

double expected_impulses(const ProcessConfig& config, const Region& region) {
    // Live impulses in the region, plus the not-yet-dead part of the time cells kept around
    // them (the simulator holds about (T + 3 dt_cell) / T of the live count).
    double n = config.intensity * region.area();
    if (config.lifetime_s > 0) n *= 1.75;
    return n;
}

}  // namespace impulse::sim
