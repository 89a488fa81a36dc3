// SPDX-License-Identifier: Apache-2.0
// The live impulses of a layer at any frame: births, integration from birth or from the
// previous frame with identical arithmetic, Jacobian compensation, orientation.

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <tuple>

#include "sim/sim.h"
#include "sim/detail/angle.h"
#include "sim/layout.h"
#include "sim/normal.h"
#include "numeric/rng.h"
#include "numeric/errors.h"

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
    void resize(size_t n) {
        x.resize(n), y.resize(n), lnj.resize(n), th.resize(n), step.resize(n), birth_step.resize(n);
        birth_frac.resize(n), stepped.resize(n), amp.resize(n), th0.resize(n);
    }
    /// Particles [from, from + n) of `o` to [to, to + n) here.
    void copy_range(const Particles& o, size_t from, size_t n, size_t to) {
        for (size_t k = 0; k < n; ++k) {
            const size_t i = from + k, j = to + k;
            x[j] = o.x[i], y[j] = o.y[i], lnj[j] = o.lnj[i], th[j] = o.th[i];
            step[j] = o.step[i], birth_step[j] = o.birth_step[i], birth_frac[j] = o.birth_frac[i];
            stepped[j] = o.stepped[i], amp[j] = o.amp[i], th0[j] = o.th0[i];
        }
    }
};


/// Scratch arrays for one chunk of the integrator. The div and curl arrays stay empty when
/// not wanted (the flow is then passed null for them and skips their work).
struct Scratch {
    std::vector<double> h, xt, yt, k[4][4];  // k[stage][x, y, div, curl]
    void resize(size_t n, bool div, bool curl) {
        h.resize(n), xt.resize(n), yt.resize(n);
        for (auto& s : k) {
            s[0].resize(n), s[1].resize(n);
            s[2].resize(div ? n : 0), s[3].resize(curl ? n : 0);
        }
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
    std::vector<size_t> block_source;        // impulses_at scratch
    /// Still fast path scratch: pieces of rows of cells and their cells' plans.
    struct Piece {
        int64_t cy, cx0, cx1;  // cells [cx0, cx1] of row cy
        size_t cell, start;    // first plan in `plans`, first impulse in the output
    };
    std::vector<Piece> pieces;
    std::vector<detail::StillCell> plans;
    tbb::enumerable_thread_specific<detail::DrawBatch> draws;  // per thread, kept across frames
    tbb::enumerable_thread_specific<detail::NormalBatch> normals;  // the same
    int64_t last_step = 0;
    bool valid = false;

    State(ProcessConfig c, std::shared_ptr<Flow> f, Timing t, double r)
        : config(std::move(c)), layout(config), flow(std::move(f)), timing(t), support_radius(r) {
        detail::tabulate_poisson(layout);
        substeps = config.substeps;
        dt = 1.0 / (timing.fps * static_cast<double>(substeps));
        if (config.loop_s > 0) loop_steps = std::llround(config.loop_s * timing.fps) * substeps;
    }

    /// The box a flow is prepared for (its caches cover it): the whole seeding cells that meet
    /// `birth` (every impulse of a cell is born and moved, also where the cell overhangs the
    /// birth region) grown by how far an impulse travels, `travel`. A point outside the caches
    /// costs a stencil of nodes computed on the fly (the same bits, ~100 times the time).
    Box flow_region(const Region& birth, double travel) const {
        const Box b = birth.bounds();
        const Box cells{std::floor(b.x0 / layout.cell_x) * layout.cell_x,
                        std::floor(b.y0 / layout.cell_y) * layout.cell_y,
                        (std::floor(b.x1 / layout.cell_x) + 1.0) * layout.cell_x,
                        (std::floor(b.y1 / layout.cell_y) + 1.0) * layout.cell_y};
        return cells.expanded(travel + 1.0);
    }

    /// Time argument of grid step s: wrapped into the loop so looped copies see the same flow.
    double time_of_step(int64_t s) const {
        if (loop_steps) s = detail::floor_mod(s, loop_steps);
        return static_cast<double>(s) * dt;
    }

    /// The times the steps up to `target` of the impulses alive then evaluate: from a lifetime
    /// and a step before to `target` (the whole loop when that span wraps round it).
    std::pair<double, double> time_span(int64_t target) const {
        const int64_t first =
            target - static_cast<int64_t>(std::ceil(config.lifetime_s / dt)) - 1;
        if (loop_steps && detail::floor_div(first, loop_steps) != detail::floor_div(target, loop_steps))
            return {0.0, static_cast<double>(loop_steps) * dt};
        return {time_of_step(first), time_of_step(target)};
    }

    /// Birth (grid step, fraction) from the reduced birth time; copies one loop apart differ
    /// by exactly loop_steps in the step and not at all in the fraction.
    std::pair<int64_t, double> birth_grid(const BirthTime& b) const {
        const double g = b.phase_s / dt;
        const double fl = std::floor(g);
        return {static_cast<int64_t>(fl) + b.loop_index * loop_steps, g - fl};
    }

    /// How far from the view's support a particle can start and still reach it within one
    /// lifetime T. A flow whose speed bound does not depend on the region gives v T. Where the
    /// bound S(rho) over the view grown by rho increases with rho (a source or a shear, linear
    /// in the distance), a particle rho away moves at most S(rho), so it reaches the view only
    /// if int_0^rho drho' / S(rho') <= T (Gronwall): the reach is the rho where that integral
    /// meets T, summed in steps with S at each step's far end (each step's time is then under
    /// the truth, and the reach over it). docs/design.md §3.
    double travel(const Box& view) const {
        if (!flow || config.lifetime_s <= 0) return 0.0;
        const double T = config.lifetime_s, R = support_radius;
        const double v = flow->max_speed(view.expanded(R + 1.0));
        double reach = v * T;
        if (flow->max_speed(view.expanded(R + 2.0 * reach + 1.0)) != v) {
            double time = 0.0, rho = 0.0;
            for (reach = -1.0; reach < 0.0 && rho <= config.max_travel;) {
                const double step = std::max(1.0, rho / 32.0);
                const double s = flow->max_speed(view.expanded(R + rho + step + 1.0));
                if (time + step / s >= T) reach = rho + (T - time) * s;
                time += step / s, rho += step;
            }
            if (reach < 0.0) reach = rho;
        }
        if (reach > config.max_travel) {
            std::ostringstream s;
            s << "flow speed bound " << v << " units/s over lifetime " << T
              << " s carries particles " << reach << " units, beyond max_travel = "
              << config.max_travel << " (raise max_travel or slow the flow)";
            throw ValueError(s.str());
        }
        return reach;
    }

    /// The birth region for `view`: the view plus the kernel support, each side extended
    /// upstream by how far the flow can carry a particle into the view within one lifetime. A
    /// particle born left of the support can only enter it moving right, and until it does it
    /// is in the strip left of the support: the left margin is T times the largest vx over that
    /// strip (and likewise for each side). The strips' bounds grow with the box where the flow
    /// grows with the distance (a source, a shear), so the box is their least fixed point,
    /// iterated from the support: a particle cannot leave it backwards in time through a side,
    /// since crossing the side's strip takes at least T (docs/design.md §3).
    Box birth_region(const Box& view) const {
        const double R = support_radius;
        const Box inner = view.expanded(R);
        if (!flow || config.lifetime_s <= 0) return inner;
        travel(view);  // refuses flows beyond max_travel
        const double T = config.lifetime_s;
        Box r = inner;
        for (int it = 0;; ++it) {
            const Box g = r.expanded(1.0);
            const double left = std::max(0.0, flow->velocity_bounds({g.x0, g.y0, inner.x0, g.y1})[1]);
            const double right = std::max(0.0, -flow->velocity_bounds({inner.x1, g.y0, g.x1, g.y1})[0]);
            const double below = std::max(0.0, flow->velocity_bounds({g.x0, g.y0, g.x1, inner.y0})[3]);
            const double above = std::max(0.0, -flow->velocity_bounds({g.x0, inner.y1, g.x1, g.y1})[2]);
            const Box next{view.x0 - R - left * T, view.y0 - R - below * T,
                           view.x1 + R + right * T, view.y1 + R + above * T};
            const double grown = std::max({r.x0 - next.x0, r.y0 - next.y0, next.x1 - r.x1,
                                           next.y1 - r.y1});
            if (it > 0 && grown <= 1e-3) {
                // A bound that settled at once (constant in the region) is exact; one that grew
                // with the box stops within its last steps' geometric tail: one unit covers it.
                return it == 1 ? next : next.expanded(1.0);
            }
            if (std::max({inner.x0 - next.x0, inner.y0 - next.y0, next.x1 - inner.x1,
                          next.y1 - inner.y1}) > config.max_travel || it >= 4096) {
                std::ostringstream s;
                s << "the flow's speed bounds grow with the region faster than a lifetime of "
                  << T << " s settles: the birth region reaches beyond max_travel = "
                  << config.max_travel << " (raise max_travel, slow the flow or shorten the lifetime)";
                throw ValueError(s.str());
            }
            r = next;
        }
    }

    /// Marks a block of the next frame that is generated rather than carried over.
    static constexpr size_t kGenerate = static_cast<size_t>(-1);
    double age_s(const Particles& P, size_t i, int64_t target) const;
    bool alive(const Particles& P, size_t i, int64_t target) const;
    void plan_blocks(const detail::CellCover& cover, int64_t ct0, int64_t ct1, bool reuse);
    void fill_blocks();
    void advance(int64_t target, int64_t alive_from);
    void blur(const Region& view, int64_t target, int64_t g_open, const Shutter& shutter,
              std::vector<Particles>& states, Impulses& out) const;
    std::vector<uint8_t> blur_levels(const Region& view, int64_t target, const Shutter& shutter,
                                     const std::vector<Particles>& states, int64_t g_open) const;
    std::vector<size_t> emit(const Region& view, int64_t target, Impulses& out) const;
    void orient(double t_s, const std::vector<size_t>& emitted, Impulses& out) const;
    void integrate(Particles& p, const std::vector<size_t>& order, int64_t target);
    void step(double t0, double t1, double tm, size_t n, Scratch& s, double* x, double* y,
              double* lj, double* th) const;
    /// ln J only matters with the compensation on, and stays exactly 0 in a divergence-free
    /// flow; theta integrates the vorticity only in OrientationMode::Vorticity (the other modes
    /// set it at birth or at the frame time). Skipping them changes no bit of x and y.
    bool want_div() const { return config.jacobian && !flow->divergence_free(); }
    bool want_curl() const { return config.orientation == OrientationMode::Vorticity; }
    void still_impulses(const detail::CellCover& cover, const Region& view, bool theta0,
                        Impulses& out);
    void field_orientation(double t_s, const std::vector<float>& th0, Impulses& out) const;
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
double LayerSimulator::flow_cache_bytes(const Region& view) const {
    const State& S = *m_state;
    if (!S.flow || S.config.lifetime_s <= 0 || view.empty()) return 0.0;
    // The region impulses_at prepares the flow for.
    return S.flow->cache_bytes(S.flow_region(birth_region(view), S.travel(view.bounds())));
}
double LayerSimulator::first_frame_steps(const Region& view) const {
    const State& S = *m_state;
    if (!S.flow || S.config.lifetime_s <= 0 || view.empty()) return 0.0;
    const double steps_per_s = 1.0 / S.dt;
    return expected_impulses(S.config, birth_region(view)) *
           (0.5 * S.config.lifetime_s + 1.0 / S.timing.fps) * steps_per_s;
}

Box LayerSimulator::birth_region(const Box& view) const {
    return m_state->birth_region(view);
}
Region LayerSimulator::birth_region(const Region& view) const {
    Region r;
    for (const Box& b : view.boxes)
        if (b.x1 >= b.x0 && b.y1 >= b.y0) r.boxes.push_back(m_state->birth_region(b));
    return r;
}

// One step of the layer's integrator (Heun's RK2 or classical RK4) for particles [0, n), each by
// its own s.h[j], from time t0 (stages at t1 = t0 + h and tm = t0 + h / 2), with ln J
// (d ln J / dt = div v) and theta (d theta / dt = w / 2) when wanted (design.md §1).
void LayerSimulator::State::step(double t0, double t1, double tm, size_t n, Scratch& s, double* x,
                                 double* y, double* lj, double* th) const {
    const bool div = want_div(), curl = want_curl();
    auto eval = [&](int stage, double t, const double* px, const double* py) {
        double* out[4];
        for (int q = 0; q < 4; ++q) {
            auto& v = s.k[stage][q];
            out[q] = v.empty() ? nullptr : v.data();
            if (out[q]) std::fill(out[q], out[q] + n, 0.0);
        }
        flow->add(t, n, px, py, out[0], out[1], out[2], out[3]);
    };
    eval(0, t0, x, y);
    if (config.integrator != Integrator::RK4) {  // Heun's RK2
        for (size_t j = 0; j < n; ++j) {
            s.xt[j] = x[j] + s.h[j] * s.k[0][0][j];
            s.yt[j] = y[j] + s.h[j] * s.k[0][1][j];
        }
        eval(1, t1, s.xt.data(), s.yt.data());
        for (size_t j = 0; j < n; ++j) {
            const double hh = 0.5 * s.h[j];
            x[j] += hh * (s.k[0][0][j] + s.k[1][0][j]);
            y[j] += hh * (s.k[0][1][j] + s.k[1][1][j]);
        }
        if (div)
            for (size_t j = 0; j < n; ++j) lj[j] += 0.5 * s.h[j] * (s.k[0][2][j] + s.k[1][2][j]);
        if (curl)
            for (size_t j = 0; j < n; ++j)
                th[j] += 0.5 * s.h[j] * 0.5 * (s.k[0][3][j] + s.k[1][3][j]);
        return;
    }
    for (int st = 1; st < 4; ++st) {  // classical RK4
        const double frac_h = st == 3 ? 1.0 : 0.5;
        for (size_t j = 0; j < n; ++j) {
            s.xt[j] = x[j] + frac_h * s.h[j] * s.k[st - 1][0][j];
            s.yt[j] = y[j] + frac_h * s.h[j] * s.k[st - 1][1][j];
        }
        eval(st, st == 3 ? t1 : tm, s.xt.data(), s.yt.data());
    }
    for (size_t j = 0; j < n; ++j) {
        const double h6 = s.h[j] / 6.0;
        auto comb = [&](int q) {
            return s.k[0][q][j] + 2.0 * s.k[1][q][j] + 2.0 * s.k[2][q][j] + s.k[3][q][j];
        };
        x[j] += h6 * comb(0);
        y[j] += h6 * comb(1);
        if (div) lj[j] += h6 * comb(2);
        if (curl) th[j] += h6 * 0.5 * comb(3);
    }
}

void LayerSimulator::State::integrate(Particles& p, const std::vector<size_t>& order,
                                      int64_t target) {
    // `order` lists the particles to advance sorted by their first step, so at any grid step
    // the particles already moving are a prefix of the chunk. Each particle's arithmetic is
    // the same whichever chunk, thread or frame it is advanced in.
    constexpr size_t kChunk = 256;  // small enough to balance two threads in random access
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
        s.resize(m, want_div(), want_curl());
        size_t active = 0;
        for (int64_t g = m ? first[0] : target; g < target; ++g) {
            while (active < m && first[active] <= g) ++active;
            // A particle's first step runs from its birth to the next grid point.
            for (size_t j = 0; j < active; ++j) {
                s.h[j] = stepped[j] ? dt : (1.0 - frac[j]) * dt;
                stepped[j] = 1;
            }
            const double t0 = time_of_step(g);
            step(t0, time_of_step(g + 1), t0 + 0.5 * dt, active, s, x.data(), y.data(), lj.data(),
                 th.data());
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

void LayerSimulator::State::still_impulses(const detail::CellCover& cover, const Region& view,
                                           bool theta0, Impulses& out) {
    // A still layer has nothing to carry between frames and nothing to integrate, so its kept
    // impulses go straight into `out`: each piece of a row of cells is counted (the plan notes
    // which candidates are kept), then written in place, in parallel. Pieces in canonical order
    // (rows, then cells) and candidates in order give the order of the general path.
    constexpr int64_t kPieceCells = 64;  // a few hundred impulses per piece at ~5 per cell
    pieces.clear();
    size_t n_cells = 0;
    for (int64_t cy = cover.cy0; cy <= cover.cy1; ++cy)
        for (const auto& [cx0, cx1] : cover.rows[size_t(cy - cover.cy0)])
            for (int64_t a = cx0; a <= cx1; a += kPieceCells) {
                const int64_t b = std::min(cx1, a + kPieceCells - 1);
                pieces.push_back({cy, a, b, n_cells, 0});
                n_cells += static_cast<size_t>(b - a + 1);
            }
    plans.resize(n_cells);
    const detail::BoxIndex keep(view.expanded(support_radius));
    tbb::parallel_for(size_t(0), pieces.size(), [&](size_t p) {
        Piece& q = pieces[p];
        q.start = detail::still_piece_plan(config, layout, keep, q.cy, q.cx0, q.cx1,
                                           &plans[q.cell], draws.local());
    });
    size_t total = 0;
    for (Piece& q : pieces) {
        const size_t n = q.start;
        q.start = total, total += n;
    }
    // Every element below `total` is written, so the old contents need no clearing. Growing a
    // vector zeroes it (and faults its pages in): for a new output that is tens of MB, so the
    // four arrays grow side by side.
    tbb::parallel_invoke([&] { out.x.resize(total); }, [&] { out.y.resize(total); },
                         [&] { out.weight.resize(total); }, [&] { out.theta.resize(total); });
    tbb::parallel_for(size_t(0), pieces.size(), [&](size_t p) {
        const Piece& q = pieces[p];
        detail::still_piece_write(config, layout, keep, q.cy, q.cx0, q.cx1, &plans[q.cell], theta0,
                                  draws.local(), normals.local(), out, q.start);
    });
}

void LayerSimulator::State::field_orientation(double t_s, const std::vector<float>& th0,
                                              Impulses& out) const {
    // theta(x, t) at the particle's current position at the frame time (loop-wrapped like the
    // flow, so a looped layer repeats), plus the per-particle jitter from th0, its birth angle
    // (`th0` is only read when the jitter is not 0).
    config.orientation_field->angles(t_s, out.size(), out.x.data(), out.y.data(),
                                     out.theta.data());
    const double jitter = config.orientation_jitter.value(t_s);
    if (jitter != 0.0) {
        constexpr double kInvPi = 1.0 / 3.14159265358979323846;
        for (size_t j = 0; j < out.size(); ++j)
            out.theta[j] = detail::theta_of(out.theta[j] + jitter * (th0[j] * kInvPi - 1.0));
    }
}

// Age in grid steps (exact integer part) so looped copies agree bit for bit.
double LayerSimulator::State::age_s(const Particles& P, size_t i, int64_t target) const {
    return (static_cast<double>(target - P.birth_step[i]) - P.birth_frac[i]) * dt;
}

bool LayerSimulator::State::alive(const Particles& P, size_t i, int64_t target) const {
    const double a = age_s(P, i, target);
    return a >= 0.0 && a < config.lifetime_s;
}

// The blocks of the birth region in canonical order (time cells [ct0, ct1]), each carried over
// from the previous frame (block_source: its index in `blocks`) or to be generated (kGenerate).
// Both block lists are in canonical order: merge instead of search.
void LayerSimulator::State::plan_blocks(const detail::CellCover& cover, int64_t ct0, int64_t ct1,
                                        bool reuse) {
    size_t cursor = 0;
    next_blocks.clear();
    block_source.clear();
    for (int64_t ct = ct0; ct <= ct1; ++ct)
        for (int64_t cy = cover.cy0; cy <= cover.cy1; ++cy)
            for (const auto& [cx0, cx1] : cover.rows[size_t(cy - cover.cy0)])
                for (int64_t cx = cx0; cx <= cx1; ++cx) {
                    const BlockKey key{ct, cy, cx};
                    while (reuse && cursor < blocks.size() && blocks[cursor].key < key) ++cursor;
                    const bool kept = reuse && cursor < blocks.size() && blocks[cursor].key == key;
                    next_blocks.push_back({key, 0, kept ? blocks[cursor].count : 0});
                    block_source.push_back(kept ? cursor : kGenerate);
                }
}

// New cells are counted, then generated straight into their place in `next`, in parallel (an
// impulse is a pure function of its cell and index): the layout is the canonical order whatever
// the threads do.
void LayerSimulator::State::fill_blocks() {
    const ProcessConfig& c = config;
    const Layout& L = layout;
    const size_t n_blocks = next_blocks.size();
    constexpr size_t kGrain = 64;  // blocks per task: cells hold a few impulses each
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_blocks, kGrain), [&](const auto& r) {
        for (size_t b = r.begin(); b != r.end(); ++b) {
            if (block_source[b] != kGenerate) continue;
            const BlockKey& k = next_blocks[b].key;
            next_blocks[b].count = static_cast<size_t>(detail::cell_count(c, L, k.cx, k.cy, k.ct));
        }
    });
    size_t total = 0;
    for (Block& blk : next_blocks) blk.start = total, total += blk.count;
    Particles& P = next;
    P.resize(total);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_blocks, kGrain), [&](const auto& r) {
        for (size_t b = r.begin(); b != r.end(); ++b) {
            const Block& blk = next_blocks[b];
            if (block_source[b] != kGenerate) {
                P.copy_range(live, blocks[block_source[b]].start, blk.count, blk.start);
                continue;
            }
            // The block's survivors of the thinning (all its candidates when nothing thins),
            // in candidate order.
            detail::CellBirth nb;
            size_t i = blk.start;
            for (int k = 0; i < blk.start + blk.count; ++k) {
                if (!detail::cell_birth(c, L, blk.key.cx, blk.key.cy, blk.key.ct, k, nb)) continue;
                const auto [bs, bf] = birth_grid(nb.time);
                P.x[i] = nb.x;
                P.y[i] = nb.y;
                P.lnj[i] = 0.0;
                P.th[i] = c.orientation == OrientationMode::Random ? nb.theta0 : 0.0;
                P.birth_step[i] = bs;
                P.birth_frac[i] = bf;
                P.step[i] = bs;
                P.stepped[i] = 0;
                P.amp[i] = nb.amplitude;
                P.th0[i] = nb.theta0;
                ++i;
            }
        }
    });
}

// The particles of `next` behind `target` alive at it (or at `alive_from`: the motion blur's
// walk also moves those that die between the two steps), ordered by the step they start from (then by
// index): a counting sort, as those steps span about one lifetime. The order only groups
// particles that move together; it changes no particle's arithmetic.
void LayerSimulator::State::advance(int64_t target, int64_t alive_from) {
    Particles& P = next;
    std::vector<size_t> todo;
    int64_t lowest = target;
    auto first_of = [&](size_t i) { return P.stepped[i] ? P.step[i] : P.birth_step[i]; };
    for (size_t i = 0; i < P.size(); ++i) {
        if (!alive(P, i, target) && !(alive_from < target && alive(P, i, alive_from))) continue;
        const int64_t first = first_of(i);
        if (first < target) todo.push_back(i), lowest = std::min(lowest, first);
    }
    std::vector<size_t> starts(static_cast<size_t>(target - lowest) + 1, 0);
    for (size_t i : todo) ++starts[static_cast<size_t>(first_of(i) - lowest) + 1];
    for (size_t k = 1; k < starts.size(); ++k) starts[k] += starts[k - 1];
    std::vector<size_t> order(todo.size());
    for (size_t i : todo) order[starts[static_cast<size_t>(first_of(i) - lowest)]++] = i;
    integrate(P, order, target);
}

// Emits the live impulses of `next` whose support can touch the view, in canonical order, with
// their weights a w(age) sqrt(J); returns their indices in `next`.
std::vector<size_t> LayerSimulator::State::emit(const Region& view, int64_t target,
                                                Impulses& out) const {
    const ProcessConfig& c = config;
    const Particles& P = next;
    out.clear();
    const detail::BoxIndex keep(view.expanded(support_radius));
    std::vector<size_t> emitted;
    for (size_t i = 0; i < P.size(); ++i) {
        if (!alive(P, i, target)) continue;
        if (!keep.contains(P.x[i], P.y[i])) continue;
        double w = P.amp[i];
        w *= envelope_weight(c.envelope, age_s(P, i, target), c.lifetime_s);
        if (c.jacobian) w *= std::exp(0.5 * P.lnj[i]);  // s_k = sqrt(J_k)
        out.x.push_back(P.x[i]);
        out.y.push_back(P.y[i]);
        out.weight.push_back(static_cast<float>(w));
        out.theta.push_back(detail::theta_of(P.th[i]));
        emitted.push_back(i);
    }
    return emitted;
}

// Kernel angles that depend on where the impulses are now: along the local flow, or from an
// orientation field (with the birth angles of `emitted` for its jitter).
void LayerSimulator::State::orient(double t_s, const std::vector<size_t>& emitted,
                                   Impulses& out) const {
    const ProcessConfig& c = config;
    if (c.orientation == OrientationMode::Flow && flow) {
        const size_t n = out.size();
        std::vector<double> vx(n, 0.0), vy(n, 0.0);
        flow->add(t_s, n, out.x.data(), out.y.data(), vx.data(), vy.data(), nullptr, nullptr);
        for (size_t j = 0; j < n; ++j) out.theta[j] = static_cast<float>(std::atan2(vy[j], vx[j]));
    }
    if (c.orientation == OrientationMode::Field && c.orientation_field) {
        // Birth angles only for the jitter (field_orientation reads them only then).
        std::vector<float> th0;
        if (c.orientation_jitter.value(t_s) != 0.0) {
            th0.resize(emitted.size());
            for (size_t j = 0; j < emitted.size(); ++j) th0[j] = next.th0[emitted[j]];
        }
        field_orientation(t_s, th0, out);
    }
}

void LayerSimulator::impulses_at(int64_t frame, const Region& view, Impulses& out) {
    impulses_at(frame, view, Shutter{}, out);
}

void LayerSimulator::impulses_at(int64_t frame, const Region& view, const Shutter& shutter,
                                 Impulses& out) {
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
    const double travel = S.travel(view.bounds());
    // The birth region follows the view's boxes (a perspective view's wedge, say): only the
    // cells that meet one of them are generated.
    const Region region = birth_region(view);
    if (S.flow && !still) {
        S.flow->prepare(S.flow_region(region, travel));
        const auto [t0, t1] = S.time_span(target);
        S.flow->prepare_span(t0, t1);
    }
    const detail::CellCover cover = detail::cell_cover(region, L);
    if (still) {
        // out.theta holds theta0 for a random orientation, and for the field's jitter until
        // field_orientation overwrites it (kept aside first). A still layer neither moves nor
        // fades: a shutter changes nothing.
        const bool field = c.orientation == OrientationMode::Field && c.orientation_field;
        const bool jitter = field && c.orientation_jitter.value(S.time_of_step(target)) != 0.0;
        S.still_impulses(cover, view, c.orientation == OrientationMode::Random || jitter, out);
        if (field) {
            const std::vector<float> th0 = jitter ? out.theta : std::vector<float>{};
            S.field_orientation(S.time_of_step(target), th0, out);
        }
        S.valid = false;
        return;
    }
    // A shutter [t + open_s, t + close_s] is walked on the global grid from the step at or
    // before its opening to the one at or before its closing; without one both are the frame.
    const bool blur = shutter.open();
    auto steps_before = [&](double offset_s) {
        return target + static_cast<int64_t>(std::floor(offset_s / S.dt));
    };
    const int64_t g_open = blur ? steps_before(shutter.open_s) : target;
    const int64_t g_close = blur ? steps_before(shutter.close_s) : target;
    // Reuse the previous frame's particles only when moving forward in time.
    const bool reuse = S.valid && S.last_step <= g_open;
    const double t_frame = static_cast<double>(target) * S.dt;
    const double t_first = t_frame + std::min(0.0, blur ? shutter.open_s : 0.0);
    const double t_last = t_frame + std::max(0.0, blur ? shutter.close_s : 0.0);
    const int64_t ct0 =
        static_cast<int64_t>(std::floor((t_first - c.lifetime_s) / L.time_cell_s)) - 1;
    const int64_t ct1 = static_cast<int64_t>(std::floor(t_last / L.time_cell_s)) + 1;
    S.plan_blocks(cover, ct0, ct1, reuse);
    S.fill_blocks();
    if (!blur) {
        if (S.flow) S.advance(target, target);
        S.orient(S.time_of_step(target), S.emit(view, target, out), out);
    } else {
        // The particles' states at every grid step of the shutter (the last one is kept).
        std::vector<Particles> states;
        for (int64_t g = g_open; g <= g_close; ++g) {
            if (S.flow) S.advance(g, g == g_open ? g : g - 1);
            states.push_back(S.next);
        }
        S.blur(view, target, g_open, shutter, states, out);
    }

    std::swap(S.live, S.next);
    std::swap(S.blocks, S.next_blocks);
    S.last_step = g_close;
    S.valid = true;
}

// Each particle's number of sub-steps over the shutter, as a power of two 2^level: its travel
// over the shutter against shutter.max_step (docs/motion_blur.md). The travel is its chord
// between the first and last grid states of the walk, scaled to the shutter's length; with one
// grid state (a shutter within one grid step) or a particle born during the walk, its speed at
// that state times the shutter's length. 255 marks a particle the view cannot see.
std::vector<uint8_t> LayerSimulator::State::blur_levels(const Region& view, int64_t target,
                                                        const Shutter& shutter,
                                                        const std::vector<Particles>& states,
                                                        int64_t g_open) const {
    const double length = shutter.close_s - shutter.open_s;
    const Particles& A = states.front();
    const Particles& B = states.back();
    const int64_t g_close = g_open + int64_t(states.size()) - 1;
    const size_t n = A.size();
    auto at_grid = [](const Particles& P, size_t i, int64_t g) {
        return P.stepped[i] && P.step[i] == g;
    };
    std::vector<size_t> need;  // particles whose speed is taken from the flow
    for (size_t i = 0; i < n; ++i)
        if (g_close == g_open || !at_grid(A, i, g_open) || !at_grid(B, i, g_close)) need.push_back(i);
    std::vector<double> px(need.size()), py(need.size()), vx(need.size(), 0.0), vy(need.size(), 0.0);
    for (size_t q = 0; q < need.size(); ++q) px[q] = A.x[need[q]], py[q] = A.y[need[q]];
    if (flow && !need.empty())
        flow->add(time_of_step(g_open), need.size(), px.data(), py.data(), vx.data(), vy.data(),
                  nullptr, nullptr);
    std::vector<double> travel(n, 0.0);
    const double span = static_cast<double>(g_close - g_open) * dt;
    for (size_t i = 0; i < n; ++i)
        if (g_close > g_open) travel[i] = std::hypot(B.x[i] - A.x[i], B.y[i] - A.y[i]) * length / span;
    for (size_t q = 0; q < need.size(); ++q) travel[need[q]] = std::hypot(vx[q], vy[q]) * length;
    const double reach = (flow ? flow->max_speed(view.bounds().expanded(support_radius)) : 0.0) *
                         (length + dt);
    const detail::BoxIndex near(view.expanded(support_radius + reach + 1.0));
    const int max_level = std::max(0, std::ilogb(std::max(1, shutter.max_samples)));
    std::vector<uint8_t> level(n, 255);
    for (size_t i = 0; i < n; ++i) {
        const double age = age_s(A, i, target);  // at the frame time
        if (age + shutter.close_s < 0.0 || age + shutter.open_s >= config.lifetime_s) continue;
        if (!near.contains(A.x[i], A.y[i])) continue;
        int l = 0;
        while (l < max_level && travel[i] > shutter.max_step * double(int64_t(1) << l)) ++l;
        level[i] = static_cast<uint8_t>(l);
    }
    return level;
}

// Motion blur (docs/motion_blur.md): particle i becomes n_i = 2^level copies at the centres of
// n_i equal strata of the shutter, each weighted 1 / n_i with its own envelope, sqrt(J) and
// angle there. A copy's state is one partial step of the layer's integrator from the grid state
// at or before its time (`states`, from g_open): a pure function of the particle, so frames stay
// identical for any order, thread count or frame range. Copies are in canonical order
// (particles in order, each one's in time order); those whose support misses the view dropped.
void LayerSimulator::State::blur(const Region& view, int64_t target, int64_t g_open,
                                 const Shutter& shutter, std::vector<Particles>& states,
                                 Impulses& out) const {
    const ProcessConfig& c = config;
    const Particles& P = states.back();  // birth data and amplitudes are the same in every state
    const std::vector<uint8_t> level = blur_levels(view, target, shutter, states, g_open);
    const double length = shutter.close_s - shutter.open_s;
    auto offset = [&](int l, int64_t j) {  // sub-time j of 2^l, seconds from the frame time
        return shutter.open_s + (static_cast<double>(j) + 0.5) * length / double(int64_t(1) << l);
    };
    // Slots in canonical order; `members[key]` the (particle, slot) pairs of sub-time key
    // 2^l - 1 + j, whose copies share a time and a grid state.
    const int max_level = std::max(0, std::ilogb(std::max(1, shutter.max_samples)));
    std::vector<std::vector<std::pair<size_t, size_t>>> members(size_t(2) << max_level);
    size_t slots = 0;
    for (size_t i = 0; i < P.size(); ++i) {
        if (level[i] == 255) continue;
        const int l = level[i];
        const double age = age_s(P, i, target);
        for (int64_t j = 0; j < (int64_t(1) << l); ++j) {
            const double a = age + offset(l, j);
            if (a < 0.0 || a >= c.lifetime_s) continue;
            members[size_t((int64_t(1) << l) - 1 + j)].push_back({i, slots++});
        }
    }
    Impulses all;
    all.x.resize(slots), all.y.resize(slots), all.weight.resize(slots), all.theta.resize(slots);
    constexpr size_t kChunk = 256;
    struct Task {
        int l;
        int64_t j;
        size_t from, to;
    };
    std::vector<Task> tasks;
    for (int l = 0; l <= max_level; ++l)
        for (int64_t j = 0; j < (int64_t(1) << l); ++j) {
            const size_t m = members[size_t((int64_t(1) << l) - 1 + j)].size();
            for (size_t a = 0; a < m; a += kChunk) tasks.push_back({l, j, a, std::min(m, a + kChunk)});
        }
    tbb::parallel_for(size_t(0), tasks.size(), [&](size_t k) {
        const Task& T = tasks[k];
        const auto& mem = members[size_t((int64_t(1) << T.l) - 1 + T.j)];
        const double off = offset(T.l, T.j);
        const int64_t whole = static_cast<int64_t>(std::floor(off / dt));
        const int64_t g = target + whole;
        const double u = off - static_cast<double>(whole) * dt;  // from grid step g, in [0, dt)
        const Particles& G =
            states[size_t(std::clamp<int64_t>(g - g_open, 0, int64_t(states.size()) - 1))];
        const size_t m = T.to - T.from;
        std::vector<double> x(m), y(m), lj(m), th(m);
        std::vector<size_t> who(m);
        Scratch s;
        s.resize(m, flow && want_div(), flow && want_curl());
        for (size_t q = 0; q < m; ++q) {
            const size_t i = mem[T.from + q].first;
            who[q] = i;
            x[q] = G.x[i], y[q] = G.y[i], lj[q] = G.lnj[i], th[q] = G.th[i];
            // From the grid state, or from the birth for a particle born after step g.
            s.h[q] = G.stepped[i] && G.step[i] == g ? u : age_s(G, i, g) + u;
        }
        const double t0 = time_of_step(g);
        // A copy on a grid point from its grid state needs no step (a centred shutter's single
        // copies: the frame's own state).
        const bool moves = std::any_of(s.h.begin(), s.h.begin() + m, [](double h) { return h != 0.0; });
        if (flow && moves)
            step(t0, t0 + u, t0 + 0.5 * u, m, s, x.data(), y.data(), lj.data(), th.data());
        Impulses batch;
        batch.x = x, batch.y = y;
        batch.weight.resize(m), batch.theta.resize(m);
        for (size_t q = 0; q < m; ++q) {
            const size_t i = who[q];
            double w = P.amp[i] / double(int64_t(1) << T.l);
            w *= envelope_weight(c.envelope, age_s(P, i, g) + u, c.lifetime_s);
            if (c.jacobian) w *= std::exp(0.5 * lj[q]);  // s_k = sqrt(J_k)
            batch.weight[q] = static_cast<float>(w);
            batch.theta[q] = detail::theta_of(th[q]);
        }
        orient(t0 + u, who, batch);
        for (size_t q = 0; q < m; ++q) {
            const size_t slot = mem[T.from + q].second;
            all.x[slot] = batch.x[q], all.y[slot] = batch.y[q];
            all.weight[slot] = batch.weight[q], all.theta[slot] = batch.theta[q];
        }
    });
    out.clear();
    const detail::BoxIndex keep(view.expanded(support_radius));
    for (size_t k = 0; k < slots; ++k) {
        if (!keep.contains(all.x[k], all.y[k])) continue;
        out.x.push_back(all.x[k]), out.y.push_back(all.y[k]);
        out.weight.push_back(all.weight[k]), out.theta.push_back(all.theta[k]);
    }
}

}  // namespace impulse::sim
