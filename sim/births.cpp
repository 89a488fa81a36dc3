// SPDX-License-Identifier: Apache-2.0
// Cell-seeded Poisson births (Lewis 1986 §3.1 "numbered cells", here in space and time).

#include <algorithm>
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
    const int64_t kx = L.period_cells_x ? floor_mod(cx, L.period_cells_x) : cx;
    const int64_t ky = L.period_cells_y ? floor_mod(cy, L.period_cells_y) : cy;
    const int64_t kt = L.loop_cells ? floor_mod(ct, L.loop_cells) : ct;
    const int64_t loop_index = L.loop_cells ? floor_div(ct, L.loop_cells) : 0;
    const CounterRng rng(c.seed, c.layer);
    // Birth-region thinning draws from a stream of its own, so adding a region changes no other
    // draw: a region that accepts everything gives the same impulses, bit for bit.
    const CounterRng region_rng(c.seed, c.layer ^ kRegionStream);

    // Large means are split into independent Poisson parts (the sum of Poissons is Poisson)
    // so the inversion stays accurate (exp(-mean) does not underflow).
    const int parts = static_cast<int>(std::ceil(L.mean_per_cell / 200.0));
    int count = 0;
    for (int p = 0; p < std::max(parts, 1); ++p) {
        const auto u = rng.uniforms(kx, ky, kt, 0xFFFFFFFFu - static_cast<uint32_t>(p));
        count += poisson_inverse(L.mean_per_cell / std::max(parts, 1), u[0]);
    }

    // Uniforms of impulse k: r0 = (x, y, birth time, amplitude), r1 = (normal amplitude's
    // angle, theta0, density thinning, unused).
    const bool thinned = c.density_scale && L.time_cell_s > 0;
    for (int k = 0; k < count; ++k) {
        const auto r0 = rng.uniforms(kx, ky, kt, 2u * k);
        const double x = (static_cast<double>(cx) + r0[0]) * L.cell_x;
        const double y = (static_cast<double>(cy) + r0[1]) * L.cell_y;
        // Birth region (Lewis 1986 §3.1, points "restricted to an area of the plane"): keep the
        // birth iff its own uniform u in (0, 1] is <= p(x, y) at the birth position. Thinning a
        // Poisson process by p gives a Poisson process of intensity lambda p (p = 1 keeps all).
        if (c.region && region_rng.uniforms(kx, ky, kt, k)[0] > c.region->acceptance(x, y))
            continue;
        const auto r1 = rng.uniforms(kx, ky, kt, 2u * k + 1u);
        BirthTime b;
        if (L.time_cell_s > 0) b = {(static_cast<double>(kt) + r0[2]) * L.time_cell_s, loop_index};
        // A time-varying birth rate by thinning (Lewis & Shedler 1979): a birth at t_b of the
        // maximum-rate process is kept with probability density_scale(t_b), decided by a
        // uniform of its own identity, so any region and frame order keeps the same births.
        // The loop-reduced time makes a looped process thin alike in every period.
        if (thinned && r1[2] > c.density_scale(b.phase_s)) continue;
        out.x.push_back(x);
        out.y.push_back(y);
        out.birth_s.push_back(b.phase_s + static_cast<double>(b.loop_index) * c.loop_s);
        if (births) births->push_back(b);
        float a = 0.0f;
        switch (c.amplitude) {
            case Amplitude::Normal:  // Box–Muller; u in (0, 1] so the log is finite
                a = static_cast<float>(std::sqrt(-2.0 * std::log(r0[3])) *
                                       std::cos(2.0 * std::numbers::pi * r1[0]));
                break;
            case Amplitude::Uniform: a = static_cast<float>(2.0 * r0[3] - 1.0); break;
            case Amplitude::Sign: a = r0[3] < 0.5 ? -1.0f : 1.0f; break;
        }
        out.amplitude.push_back(a);
        out.theta0.push_back(static_cast<float>(2.0 * std::numbers::pi * r1[1]));
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
    double area = region.area();
    if (config.region) {  // births only where the region's support meets `region`
        if (const auto s = config.region->support())
            area = std::max(0.0, std::min(region.x1, s->x1) - std::max(region.x0, s->x0)) *
                   std::max(0.0, std::min(region.y1, s->y1) - std::max(region.y0, s->y0));
    }
    double n = config.intensity * area;
    if (config.lifetime_s > 0) n *= 1.75;
    return n;
}

}  // namespace impulse::sim
