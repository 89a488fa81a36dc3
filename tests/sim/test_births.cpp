// SPDX-License-Identifier: Apache-2.0
// Cell-seeded Poisson births (sim::cell_impulses): consistency whatever the order or thread,
// the Poisson law of the counts, amplitude and position distributions, periodic domains and
// loops, and independence of seeds and layers. Statistical checks use fixed seeds and bands of
// 5 standard errors derived next to each check.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <numbers>
#include <thread>
#include <vector>

#include "sim/sim.h"

namespace {

using impulse::sim::Amplitude;
using impulse::sim::CellImpulses;
using impulse::sim::ProcessConfig;

constexpr double kPi = std::numbers::pi;

/// Density 16 per kernel area of a radius-16 kernel, cells of 16: 16/pi = 5.09 per cell.
ProcessConfig still_config(uint64_t seed = 1234, uint32_t layer = 0) {
    ProcessConfig c;
    c.seed = seed;
    c.layer = layer;
    c.cell_size = 16.0;
    c.intensity = 16.0 / (kPi * 16.0 * 16.0);
    return c;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

bool same_bits(const CellImpulses& a, const CellImpulses& b) {
    return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.birth_s, b.birth_s) &&
           same_bits(a.amplitude, b.amplitude) && same_bits(a.theta0, b.theta0);
}

/// Cells (cx, cy, ct) of a block, in row-major order.
struct CellId {
    int64_t cx, cy, ct;
};
std::vector<CellId> block(int64_t x0, int64_t y0, int n, int64_t ct0, int nt) {
    std::vector<CellId> ids;
    for (int64_t t = ct0; t < ct0 + nt; ++t)
        for (int64_t y = y0; y < y0 + n; ++y)
            for (int64_t x = x0; x < x0 + n; ++x) ids.push_back({x, y, t});
    return ids;
}

/// Standard normal CDF.
double phi(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

/// Kolmogorov–Smirnov distance of a sample from a continuous CDF.
double ks(std::vector<double> v, const std::function<double(double)>& cdf) {
    std::sort(v.begin(), v.end());
    const double n = static_cast<double>(v.size());
    double d = 0.0;
    for (size_t i = 0; i < v.size(); ++i) {
        const double f = cdf(v[i]);
        d = std::max({d, std::abs(f - i / n), std::abs((i + 1) / n - f)});
    }
    return d;
}

// KS band: P(sqrt(n) D > x) ~ 2 exp(-2 x^2); x = 2.5 gives 7e-6, the tail of a 4.5-sd event.
constexpr double kKsX = 2.5;

}  // namespace

TEST_CASE("a cell's impulses do not depend on the order or thread that generates them",
          "[sim][determinism]") {
    for (const bool animated : {false, true}) {
        ProcessConfig c = still_config();
        if (animated) c.lifetime_s = 2.0, c.orientation = impulse::sim::OrientationMode::Random;
        CAPTURE(animated);
        const auto ids = block(-20, -7, 40, animated ? -2 : 0, animated ? 4 : 1);
        const size_t n = ids.size();

        std::vector<CellImpulses> forward(n), backward(n), threads(n), tbb_out(n);
        for (size_t i = 0; i < n; ++i)
            impulse::sim::cell_impulses(c, ids[i].cx, ids[i].cy, ids[i].ct, forward[i]);
        // Reverse order with one reused output buffer (stale contents must not leak).
        CellImpulses scratch;
        for (size_t i = n; i-- > 0;) {
            impulse::sim::cell_impulses(c, ids[i].cx, ids[i].cy, ids[i].ct, scratch);
            backward[i] = scratch;
        }
        // Four std::threads taking interleaved cells.
        std::vector<std::thread> pool;
        for (size_t t = 0; t < 4; ++t)
            pool.emplace_back([&, t] {
                for (size_t i = t; i < n; i += 4)
                    impulse::sim::cell_impulses(c, ids[i].cx, ids[i].cy, ids[i].ct, threads[i]);
            });
        for (auto& th : pool) th.join();
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            impulse::sim::cell_impulses(c, ids[i].cx, ids[i].cy, ids[i].ct, tbb_out[i]);
        });

        size_t total = 0, mismatches = 0;
        for (size_t i = 0; i < n; ++i) {
            total += forward[i].x.size();
            if (!same_bits(forward[i], backward[i]) || !same_bits(forward[i], threads[i]) ||
                !same_bits(forward[i], tbb_out[i]))
                ++mismatches;
        }
        CHECK(total > 1000);
        CHECK(mismatches == 0);
    }
}

TEST_CASE("counts per cell are Poisson with mean intensity * cell area", "[sim][stats]") {
    // For N independent Poisson(mu) counts: sd(sample mean) = sqrt(mu / N) and, with the
    // central fourth moment mu + 3 mu^2, sd(sample variance) ~ sqrt((mu + 2 mu^2) / N).
    // Bands are 5 sd. The dispersion check has teeth against any non-Poisson count law
    // (a fixed or binomial count would have variance 0 or mu (1 - p)).
    struct Case {
        const char* name;
        double mu;  // expected count per cell
        int side;   // side x side cells
        double lifetime_s;
    };
    // 450 per cell exercises the split into independent Poisson parts (mean / 200 parts).
    for (const Case k : {Case{"still, 16/pi per cell", 16.0 / kPi, 200, 0.0},
                         Case{"still, 450 per cell", 450.0, 45, 0.0},
                         Case{"animated, 4 time cells per lifetime", 16.0 / kPi, 100, 2.0}}) {
        CAPTURE(k.name);
        ProcessConfig c = still_config(99);
        c.intensity = k.mu / (c.cell_size * c.cell_size);
        c.lifetime_s = k.lifetime_s;
        // An animated process draws births per space-time cell of lifetime / 4 seconds at
        // beta = lambda / T: mean per cell is lambda C^2 / 4.
        const double mu = k.lifetime_s > 0 ? k.mu / 4.0 : k.mu;
        const int nt = k.lifetime_s > 0 ? 4 : 1;
        CellImpulses cell;
        double s1 = 0.0, s2 = 0.0;
        double n = 0.0;
        for (int t = 0; t < nt; ++t)
            for (int y = 0; y < k.side; ++y)
                for (int x = 0; x < k.side; ++x) {
                    impulse::sim::cell_impulses(c, x - k.side / 2, y, t, cell);
                    const double m = static_cast<double>(cell.x.size());
                    s1 += m, s2 += m * m, n += 1.0;
                    if (k.lifetime_s > 0)
                        for (double b : cell.birth_s) {
                            REQUIRE(b >= t * 0.5);
                            REQUIRE(b < (t + 1) * 0.5);
                        }
                }
        const double mean = s1 / n, var = s2 / n - mean * mean;
        const double sd_mean = std::sqrt(mu / n), sd_var = std::sqrt((mu + 2.0 * mu * mu) / n);
        CAPTURE(n, mu, mean, sd_mean, var, sd_var);
        CHECK(std::abs(mean - mu) < 5.0 * sd_mean);
        CHECK(std::abs(var - mu) < 5.0 * sd_var);
    }
}

TEST_CASE("amplitudes have the documented moments and laws", "[sim][stats]") {
    // n ~ 2e5 impulses. sd of a sample moment E[g(a)] is sqrt(Var g(a) / n):
    //   normal : Var a^2 = 3 - 1 = 2,      Var a^4 = 105 - 9 = 96
    //   uniform: Var a^2 = 1/5 - 1/9,      Var a^4 = 1/9 - 1/25
    //   sign   : a^2 = a^4 = 1 exactly.
    //   exponential (rate 1, E[a^n] = n!): Var a = 1, Var a^2 = 24 - 4, Var a^4 = 8! - 24^2.
    // Bands are 5 sd; the shape is checked with a KS band (see kKsX).
    struct Case {
        Amplitude a;
        double m2, m4, var2, var4;
    };
    for (const Case k : {Case{Amplitude::Normal, 1.0, 3.0, 2.0, 96.0},
                         Case{Amplitude::Uniform, 1.0 / 3.0, 0.2, 0.2 - 1.0 / 9.0, 1.0 / 9.0 - 1.0 / 25.0},
                         Case{Amplitude::Sign, 1.0, 1.0, 0.0, 0.0},
                         Case{Amplitude::Exponential, 2.0, 24.0, 20.0, 40320.0 - 576.0}}) {
        ProcessConfig c = still_config(7);
        c.amplitude = k.a;
        CAPTURE(static_cast<int>(k.a));
        REQUIRE(impulse::sim::amplitude_second_moment(k.a) == k.m2);
        REQUIRE(impulse::sim::amplitude_fourth_moment(k.a) == k.m4);
        std::vector<double> amps;
        CellImpulses cell;
        for (int y = 0; y < 200; ++y)
            for (int x = 0; x < 200; ++x) {
                impulse::sim::cell_impulses(c, x, y, 0, cell);
                amps.insert(amps.end(), cell.amplitude.begin(), cell.amplitude.end());
            }
        const double n = static_cast<double>(amps.size());
        double s1 = 0, s2 = 0, s4 = 0;
        for (double a : amps) s1 += a, s2 += a * a, s4 += a * a * a * a;
        const double m1 = s1 / n, m2 = s2 / n, m4 = s4 / n;
        CAPTURE(n, m1, m2, m4);
        const double mean = impulse::sim::amplitude_mean(k.a);
        CHECK(std::abs(m1 - mean) < 5.0 * std::sqrt((k.m2 - mean * mean) / n));
        CHECK(std::abs(m2 - k.m2) <= 5.0 * std::sqrt(k.var2 / n));
        CHECK(std::abs(m4 - k.m4) <= 5.0 * std::sqrt(k.var4 / n));
        if (k.a == Amplitude::Normal) {
            CHECK(ks(amps, phi) < kKsX / std::sqrt(n));
            // Teeth: the uniform law's second moment is far outside the normal band.
            CHECK(std::abs(m2 - 1.0 / 3.0) > 5.0 * std::sqrt(k.var2 / n));
        }
        if (k.a == Amplitude::Uniform) {
            CHECK(ks(amps, [](double a) { return std::clamp(0.5 * (a + 1.0), 0.0, 1.0); }) <
                  kKsX / std::sqrt(n));
            CHECK(std::abs(m2 - 1.0) > 5.0 * std::sqrt(k.var2 / n));
        }
        if (k.a == Amplitude::Sign) {
            CHECK(std::all_of(amps.begin(), amps.end(), [](double a) { return a == 1.0 || a == -1.0; }));
        }
        if (k.a == Amplitude::Exponential) {
            CHECK(ks(amps, [](double a) { return a > 0.0 ? 1.0 - std::exp(-a) : 0.0; }) <
                  kKsX / std::sqrt(n));
            // Teeth: a zero-mean law's mean is far outside the band.
            CHECK(std::abs(m1) > 5.0 * std::sqrt((k.m2 - mean * mean) / n));
        }
    }
}

TEST_CASE("impulses lie inside their cell, uniformly", "[sim][stats]") {
    // Fractional positions within the cell are U(0, 1): mean 1/2 with sd sqrt(1/12 / n), and
    // KS distance below kKsX / sqrt(n). Cells on both sides of 0 (floor vs truncation).
    for (const bool periodic : {false, true}) {
        // Periodic: 1910 x 1000 is 119 x 62 cells of 1910/119 x 1000/62 (not a multiple of 16);
        // the loops below cover exactly one period, so every cell is distinct.
        ProcessConfig c = still_config(5);
        if (periodic) c.period = std::array<double, 2>{1910.0, 1000.0};
        const double cw = periodic ? 1910.0 / 119.0 : c.cell_size;
        const double ch = periodic ? 1000.0 / 62.0 : c.cell_size;
        const int64_t nx = periodic ? 119 : 120, ny = periodic ? 62 : 120;
        CAPTURE(periodic);
        std::vector<double> fx, fy;
        CellImpulses cell;
        bool inside = true;
        for (int64_t cy = -ny / 2; cy < ny - ny / 2; ++cy)
            for (int64_t cx = -nx / 2; cx < nx - nx / 2; ++cx) {
                impulse::sim::cell_impulses(c, cx, cy, 0, cell);
                for (size_t k = 0; k < cell.x.size(); ++k) {
                    // Positions are (cx + u) * cell: exactly inside up to one rounding.
                    inside &= cell.x[k] >= cx * cw - 1e-12 * cw && cell.x[k] < (cx + 1) * cw;
                    inside &= cell.y[k] >= cy * ch - 1e-12 * ch && cell.y[k] < (cy + 1) * ch;
                    fx.push_back(cell.x[k] / cw - cx);
                    fy.push_back(cell.y[k] / ch - cy);
                }
            }
        CHECK(inside);
        const double n = static_cast<double>(fx.size());
        double mx = 0, my = 0;
        for (size_t i = 0; i < fx.size(); ++i) mx += fx[i], my += fy[i];
        mx /= n, my /= n;
        CAPTURE(n, mx, my);
        CHECK(std::abs(mx - 0.5) < 5.0 * std::sqrt(1.0 / 12.0 / n));
        CHECK(std::abs(my - 0.5) < 5.0 * std::sqrt(1.0 / 12.0 / n));
        auto unif = [](double u) { return std::clamp(u, 0.0, 1.0); };
        CHECK(ks(fx, unif) < kKsX / std::sqrt(n));
        CHECK(ks(fy, unif) < kKsX / std::sqrt(n));
    }
}

TEST_CASE("a periodic domain repeats its cells shifted by exactly the period", "[sim]") {
    struct Case {
        double px, py;
        int64_t cells_x, cells_y;  // period in cells: floor(period / cell_size)
    };
    // 256 x 192 is a whole number of 16-unit cells; 250 x 100 is not (cells stretch to 250/15,
    // 100/6).
    for (const Case k : {Case{256.0, 192.0, 16, 12}, Case{250.0, 100.0, 15, 6}}) {
        ProcessConfig c = still_config(42);
        c.period = std::array<double, 2>{k.px, k.py};
        CAPTURE(k.px, k.py);
        CellImpulses a, b;
        size_t compared = 0;
        bool ok = true;
        for (int64_t cy = -3; cy < 3; ++cy)
            for (int64_t cx = -3; cx < 3; ++cx)
                for (const auto& [mx, my] : {std::pair<int64_t, int64_t>{1, 0}, {0, 1}, {-2, 3}, {5, -1}}) {
                    impulse::sim::cell_impulses(c, cx, cy, 0, a);
                    impulse::sim::cell_impulses(c, cx + mx * k.cells_x, cy + my * k.cells_y, 0, b);
                    REQUIRE(a.x.size() == b.x.size());
                    ok &= same_bits(a.amplitude, b.amplitude) && same_bits(a.theta0, b.theta0);
                    for (size_t i = 0; i < a.x.size(); ++i) {
                        const double sx = mx * k.px, sy = my * k.py;
                        ok &= std::abs(b.x[i] - a.x[i] - sx) <= 1e-9 * std::max(1.0, std::abs(sx)) * k.px;
                        ok &= std::abs(b.y[i] - a.y[i] - sy) <= 1e-9 * std::max(1.0, std::abs(sy)) * k.py;
                        ++compared;
                    }
                }
        CHECK(compared > 300);
        CHECK(ok);
        // Teeth: without the period the same cells are unrelated.
        ProcessConfig free = c;
        free.period.reset();
        impulse::sim::cell_impulses(free, 0, 0, 0, a);
        impulse::sim::cell_impulses(free, k.cells_x, 0, 0, b);
        CHECK_FALSE(same_bits(a.amplitude, b.amplitude));
    }
}

TEST_CASE("looped births repeat every loop with birth times shifted by the loop", "[sim]") {
    ProcessConfig c = still_config(8);
    c.lifetime_s = 2.0;
    c.loop_s = 6.0;  // 12 time cells of 0.5 s per loop
    CellImpulses a, b;
    size_t compared = 0;
    bool ok = true;
    for (int64_t ct = -3; ct < 15; ++ct)
        for (int64_t cx = 0; cx < 8; ++cx) {
            impulse::sim::cell_impulses(c, cx, 1, ct, a);
            impulse::sim::cell_impulses(c, cx, 1, ct + 12, b);
            REQUIRE(a.x.size() == b.x.size());
            ok &= same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.amplitude, b.amplitude);
            for (size_t i = 0; i < a.x.size(); ++i) {
                ok &= std::abs(b.birth_s[i] - a.birth_s[i] - 6.0) < 1e-9;
                ++compared;
            }
        }
    CHECK(compared > 100);
    CHECK(ok);
}

TEST_CASE("different seeds and layers give different impulses", "[sim]") {
    // Same cells under four keys; no impulse position may coincide between any two of them,
    // and the counts must not all agree (each pair of cells agrees in count with probability
    // ~0.18 for Poisson(5.1), so 100 equal counts would be a 1e-74 event).
    const std::vector<ProcessConfig> configs = {still_config(1, 0), still_config(2, 0),
                                                still_config(1, 1),
                                                still_config(1 + (uint64_t{1} << 32), 0)};
    std::vector<std::vector<CellImpulses>> cells(configs.size(), std::vector<CellImpulses>(100));
    for (size_t k = 0; k < configs.size(); ++k)
        for (int i = 0; i < 100; ++i) impulse::sim::cell_impulses(configs[k], i % 10, i / 10, 0, cells[k][i]);
    for (size_t a = 0; a < configs.size(); ++a)
        for (size_t b = a + 1; b < configs.size(); ++b) {
            CAPTURE(a, b);
            int same_count = 0, shared_positions = 0;
            for (int i = 0; i < 100; ++i) {
                same_count += cells[a][i].x.size() == cells[b][i].x.size();
                for (double x : cells[a][i].x)
                    shared_positions += std::count(cells[b][i].x.begin(), cells[b][i].x.end(), x) > 0;
            }
            CHECK(same_count < 100);
            CHECK(shared_positions == 0);
        }
}
