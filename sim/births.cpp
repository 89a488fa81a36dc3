// SPDX-License-Identifier: Apache-2.0
// Cell-seeded Poisson births (Lewis 1986 §3.1 "numbered cells", here in space and time).

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "sim/sim.h"
#include "sim/layout.h"
#include "sim/normal.h"
#include "numeric/errors.h"
#include "numeric/rng.h"

namespace impulse::sim {
namespace detail {

namespace {

/// poisson_inverse's walk of the CDF: calls next(cdf) for k = 0, 1, ... until next returns
/// false or k reaches the cap (which guards against rounding leaving the CDF just below u).
template <typename Next>
int walk_poisson_cdf(double mean, Next&& next) {
    double p = std::exp(-mean), cdf = p;
    int k = 0;
    const int cap = static_cast<int>(mean + 40.0 * std::sqrt(mean) + 40.0);
    while (next(cdf) && k < cap) {
        ++k;
        p *= mean / k;
        cdf += p;
    }
    return k;
}

}  // namespace

int poisson_inverse(double mean, double u) {
    // Walk the CDF from k = 0; terminates because u <= 1 and the CDF reaches 1 - eps.
    return walk_poisson_cdf(mean, [u](double cdf) { return u > cdf; });
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

namespace {

/// Large means are split into independent Poisson parts (the sum of Poissons is Poisson) so the
/// inversion stays accurate (exp(-mean) does not underflow); part p draws counter index
/// kCountIndex - p.
int poisson_parts(const Layout& L) {
    const double parts = std::ceil(L.mean_per_cell / 200.0);
    // A count drawn as more parts than an int holds (4.3e11 impulses expected per cell) is
    // beyond every budget; it is refused here, at construction (tabulate_poisson), where the
    // conversion would otherwise be undefined (fuzzing found a density of 1.6e80).
    if (!(parts <= double(std::numeric_limits<int>::max()))) {
        std::ostringstream s;
        s << "a seeding cell expects " << L.mean_per_cell << " impulses, over the "
          << 200.0 * std::numeric_limits<int>::max() << " the Poisson sampler draws (lower the density)";
        throw BudgetError(s.str());
    }
    return std::max(static_cast<int>(parts), 1);
}
constexpr uint32_t kCountIndex = 0xFFFFFFFFu;

/// One part's count from its uniform u: poisson_inverse, or the same walk over the tabulated
/// sums (the same comparisons, the same count).
int poisson_part(const Layout& L, double u) {
    const std::vector<double>& cdf = L.poisson_cdf;
    if (cdf.empty()) return poisson_inverse(L.mean_per_cell / poisson_parts(L), u);
    int k = 0;
    while (k < static_cast<int>(cdf.size()) && u > cdf[size_t(k)]) ++k;
    return k;
}

}  // namespace

int cell_candidates(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct) {
    const CellKey key = cell_key(L, cx, cy, ct);
    const CounterRng rng(c.seed, c.layer);
    int count = 0;
    for (int p = 0; p < poisson_parts(L); ++p)
        count += poisson_part(
            L, rng.uniforms(key.kx, key.ky, key.kt, kCountIndex - static_cast<uint32_t>(p))[0]);
    return count;
}

void tabulate_poisson(Layout& L) {
    L.poisson_cdf.clear();
    // The walk stops at the cap, so the table holds the sums below it.
    walk_poisson_cdf(L.mean_per_cell / poisson_parts(L), [&](double cdf) {
        L.poisson_cdf.push_back(cdf);
        return true;
    });
    L.poisson_cdf.pop_back();
}

bool thins(const ProcessConfig& c, const Layout& L) {
    return c.region || (c.density_scale && L.time_cell_s > 0);
}

bool outside_region(const Layout& L, int64_t cx, int64_t cy) {
    // Birth-region culling: a seeding cell outside the region's support would have every birth
    // thinned away (p = 0 there), so it is not generated at all. The test has a margin of a
    // millionth of a cell for rounding in the positions; empty (inverted) supports meet nothing.
    const std::optional<Box>& support = L.region_support;
    if (!support) return false;
    const double m = 1e-6 * std::max(L.cell_x, L.cell_y);
    const double x0 = static_cast<double>(cx) * L.cell_x - m, x1 = (cx + 1.0) * L.cell_x + m;
    const double y0 = static_cast<double>(cy) * L.cell_y - m, y1 = (cy + 1.0) * L.cell_y + m;
    return std::max(x0, support->x0) > std::min(x1, support->x1) ||
           std::max(y0, support->y0) > std::min(y1, support->y1);
}

int cell_count(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct) {
    if (outside_region(L, cx, cy)) return 0;
    const int candidates = cell_candidates(c, L, cx, cy, ct);
    if (!thins(c, L)) return candidates;
    int count = 0;
    CellBirth b;
    for (int k = 0; k < candidates; ++k) count += cell_birth(c, L, cx, cy, ct, k, b);
    return count;
}

namespace {

/// Whether the birth region keeps candidate k born at (x, y) (Lewis 1986 §3.1, points
/// "restricted to an area of the plane"): iff its own uniform u in (0, 1] is <= p(x, y) at the
/// birth position. Thinning a Poisson process by p gives a Poisson process of intensity lambda p
/// (p = 1 keeps all). The uniform comes from a stream of its own, so a region changes no other
/// draw.
bool region_keeps(const ProcessConfig& c, const CellKey& key, int k, double x, double y) {
    if (!c.region) return true;
    const CounterRng region_rng(c.seed, c.layer ^ kRegionStream);
    return !(region_rng.uniforms(key.kx, key.ky, key.kt, k)[0] > c.region->acceptance(x, y));
}

/// The amplitude from its uniform u (r0[3]) and, for the normal, the angle's uniform v (r1[0]).
float amplitude_of(Amplitude a, double u, double v) {
    switch (a) {
        case Amplitude::Normal:  // Box–Muller; u in (0, 1] so the log is finite
            return static_cast<float>(normal_from_uniforms(u, v));
        case Amplitude::Uniform: return static_cast<float>(2.0 * u - 1.0);
        case Amplitude::Sign: return u < 0.5 ? -1.0f : 1.0f;
        case Amplitude::Exponential:  // inversion: -ln u, u in (0, 1] so finite and >= 0
            return static_cast<float>(-std::log(u));
    }
    return 0.0f;
}

float theta0_of(double u) { return static_cast<float>(2.0 * std::numbers::pi * u); }

}  // namespace

bool cell_birth(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct, int k,
                CellBirth& b) {
    const CellKey key = cell_key(L, cx, cy, ct);
    const CounterRng rng(c.seed, c.layer);
    // Uniforms of candidate k: r0 = (x, y, birth time, amplitude), r1 = (normal amplitude's
    // angle, theta0, density thinning, unused).
    const auto r0 = rng.uniforms(key.kx, key.ky, key.kt, 2u * k);
    b.x = (static_cast<double>(cx) + r0[0]) * L.cell_x;
    b.y = (static_cast<double>(cy) + r0[1]) * L.cell_y;
    if (!region_keeps(c, key, k, b.x, b.y)) return false;
    const auto r1 = rng.uniforms(key.kx, key.ky, key.kt, 2u * k + 1u);
    b.time = {};
    if (L.time_cell_s > 0) b.time = {(static_cast<double>(key.kt) + r0[2]) * L.time_cell_s, key.loop_index};
    // A time-varying birth rate by thinning (Lewis & Shedler 1979): a birth at t_b of the
    // maximum-rate process is kept with probability density_scale(t_b), decided by a uniform of
    // its own identity, so any region and frame order keeps the same births. The loop-reduced
    // time makes a looped process thin alike in every period.
    if (c.density_scale && L.time_cell_s > 0 && r1[2] > c.density_scale(b.time.phase_s)) return false;
    b.amplitude = amplitude_of(c.amplitude, r0[3], r1[0]);
    b.theta0 = theta0_of(r1[1]);
    return true;
}

size_t still_piece_plan(const ProcessConfig& c, const Layout& L, const BoxIndex& keep, int64_t cy,
                        int64_t cx0, int64_t cx1, StillCell* plans, DrawBatch& draws) {
    const CounterRng rng(c.seed, c.layer);
    const int parts = poisson_parts(L);
    // The counts' draws of all cells, then the first draws (x, y) of the candidates to test.
    draws.clear();
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        if (outside_region(L, cx, cy)) continue;
        const CellKey key = cell_key(L, cx, cy, 0);
        for (int p = 0; p < parts; ++p)
            draws.add(key.kx, key.ky, key.kt, kCountIndex - static_cast<uint32_t>(p));
    }
    draws.run(rng);
    size_t d = 0, kept = 0;
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        StillCell& s = plans[cx - cx0];
        s = {};
        if (outside_region(L, cx, cy)) continue;
        for (int p = 0; p < parts; ++p) s.candidates += poisson_part(L, draws.u01(d++, 0));
        // A position is (cx + u) * cell with u in (0, 1]: rounding is monotone, so it lies in
        // the cell's box computed the same way, and a cell inside one kept box keeps all.
        const bool inside = keep.contains_box(
            static_cast<double>(cx) * L.cell_x, static_cast<double>(cy) * L.cell_y,
            (cx + 1.0) * L.cell_x, (cy + 1.0) * L.cell_y);
        if (inside && !c.region)
            kept += static_cast<size_t>(s.candidates);
        else
            s.kept = s.candidates <= 64 ? StillCell::Mask : StillCell::Test;
    }
    draws.clear();
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        const StillCell& s = plans[cx - cx0];
        if (s.kept == StillCell::All) continue;
        const CellKey key = cell_key(L, cx, cy, 0);
        for (int k = 0; k < s.candidates; ++k) draws.add(key.kx, key.ky, key.kt, 2u * k);
    }
    draws.run(rng);
    d = 0;
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        StillCell& s = plans[cx - cx0];
        if (s.kept == StillCell::All) continue;
        const CellKey key = cell_key(L, cx, cy, 0);
        for (int k = 0; k < s.candidates; ++k, ++d) {
            const double x = (static_cast<double>(cx) + draws.u01(d, 0)) * L.cell_x;
            const double y = (static_cast<double>(cy) + draws.u01(d, 1)) * L.cell_y;
            if (!region_keeps(c, key, k, x, y) || !keep.contains(x, y)) continue;
            ++kept;
            if (s.kept == StillCell::Mask) s.mask |= uint64_t(1) << k;
        }
    }
    return kept;
}

size_t still_piece_write(const ProcessConfig& c, const Layout& L, const BoxIndex& keep, int64_t cy,
                         int64_t cx0, int64_t cx1, const StillCell* plans, bool theta0,
                         DrawBatch& draws, NormalBatch& normals, Impulses& out, size_t i) {
    const CounterRng rng(c.seed, c.layer);
    // r1 holds the normal amplitude's angle and theta0; a still layer uses nothing else of it.
    const bool want_r1 = theta0 || c.amplitude == Amplitude::Normal;
    auto skipped = [](const StillCell& s, int k) {
        return s.kept == StillCell::Mask && !((s.mask >> k) & 1u);
    };
    // All the draws of the piece first (r0 and r1 of candidate k are counters 2k and 2k + 1),
    // then the arithmetic, in the same order.
    draws.clear();
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        const StillCell& s = plans[cx - cx0];
        const CellKey key = cell_key(L, cx, cy, 0);
        for (int k = 0; k < s.candidates; ++k) {
            if (skipped(s, k)) continue;
            draws.add(key.kx, key.ky, key.kt, 2u * k);
            if (want_r1) draws.add(key.kx, key.ky, key.kt, 2u * k + 1u);
        }
    }
    draws.run(rng);
    // Normal amplitudes are computed together at the end (NormalBatch: AVX2 lanes), the same
    // bits as amplitude_of's.
    const bool normal = c.amplitude == Amplitude::Normal;
    const size_t first = i;
    normals.clear();
    size_t d = 0;
    for (int64_t cx = cx0; cx <= cx1; ++cx) {
        const StillCell& s = plans[cx - cx0];
        const CellKey key = cell_key(L, cx, cy, 0);
        for (int k = 0; k < s.candidates; ++k) {
            if (skipped(s, k)) continue;
            const size_t r0 = d, r1 = d + 1;
            d += want_r1 ? 2 : 1;
            const double x = (static_cast<double>(cx) + draws.u01(r0, 0)) * L.cell_x;
            const double y = (static_cast<double>(cy) + draws.u01(r0, 1)) * L.cell_y;
            if (s.kept == StillCell::Test && !(region_keeps(c, key, k, x, y) && keep.contains(x, y)))
                continue;
            out.x[i] = x;
            out.y[i] = y;
            if (normal)
                normals.add(draws.u01(r0, 3), draws.u01(r1, 0));
            else
                out.weight[i] = amplitude_of(c.amplitude, draws.u01(r0, 3), 0.0);
            out.theta[i] = theta0 ? theta0_of(draws.u01(r1, 1)) : 0.0f;
            ++i;
        }
    }
    if (normal) normals.run(out.weight.data() + first);
    return i;
}

void generate_cell(const ProcessConfig& c, const Layout& L, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out, std::vector<BirthTime>* births) {
    out.x.clear();
    out.y.clear();
    out.birth_s.clear();
    out.amplitude.clear();
    out.theta0.clear();
    if (births) births->clear();
    const int candidates = outside_region(L, cx, cy) ? 0 : cell_candidates(c, L, cx, cy, ct);
    CellBirth b;
    for (int k = 0; k < candidates; ++k) {
        if (!cell_birth(c, L, cx, cy, ct, k, b)) continue;
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

double expected_impulses(const ProcessConfig& config, const Region& region) {
    // Live impulses in the region, plus the not-yet-dead part of the time cells kept around
    // them (the simulator holds about (T + 3 dt_cell) / T of the live count).
    double area = 0.0;
    const std::optional<Box> s = config.region ? config.region->support() : std::nullopt;
    for (const Box& b : region.boxes) {
        if (!(b.x1 >= b.x0 && b.y1 >= b.y0)) continue;
        if (s)  // births only where the birth region's support meets the box
            area += std::max(0.0, std::min(b.x1, s->x1) - std::max(b.x0, s->x0)) *
                    std::max(0.0, std::min(b.y1, s->y1) - std::max(b.y0, s->y0));
        else
            area += b.area();
    }
    double n = config.intensity * area;
    if (config.lifetime_s > 0) n *= 1.75;
    return n;
}

}  // namespace impulse::sim
