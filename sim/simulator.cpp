// SPDX-License-Identifier: Apache-2.0
// The live impulses of a layer at any frame: births, integration from birth or from the
// previous frame with identical arithmetic, Jacobian compensation, orientation.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "sim/layout.h"
#include "util/errors.h"

namespace impulse::sim {
namespace {

using detail::BirthTime;
using detail::Layout;

struct BlockKey {
    int64_t ct, cy, cx;
    auto operator<=>(const BlockKey&) const = default;
};

/// A seeding cell's particles in the live set: [start, start + count).
struct Block {
    BlockKey key;
    size_t start, count;
};

/// Particle state, structure of arrays. `step` is the grid step at which (x, y, lnj, th) hold
/// when `stepped`; otherwise they hold at the birth time.
struct Particles {
    std::vector<double> x, y, lnj, th;
    std::vector<int64_t> step, birth_step;
    std::vector<double> birth_frac;
    std::vector<uint8_t> stepped;
    std::vector<float> amp;
    std::vector<float> th0;  // random angle drawn at birth, in [0, 2 pi) (orientation jitter)

    size_t size() const { return x.size(); }
    void clear() {
        x.clear(), y.clear(), lnj.clear(), th.clear(), step.clear(), birth_step.clear();
        birth_frac.clear(), stepped.clear(), amp.clear(), th0.clear();
    }
    void copy_from(const Particles& o, size_t i) {
        x.push_back(o.x[i]), y.push_back(o.y[i]), lnj.push_back(o.lnj[i]), th.push_back(o.th[i]);
        step.push_back(o.step[i]), birth_step.push_back(o.birth_step[i]);
        birth_frac.push_back(o.birth_frac[i]), stepped.push_back(o.stepped[i]);
        amp.push_back(o.amp[i]);
        th0.push_back(o.th0[i]);
    }
};

/// Scratch arrays for one chunk of the integrator.
struct Scratch {
    std::vector<double> h, xt, yt, k[4][4];  // k[stage][x, y, div, curl]
    void resize(size_t n) {
        h.resize(n), xt.resize(n), yt.resize(n);
        for (auto& s : k)
            for (auto& v : s) v.resize(n);
    }
};

}  // namespace

struct LayerSimulator::State {
    ProcessConfig config;
    Layout layout;
    std::shared_ptr<Flow> flow;
    Timing timing;
    double support_radius;
    double dt = 0;             // grid step, seconds
    int64_t loop_steps = 0;    // grid steps per loop
    int64_t substeps = 1;

    Particles live, next;
    std::vector<Block> blocks, next_blocks;  // sorted by key (canonical order)
    int64_t last_step = 0;
    bool valid = false;
    CellImpulses cell;
    std::vector<BirthTime> births;

    State(ProcessConfig c, std::shared_ptr<Flow> f, Timing t, double r)
        : config(std::move(c)), layout(config), flow(std::move(f)), timing(t), support_radius(r) {
        substeps = config.substeps;
        dt = 1.0 / (timing.fps * static_cast<double>(substeps));
        if (config.loop_s > 0) loop_steps = std::llround(config.loop_s * timing.fps) * substeps;
    }

    /// Time argument of grid step s: wrapped into the loop so looped copies see the same flow.
    double time_of_step(int64_t s) const {
        if (loop_steps) s = detail::floor_mod(s, loop_steps);
        return static_cast<double>(s) * dt;
    }

    /// Birth (grid step, fraction) from the reduced birth time; copies one loop apart differ
    /// by exactly loop_steps in the step and not at all in the fraction.
    std::pair<int64_t, double> birth_grid(const BirthTime& b) const {
        const double g = b.phase_s / dt;
        const double fl = std::floor(g);
        return {static_cast<int64_t>(fl) + b.loop_index * loop_steps, g - fl};
    }

    double travel(const Box& view) const {
        if (!flow || config.lifetime_s <= 0) return 0.0;
        double t = 0.0;
        for (int it = 0; it < 4; ++it) {
            const double v = flow->max_speed(view.expanded(support_radius + 2.0 * t + 1.0));
            t = v * config.lifetime_s;
            if (t > config.max_travel) {
                std::ostringstream s;
                s << "flow speed bound " << v << " units/s over lifetime " << config.lifetime_s
                  << " s carries particles " << t << " units, beyond max_travel = "
                  << config.max_travel << " (raise max_travel or slow the flow)";
                throw ValueError(s.str());
            }
        }
        return t;
    }

    /// The birth region for `view`: the view plus the kernel support, extended upstream by
    /// how far the flow can carry a particle into the view within one lifetime (a particle born
    /// left of the view can only enter moving right, so the left margin is max(vx) T, etc.).
    Box birth_region(const Box& view) const {
        const double R = support_radius;
        Box r = view.expanded(R);
        if (!flow || config.lifetime_s <= 0) return r;
        travel(view);  // refuses flows beyond max_travel
        const double T = config.lifetime_s;
        for (int it = 0; it < 4; ++it) {
            const auto b = flow->velocity_bounds(r.expanded(1.0));
            r = {view.x0 - R - std::max(0.0, b[1]) * T, view.y0 - R - std::max(0.0, b[3]) * T,
                 view.x1 + R + std::max(0.0, -b[0]) * T, view.y1 + R + std::max(0.0, -b[2]) * T};
        }
        return r;
    }

    void integrate(Particles& p, const std::vector<size_t>& order, int64_t target);
    /// The impulses of a still process for `view` (see still_impulses in the .cpp).
    void still_impulses(const Region& view, int64_t target, Impulses& out);
    /// OrientationMode::Field: the field's angle at each impulse plus its jitter (from th0).
    void orient_by_field(int64_t target, const std::vector<float>& th0, Impulses& out) const;

    /// One row of cells of a still process (buffers reused between frames).
    struct StillRow {
        std::vector<double> x, y;
        std::vector<float> weight, theta, th0;
        void clear() { x.clear(), y.clear(), weight.clear(), theta.clear(), th0.clear(); }
    };
    std::vector<StillRow> still_rows;
};

LayerSimulator::LayerSimulator(ProcessConfig config, std::shared_ptr<Flow> flow, Timing timing,
                               double support_radius)
    : m_state(std::make_unique<State>(std::move(config), std::move(flow), timing,
                                      support_radius)) {}
LayerSimulator::~LayerSimulator() = default;
LayerSimulator::LayerSimulator(LayerSimulator&&) noexcept = default;

const ProcessConfig& LayerSimulator::config() const { return m_state->config; }
void LayerSimulator::reset() { m_state->valid = false; }
double LayerSimulator::travel_bound(const Box& view) const { return m_state->travel(view); }
Box LayerSimulator::birth_region(const Box& view) const {
    return m_state->birth_region(view);
}
Region LayerSimulator::birth_region(const Region& view) const {
    Region r;
    for (const Box& b : view.boxes)
        if (b.x1 >= b.x0 && b.y1 >= b.y0) r.boxes.push_back(m_state->birth_region(b));
    return r;
}

void LayerSimulator::State::integrate(Particles& p, const std::vector<size_t>& order,
                                      int64_t target) {
    // `order` lists the particles to advance sorted by their first step, so at any grid step
    // the particles already moving are a prefix of the chunk. Each particle's arithmetic is
    // the same whichever chunk, thread or frame it is advanced in.
    constexpr size_t kChunk = 512;
    const size_t n = order.size();
    const size_t chunks = (n + kChunk - 1) / kChunk;
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        const size_t i0 = c * kChunk, i1 = std::min(n, i0 + kChunk), m = i1 - i0;
        std::vector<double> x(m), y(m), lj(m), th(m), frac(m);
        std::vector<int64_t> first(m);
        std::vector<uint8_t> stepped(m);
        for (size_t j = 0; j < m; ++j) {
            const size_t i = order[i0 + j];
            x[j] = p.x[i], y[j] = p.y[i], lj[j] = p.lnj[i], th[j] = p.th[i];
            stepped[j] = p.stepped[i];
            first[j] = stepped[j] ? p.step[i] : p.birth_step[i];
            frac[j] = p.birth_frac[i];
        }
        Scratch s;
        s.resize(m);
        size_t active = 0;
        const bool rk4 = config.integrator == Integrator::RK4;
        auto eval = [&](int stage, double t, size_t na, const double* px, const double* py) {
            for (auto& v : s.k[stage]) std::fill(v.begin(), v.begin() + na, 0.0);
            flow->add(t, na, px, py, s.k[stage][0].data(), s.k[stage][1].data(),
                      s.k[stage][2].data(), s.k[stage][3].data());
        };
        for (int64_t g = m ? first[0] : target; g < target; ++g) {
            while (active < m && first[active] <= g) ++active;
            // A particle's first step runs from its birth to the next grid point.
            for (size_t j = 0; j < active; ++j) {
                s.h[j] = stepped[j] ? dt : (1.0 - frac[j]) * dt;
                stepped[j] = 1;
            }
            const double t0 = time_of_step(g), t1 = time_of_step(g + 1);
            const double tm = t0 + 0.5 * dt;
            eval(0, t0, active, x.data(), y.data());
            if (!rk4) {  // Heun's RK2
                for (size_t j = 0; j < active; ++j) {
                    s.xt[j] = x[j] + s.h[j] * s.k[0][0][j];
                    s.yt[j] = y[j] + s.h[j] * s.k[0][1][j];
                }
                eval(1, t1, active, s.xt.data(), s.yt.data());
                for (size_t j = 0; j < active; ++j) {
                    const double hh = 0.5 * s.h[j];
                    x[j] += hh * (s.k[0][0][j] + s.k[1][0][j]);
                    y[j] += hh * (s.k[0][1][j] + s.k[1][1][j]);
                    lj[j] += hh * (s.k[0][2][j] + s.k[1][2][j]);  // d ln J / dt = div v
                    th[j] += hh * 0.5 * (s.k[0][3][j] + s.k[1][3][j]);  // d theta / dt = w / 2
                }
            } else {  // classical RK4
                for (int st = 1; st < 4; ++st) {
                    const double frac_h = st == 3 ? 1.0 : 0.5;
                    for (size_t j = 0; j < active; ++j) {
                        s.xt[j] = x[j] + frac_h * s.h[j] * s.k[st - 1][0][j];
                        s.yt[j] = y[j] + frac_h * s.h[j] * s.k[st - 1][1][j];
                    }
                    eval(st, st == 3 ? t1 : tm, active, s.xt.data(), s.yt.data());
                }
                for (size_t j = 0; j < active; ++j) {
                    const double h6 = s.h[j] / 6.0;
                    auto comb = [&](int q) {
                        return s.k[0][q][j] + 2.0 * s.k[1][q][j] + 2.0 * s.k[2][q][j] + s.k[3][q][j];
                    };
                    x[j] += h6 * comb(0);
                    y[j] += h6 * comb(1);
                    lj[j] += h6 * comb(2);
                    th[j] += h6 * 0.5 * comb(3);
                }
            }
        }
        for (size_t j = 0; j < m; ++j) {
            const size_t i = order[i0 + j];
            p.x[i] = x[j], p.y[i] = y[j], p.lnj[i] = lj[j], p.th[i] = th[j];
            if (first[j] < target) {
                p.stepped[i] = 1;
                p.step[i] = target;
            }
        }
    });
}

void LayerSimulator::impulses_at(int64_t frame, const Region& view, Impulses& out) {
    State& S = *m_state;
    const ProcessConfig& c = S.config;
    const Layout& L = S.layout;
    const bool still = c.lifetime_s <= 0;
    const int64_t target = (S.timing.start_frame + frame) * S.substeps;
    if (view.empty()) {
        out.clear();
        S.valid = false;
        return;
    }
    if (still) return S.still_impulses(view, target, out);
    const double travel = S.travel(view.bounds());
    const Region region = birth_region(view);
    if (S.flow) S.flow->prepare(region.bounds().expanded(travel + 1.0));

    // Reuse the previous frame's particles only when moving forward in time.
    const bool reuse = S.valid && S.last_step <= target;
    size_t cursor = 0;  // both block lists are in canonical order: merge instead of search
    const detail::CellCover cover = detail::cell_cover(region, L);
    const double t_frame = static_cast<double>(target) * S.dt;
    const int64_t ct0 =
        static_cast<int64_t>(std::floor((t_frame - c.lifetime_s) / L.time_cell_s)) - 1;
    const int64_t ct1 = static_cast<int64_t>(std::floor(t_frame / L.time_cell_s)) + 1;

    Particles& P = S.next;
    P.clear();
    S.next_blocks.clear();
    for (int64_t ct = ct0; ct <= ct1; ++ct)
        for (int64_t cy = cover.cy0; cy <= cover.cy1; ++cy)
            for (const auto& [cx0, cx1] : cover.rows[size_t(cy - cover.cy0)])
                for (int64_t cx = cx0; cx <= cx1; ++cx) {
                    const BlockKey key{ct, cy, cx};
                    const size_t start = P.size();
                    while (reuse && cursor < S.blocks.size() && S.blocks[cursor].key < key)
                        ++cursor;
                    if (reuse && cursor < S.blocks.size() && S.blocks[cursor].key == key) {
                        const Block& b = S.blocks[cursor];
                        for (size_t i = b.start; i < b.start + b.count; ++i) P.copy_from(S.live, i);
                    } else {
                        detail::generate_cell(c, L, cx, cy, ct, S.cell, &S.births);
                        for (size_t k = 0; k < S.cell.x.size(); ++k) {
                            P.x.push_back(S.cell.x[k]);
                            P.y.push_back(S.cell.y[k]);
                            P.lnj.push_back(0.0);
                            P.th.push_back(
                                c.orientation == OrientationMode::Random ? S.cell.theta0[k] : 0.0);
                            const auto [bs, bf] = S.birth_grid(S.births[k]);
                            P.birth_step.push_back(bs);
                            P.birth_frac.push_back(bf);
                            P.step.push_back(bs);
                            P.stepped.push_back(0);
                            P.amp.push_back(S.cell.amplitude[k]);
                            P.th0.push_back(S.cell.theta0[k]);
                        }
                    }
                    S.next_blocks.push_back({key, start, P.size() - start});
                }

    // Age in grid steps (exact integer part) so looped copies agree bit for bit.
    auto age_s = [&](size_t i) {
        return (static_cast<double>(target - P.birth_step[i]) - P.birth_frac[i]) * S.dt;
    };
    auto alive = [&](size_t i) {
        const double a = age_s(i);
        return a >= 0.0 && a < c.lifetime_s;
    };

    if (S.flow) {
        std::vector<std::pair<int64_t, size_t>> todo;
        for (size_t i = 0; i < P.size(); ++i) {
            if (!alive(i)) continue;
            const int64_t first = P.stepped[i] ? P.step[i] : P.birth_step[i];
            if (first < target) todo.emplace_back(first, i);
        }
        std::sort(todo.begin(), todo.end());
        std::vector<size_t> order(todo.size());
        for (size_t j = 0; j < todo.size(); ++j) order[j] = todo[j].second;
        S.integrate(P, order, target);
    }

    // Emit the live impulses whose support can touch the view, in canonical order.
    out.clear();
    const detail::BoxIndex keep(view.expanded(S.support_radius));
    std::vector<float> th0;
    for (size_t i = 0; i < P.size(); ++i) {
        if (!alive(i)) continue;
        if (!keep.contains(P.x[i], P.y[i])) continue;
        double w = P.amp[i] * envelope_weight(c.envelope, age_s(i), c.lifetime_s);
        if (c.jacobian) w *= std::exp(0.5 * P.lnj[i]);  // s_k = sqrt(J_k)
        out.x.push_back(P.x[i]);
        out.y.push_back(P.y[i]);
        out.weight.push_back(static_cast<float>(w));
        out.theta.push_back(static_cast<float>(P.th[i]));
        th0.push_back(P.th0[i]);
    }
    if (c.orientation == OrientationMode::Flow && S.flow) {
        // Kernels aligned with the local flow direction at the frame time.
        const size_t n = out.size();
        std::vector<double> vx(n, 0.0), vy(n, 0.0), dv(n, 0.0), cu(n, 0.0);
        S.flow->add(S.time_of_step(target), n, out.x.data(), out.y.data(), vx.data(), vy.data(),
                    dv.data(), cu.data());
        for (size_t j = 0; j < n; ++j)
            out.theta[j] = static_cast<float>(std::atan2(vy[j], vx[j]));
    }
    S.orient_by_field(target, th0, out);

    std::swap(S.live, S.next);
    std::swap(S.blocks, S.next_blocks);
    S.last_step = target;
    S.valid = true;
}

void LayerSimulator::State::orient_by_field(int64_t target, const std::vector<float>& th0,
                                            Impulses& out) const {
    if (config.orientation != OrientationMode::Field || !config.orientation_field) return;
    // theta(x, t) at the particle's current position at the frame time (loop-wrapped like the
    // flow, so a looped layer repeats), plus the per-particle jitter drawn at birth.
    config.orientation_field->angles(time_of_step(target), out.size(), out.x.data(), out.y.data(),
                                     out.theta.data());
    if (config.orientation_jitter != 0.0) {
        constexpr double kInvPi = 1.0 / 3.14159265358979323846;
        for (size_t j = 0; j < out.size(); ++j)
            out.theta[j] = static_cast<float>(out.theta[j] +
                                              config.orientation_jitter * (th0[j] * kInvPi - 1.0));
    }
}

void LayerSimulator::State::still_impulses(const Region& view, int64_t target, Impulses& out) {
    // A still process: no birth times, no motion, nothing kept between frames. Rows of cells
    // are generated in parallel into their own buffers and joined in row order, so the result
    // is the canonical order (cell row, cell, index) whatever the threads.
    valid = false;
    const ProcessConfig& c = config;
    const detail::CellCover cover = detail::cell_cover(view.expanded(support_radius), layout);
    const detail::BoxIndex keep(view.expanded(support_radius));
    const size_t nrows = cover.rows.size();
    if (still_rows.size() < nrows) still_rows.resize(nrows);
    const bool random = c.orientation == OrientationMode::Random;
    const bool field = c.orientation == OrientationMode::Field && c.orientation_field;
    const detail::CounterRng rng(c.seed, c.layer);
    tbb::parallel_for(size_t(0), nrows, [&](size_t r) {
        StillRow& row = still_rows[r];
        row.clear();
        const int64_t cy = cover.cy0 + static_cast<int64_t>(r);
        for (const auto& [cx0, cx1] : cover.rows[r])
            for (int64_t cx = cx0; cx <= cx1; ++cx) {
                const detail::CellKey key(layout, cx, cy, 0);
                const int count = detail::cell_count(rng, layout, key);
                for (int k = 0; k < count; ++k) {
                    const detail::ImpulseDraw d =
                        detail::draw_impulse(c, layout, rng, key, cx, cy, k);
                    if (!keep.contains(d.x, d.y)) continue;
                    row.x.push_back(d.x);
                    row.y.push_back(d.y);
                    row.weight.push_back(d.amplitude);
                    row.theta.push_back(random ? d.theta0 : 0.0f);
                    if (field) row.th0.push_back(d.theta0);
                }
            }
    });
    std::vector<size_t> start(nrows + 1, 0);
    for (size_t r = 0; r < nrows; ++r) start[r + 1] = start[r] + still_rows[r].x.size();
    const size_t n = start[nrows];
    out.x.resize(n), out.y.resize(n), out.weight.resize(n), out.theta.resize(n);
    std::vector<float> th0(field ? n : 0);
    tbb::parallel_for(size_t(0), nrows, [&](size_t r) {
        const StillRow& row = still_rows[r];
        std::copy(row.x.begin(), row.x.end(), out.x.begin() + ptrdiff_t(start[r]));
        std::copy(row.y.begin(), row.y.end(), out.y.begin() + ptrdiff_t(start[r]));
        std::copy(row.weight.begin(), row.weight.end(), out.weight.begin() + ptrdiff_t(start[r]));
        std::copy(row.theta.begin(), row.theta.end(), out.theta.begin() + ptrdiff_t(start[r]));
        if (field) std::copy(row.th0.begin(), row.th0.end(), th0.begin() + ptrdiff_t(start[r]));
    });
    orient_by_field(target, th0, out);
}

}  // namespace impulse::sim
