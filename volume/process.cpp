// SPDX-License-Identifier: Apache-2.0
// One 3-D process as a particle system: cell-seeded Poisson births in space and time (Lewis 1986
// §3.1 "numbered cells", design.md §3), Heun integration on a global time grid, ln J carried
// along the path (d ln J / dt = div v), weights a w(age) sqrt(J) (design.md §1), and the kernel
// axis each impulse carries (docs/volume.md "Orientation").

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>

#include "numeric/rng.h"
#include "sim/layout.h"
#include "sim/normal.h"
#include "volume/process.h"

namespace impulse::volume {
namespace {

struct CellKey {
    int64_t ct, cz, cy, cx;
    auto operator<=>(const CellKey&) const = default;
};

/// A seeding cell's particles in the flat arrays: [start, start + count).
struct Block {
    CellKey key;
    size_t start = 0, count = 0;
};

/// Particle state (structure of arrays). (x, y, z, lnj, u) hold at grid step `step` when
/// `stepped`, else at the birth time, which lies `frac` of a step after grid step `step`. u =
/// (ux, uy, uz) is the kernel axis R e_x (Random, Vorticity; empty for the other modes).
struct Particles {
    std::vector<double> x, y, z, lnj, frac, ux, uy, uz;
    std::vector<int64_t> step, birth_step;
    std::vector<uint8_t> stepped;
    std::vector<float> amp;
    bool axes = false;
    void resize(size_t n) {
        x.resize(n), y.resize(n), z.resize(n), lnj.resize(n), frac.resize(n), step.resize(n);
        birth_step.resize(n), stepped.resize(n), amp.resize(n);
        if (axes) ux.resize(n), uy.resize(n), uz.resize(n);
    }
    void copy(const Particles& o, size_t from, size_t n, size_t to) {
        for (size_t k = 0; k < n; ++k) {
            const size_t i = from + k, j = to + k;
            x[j] = o.x[i], y[j] = o.y[i], z[j] = o.z[i], lnj[j] = o.lnj[i], frac[j] = o.frac[i];
            step[j] = o.step[i], birth_step[j] = o.birth_step[i], stepped[j] = o.stepped[i];
            amp[j] = o.amp[i];
            if (axes) ux[j] = o.ux[i], uy[j] = o.uy[i], uz[j] = o.uz[i];
        }
    }
};

constexpr uint32_t kCountIndex = 0xFFFFFFFFu;

float amplitude_of(sim::Amplitude a, double u, double v) {
    switch (a) {
        case sim::Amplitude::Normal: return static_cast<float>(sim::detail::normal_from_uniforms(u, v));
        case sim::Amplitude::Uniform: return static_cast<float>(2.0 * u - 1.0);
        case sim::Amplitude::Sign: return u < 0.5 ? -1.0f : 1.0f;
        case sim::Amplitude::Exponential: return static_cast<float>(-std::log(u));  // refused by the loader
    }
    return 0.0f;
}

}  // namespace

struct Simulator3::State {
    Process3 p;
    std::shared_ptr<Flow3> flow;
    double radius;
    double dt, time_cell_s, mean_per_cell;
    Particles live, next;
    std::vector<Block> blocks, next_blocks;
    int64_t last_step = 0;
    bool valid = false;

    State(Process3 pr, std::shared_ptr<Flow3> f, double r)
        : p(pr), flow(std::move(f)), radius(r) {
        live.axes = next.axes = p.orientation == sim::OrientationMode::Random ||
                                p.orientation == sim::OrientationMode::Vorticity;
        dt = 1.0 / (p.fps * p.substeps);
        // Four time cells per lifetime (as the 2-D layout): births per unit volume per second
        // beta = lambda / T, so a space-time cell expects lambda s^3 (T/4) / T.
        time_cell_s = p.lifetime_s / 4.0;
        mean_per_cell = p.intensity * p.cell_size * p.cell_size * p.cell_size / 4.0;
    }

    numeric::CounterRng rng(int64_t ct) const {
        return numeric::CounterRng(p.seed, p.layer).keyed(ct);
    }
    int count(const CellKey& k) const {
        const auto u = rng(k.ct).uniforms(k.cx, k.cy, k.cz, kCountIndex)[0];
        return sim::detail::poisson_inverse(mean_per_cell, u);
    }
    void generate(const CellKey& k, Particles& P, size_t i, size_t n) const;
    double travel(const Box3& view) const;
    Box3 birth_region(const Box3& view) const {
        return view.expanded(radius + travel(view));
    }
    void integrate(Particles& P, const std::vector<size_t>& order, int64_t target) const;
    /// Fills `next` and `next_blocks` with the particles of `keys` (canonical order).
    void gather(const std::vector<CellKey>& keys, int64_t target);
    /// Age of particle i of `next` at grid step `target`, seconds (whole steps exact).
    double age_s(size_t i, int64_t target) const {
        return (double(target - next.birth_step[i]) - next.frac[i]) * dt;
    }
    /// The live particles of `next` that can touch `view`, weighted a w(age) sqrt(J).
    void emit(const std::vector<uint8_t>& alive, int64_t target, const Box3& view,
              Impulses3& out) const;
    /// OrientationMode::Flow: each impulse's axis along v at its position at time t_s.
    void flow_axes(double t_s, Impulses3& out) const;
};

void Simulator3::State::generate(const CellKey& k, Particles& P, size_t i, size_t n) const {
    const numeric::CounterRng r = rng(k.ct);
    const double s = p.cell_size;
    for (size_t q = 0; q < n; ++q, ++i) {
        // r0 = (x, y, z, birth time), r1 = (amplitude, normal's angle, axis z, axis azimuth).
        const auto r0 = r.uniforms(k.cx, k.cy, k.cz, 2u * uint32_t(q));
        const auto r1 = r.uniforms(k.cx, k.cy, k.cz, 2u * uint32_t(q) + 1u);
        P.x[i] = (double(k.cx) + r0[0]) * s;
        P.y[i] = (double(k.cy) + r0[1]) * s;
        P.z[i] = (double(k.cz) + r0[2]) * s;
        const double g = (double(k.ct) + r0[3]) * time_cell_s / dt;  // birth in grid steps
        const double fl = std::floor(g);
        P.birth_step[i] = P.step[i] = int64_t(fl);
        P.frac[i] = g - fl;
        P.stepped[i] = 0;
        P.lnj[i] = 0.0;
        P.amp[i] = amplitude_of(p.amplitude, r1[0], r1[1]);
        if (!P.axes) continue;
        if (p.orientation == sim::OrientationMode::Random) {
            // R e_x of a uniform rotation is uniform on the sphere (Archimedes: z uniform in
            // [-1, 1], azimuth uniform); the kernel is symmetric about its axis, so the axis is
            // all of R the field sees (docs/volume.md "Orientation").
            const double uz = 2.0 * r1[2] - 1.0, phi = 2.0 * std::numbers::pi * r1[3];
            const double rho = std::sqrt(std::max(0.0, 1.0 - uz * uz));
            P.ux[i] = rho * std::cos(phi), P.uy[i] = rho * std::sin(phi), P.uz[i] = uz;
        } else {  // Vorticity: the identity at birth
            P.ux[i] = 1.0, P.uy[i] = 0.0, P.uz[i] = 0.0;
        }
    }
}

double Simulator3::State::travel(const Box3& view) const {
    if (!flow) return 0.0;
    double t = 0.0;
    for (int it = 0; it < 4; ++it) t = flow->max_speed(view.expanded(radius + t)) * p.lifetime_s;
    return t;
}

void Simulator3::State::integrate(Particles& P, const std::vector<size_t>& order,
                                  int64_t target) const {
    // `order` is sorted by each particle's first step, so the particles moving at any step are a
    // prefix of a chunk; a particle's arithmetic does not depend on its chunk or thread.
    constexpr size_t kChunk = 256;
    const size_t n = order.size(), chunks = (n + kChunk - 1) / kChunk;
    const bool want_div = p.jacobian && !flow->divergence_free();
    const bool want_curl = p.orientation == sim::OrientationMode::Vorticity;
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        const size_t i0 = c * kChunk, m = std::min(n, i0 + kChunk) - i0;
        // k[0..2] velocity, k[3] divergence, k[4..6] curl (the vorticity orientation's omega)
        std::vector<double> x[2], h(m), lj(m), k0[7], k1[7], U, UT, a0;
        for (int a = 0; a < 3; ++a) x[0].resize(3 * m), x[1].resize(3 * m);
        for (auto* k : {k0, k1})
            for (int a = 0; a < (want_curl ? 7 : 4); ++a) k[a].resize(m);
        if (want_curl) U.resize(3 * m), UT.resize(3 * m), a0.resize(3 * m);
        std::vector<int64_t> first(m);
        std::vector<uint8_t> stepped(m);
        std::vector<double> frac(m);
        double* X = x[0].data();  // x, y, z blocks of m
        double* T = x[1].data();
        for (size_t j = 0; j < m; ++j) {
            const size_t i = order[i0 + j];
            X[j] = P.x[i], X[m + j] = P.y[i], X[2 * m + j] = P.z[i], lj[j] = P.lnj[i];
            stepped[j] = P.stepped[i], first[j] = P.step[i], frac[j] = P.frac[i];
            if (want_curl) U[j] = P.ux[i], U[m + j] = P.uy[i], U[2 * m + j] = P.uz[i];
        }
        auto eval = [&](double t, size_t na, const double* px, std::vector<double>* k) {
            const int outputs = want_curl ? 7 : 4;
            for (int a = 0; a < outputs; ++a) std::fill(k[a].begin(), k[a].begin() + na, 0.0);
            const CurlOut3 curl{k[4].data(), k[5].data(), k[6].data()};
            flow->add(t, na, px, px + m, px + 2 * m, k[0].data(), k[1].data(), k[2].data(),
                      want_div ? k[3].data() : nullptr, want_curl ? &curl : nullptr);
        };
        // du/dt = (omega / 2) x u: the first column of dR/dt = [omega/2]_x R (R's other columns
        // do not reach the field: the kernel is symmetric about its axis).
        auto spin = [&](const std::vector<double>* k, const double* u, size_t j, int a) {
            const double w[3] = {0.5 * k[4][j], 0.5 * k[5][j], 0.5 * k[6][j]};
            const double v[3] = {u[j], u[m + j], u[2 * m + j]};
            return w[(a + 1) % 3] * v[(a + 2) % 3] - w[(a + 2) % 3] * v[(a + 1) % 3];
        };
        size_t active = 0;
        for (int64_t g = m ? first[0] : target; g < target; ++g) {
            while (active < m && first[active] <= g) ++active;
            for (size_t j = 0; j < active; ++j) {  // the first step runs from the birth
                h[j] = stepped[j] ? dt : (1.0 - frac[j]) * dt;
                stepped[j] = 1;
            }
            const double t0 = double(g) * dt, t1 = double(g + 1) * dt;
            eval(t0, active, X, k0);  // Heun's RK2
            for (int a = 0; a < 3; ++a)
                for (size_t j = 0; j < active; ++j) T[a * m + j] = X[a * m + j] + h[j] * k0[a][j];
            eval(t1, active, T, k1);
            for (int a = 0; a < 3; ++a)
                for (size_t j = 0; j < active; ++j) X[a * m + j] += 0.5 * h[j] * (k0[a][j] + k1[a][j]);
            if (want_div)  // d ln J / dt = div v
                for (size_t j = 0; j < active; ++j) lj[j] += 0.5 * h[j] * (k0[3][j] + k1[3][j]);
            if (want_curl) {  // the same Heun step for the axis, omega where v was evaluated
                for (int a = 0; a < 3; ++a)
                    for (size_t j = 0; j < active; ++j) {
                        a0[a * m + j] = spin(k0, U.data(), j, a);
                        UT[a * m + j] = U[a * m + j] + h[j] * a0[a * m + j];
                    }
                for (int a = 0; a < 3; ++a)
                    for (size_t j = 0; j < active; ++j)
                        U[a * m + j] += 0.5 * h[j] * (a0[a * m + j] + spin(k1, UT.data(), j, a));
            }
        }
        for (size_t j = 0; j < m; ++j) {
            const size_t i = order[i0 + j];
            P.x[i] = X[j], P.y[i] = X[m + j], P.z[i] = X[2 * m + j], P.lnj[i] = lj[j];
            if (want_curl) P.ux[i] = U[j], P.uy[i] = U[m + j], P.uz[i] = U[2 * m + j];
            if (first[j] < target) P.stepped[i] = 1, P.step[i] = target;
        }
    });
}

Simulator3::Simulator3(Process3 process, std::shared_ptr<Flow3> flow, double support_radius)
    : m_state(std::make_unique<State>(process, std::move(flow), support_radius)) {}
Simulator3::~Simulator3() = default;
Simulator3::Simulator3(Simulator3&&) noexcept = default;
const Process3& Simulator3::process() const { return m_state->p; }
Box3 Simulator3::birth_region(const Box3& view) const { return m_state->birth_region(view); }

namespace {

/// The cells of `region` in canonical order (ct, cz, cy, cx).
std::vector<CellKey> cover(const Box3& r, double s, int64_t ct0, int64_t ct1) {
    auto lo = [s](double v) { return int64_t(std::floor(v / s)); };
    std::vector<CellKey> keys;
    for (int64_t ct = ct0; ct <= ct1; ++ct)
        for (int64_t cz = lo(r.z0); cz <= lo(r.z1); ++cz)
            for (int64_t cy = lo(r.y0); cy <= lo(r.y1); ++cy)
                for (int64_t cx = lo(r.x0); cx <= lo(r.x1); ++cx) keys.push_back({ct, cz, cy, cx});
    return keys;
}

/// The particles not yet at `target`, sorted by the step they start from (a counting sort).
std::vector<size_t> integration_order(const Particles& P, const std::vector<uint8_t>& alive,
                                      int64_t target) {
    std::vector<size_t> todo;
    int64_t lowest = target;
    for (size_t i = 0; i < P.x.size(); ++i)
        if (alive[i] && P.step[i] < target) todo.push_back(i), lowest = std::min(lowest, P.step[i]);
    std::vector<size_t> starts(size_t(target - lowest) + 1, 0), order(todo.size());
    for (size_t i : todo) ++starts[size_t(P.step[i] - lowest) + 1];
    for (size_t k = 1; k < starts.size(); ++k) starts[k] += starts[k - 1];
    for (size_t i : todo) order[starts[size_t(P.step[i] - lowest)]++] = i;
    return order;
}

}  // namespace

void Simulator3::State::gather(const std::vector<CellKey>& keys, int64_t target) {
    // Blocks carried over from the previous frame (moving forward in time) or generated; new
    // cells are counted, then generated straight into their place, in parallel (a particle is a
    // pure function of its cell and index): the layout is the canonical order for any threads.
    const bool reuse = valid && last_step <= target;
    constexpr size_t kNew = size_t(-1);
    std::vector<size_t> source(keys.size(), kNew);
    next_blocks.assign(keys.size(), {});
    size_t cursor = 0;
    for (size_t b = 0; b < keys.size(); ++b) {
        next_blocks[b].key = keys[b];
        while (reuse && cursor < blocks.size() && blocks[cursor].key < keys[b]) ++cursor;
        if (reuse && cursor < blocks.size() && blocks[cursor].key == keys[b])
            source[b] = cursor, next_blocks[b].count = blocks[cursor].count;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keys.size(), 256), [&](const auto& r) {
        for (size_t b = r.begin(); b != r.end(); ++b)
            if (source[b] == kNew) next_blocks[b].count = size_t(count(keys[b]));
    });
    size_t total = 0;
    for (Block& blk : next_blocks) blk.start = total, total += blk.count;
    next.resize(total);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keys.size(), 256), [&](const auto& r) {
        for (size_t b = r.begin(); b != r.end(); ++b) {
            const Block& blk = next_blocks[b];
            if (source[b] == kNew) generate(blk.key, next, blk.start, blk.count);
            else next.copy(live, blocks[source[b]].start, blk.count, blk.start);
        }
    });
}

void Simulator3::State::emit(const std::vector<uint8_t>& alive, int64_t target, const Box3& view,
                             Impulses3& out) const {
    const Particles& P = next;
    out.x.clear(), out.y.clear(), out.z.clear(), out.weight.clear(), out.age_s.clear();
    out.ax.clear(), out.ay.clear(), out.az.clear();
    const Box3 keep = view.expanded(radius);
    for (size_t i = 0; i < P.x.size(); ++i) {
        if (!alive[i]) continue;
        if (P.x[i] < keep.x0 || P.x[i] > keep.x1 || P.y[i] < keep.y0 || P.y[i] > keep.y1 ||
            P.z[i] < keep.z0 || P.z[i] > keep.z1)
            continue;
        const double age = age_s(i, target);
        double w = P.amp[i] * sim::envelope_weight(p.envelope, age, p.lifetime_s);
        if (p.jacobian) w *= std::exp(0.5 * P.lnj[i]);  // s_k = sqrt(J_k)
        out.x.push_back(P.x[i]);
        out.y.push_back(P.y[i]);
        out.z.push_back(P.z[i]);
        out.weight.push_back(float(w));
        out.age_s.push_back(age);
        if (P.axes) {  // Random, Vorticity: the carried axis (Heun keeps |u| = 1 to O(h^4))
            const double len = std::sqrt(P.ux[i] * P.ux[i] + P.uy[i] * P.uy[i] + P.uz[i] * P.uz[i]);
            out.ax.push_back(float(P.ux[i] / len));
            out.ay.push_back(float(P.uy[i] / len));
            out.az.push_back(float(P.uz[i] / len));
        }
    }
    if (p.orientation == sim::OrientationMode::Flow) flow_axes(double(target) * dt, out);
}

void Simulator3::State::flow_axes(double t_s, Impulses3& out) const {
    // Along v at the impulse at the frame time; where v = 0 (or with no flow) there is no
    // direction: the kernel keeps its own axis, x (docs/volume.md "Orientation").
    const size_t n = out.size();
    out.ax.assign(n, 1.0f), out.ay.assign(n, 0.0f), out.az.assign(n, 0.0f);
    if (!flow) return;
    constexpr size_t kChunk = 1024;
    tbb::parallel_for(size_t(0), (n + kChunk - 1) / kChunk, [&](size_t c) {
        const size_t i0 = c * kChunk, m = std::min(n, i0 + kChunk) - i0;
        std::vector<double> v[3];
        for (auto& a : v) a.assign(m, 0.0);
        flow->add(t_s, m, &out.x[i0], &out.y[i0], &out.z[i0], v[0].data(), v[1].data(),
                  v[2].data(), nullptr);
        for (size_t j = 0; j < m; ++j) {
            const double len = std::sqrt(v[0][j] * v[0][j] + v[1][j] * v[1][j] + v[2][j] * v[2][j]);
            if (!(len > 0.0)) continue;
            out.ax[i0 + j] = float(v[0][j] / len);
            out.ay[i0 + j] = float(v[1][j] / len);
            out.az[i0 + j] = float(v[2][j] / len);
        }
    });
}

void Simulator3::impulses_at(int64_t frame, const Box3& view, Impulses3& out) {
    State& S = *m_state;
    const int64_t target = frame * S.p.substeps;
    const Box3 region = S.birth_region(view);
    // Births up to one lifetime (and a time cell of margin) before the frame may be alive.
    const double t = double(target) * S.dt;
    if (S.flow) {
        S.flow->prepare(region.expanded(S.p.cell_size));
        S.flow->prepare_span(t - S.p.lifetime_s - S.dt, t);
    }
    const int64_t ct0 = int64_t(std::floor((t - S.p.lifetime_s) / S.time_cell_s)) - 1;
    const int64_t ct1 = int64_t(std::floor(t / S.time_cell_s)) + 1;
    S.gather(cover(region, S.p.cell_size, ct0, ct1), target);
    const size_t total = S.next.x.size();
    std::vector<uint8_t> alive(total);
    for (size_t i = 0; i < total; ++i) {
        const double a = S.age_s(i, target);
        alive[i] = a >= 0.0 && a < S.p.lifetime_s;
    }
    if (S.flow) S.integrate(S.next, integration_order(S.next, alive, target), target);
    S.emit(alive, target, view, out);
    std::swap(S.live, S.next);
    std::swap(S.blocks, S.next_blocks);
    S.last_step = target;
    S.valid = true;
}

}  // namespace impulse::volume
