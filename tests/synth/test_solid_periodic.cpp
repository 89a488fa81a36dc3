// SPDX-License-Identifier: Apache-2.0
// Periodic solid noise (SolidParams::period_cells, issue 38; docs/export.md "Volume"): the noise
// at x + N R equals the noise at x bit for bit along each periodic axis, through the point path
// and the grid path, with the non-periodic noise as the control (it differs there, so the test
// fails when the cell keys do not wrap); one-point statistics as the non-periodic noise's.

#include <catch2/catch.hpp>

#include <cmath>
#include <numeric>
#include <random>

#include "numeric/errors.h"
#include "synth/synth.h"

using namespace impulse;
using synth::SolidPoint;
using Catch::Matchers::Contains;

namespace {

// R = 8 and points on a grid of 1/16: every coordinate, cell index and offset in a cell is
// exact in binary, so x and x + N R reach the kernel with the same bits.
synth::SolidParams periodic(std::array<int64_t, 3> cells) {
    synth::SolidParams p;
    p.kernel.radius = 8.0;
    p.density = 16.0;
    p.seed = 9;
    p.period_cells = cells;
    return p;
}

std::vector<SolidPoint> dyadic_points(size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> k(-2000, 2000);
    std::vector<SolidPoint> p(n);
    for (auto& q : p) q = {k(rng) / 16.0, k(rng) / 16.0, k(rng) / 16.0, 0.0};
    return p;
}

/// How many points have the same value after a shift by `d`.
size_t unchanged(const synth::SolidNoise& noise, const std::vector<SolidPoint>& p, const SolidPoint& d) {
    std::vector<SolidPoint> q = p;
    for (auto& s : q) s.x += d.x, s.y += d.y, s.z += d.z;
    std::vector<float> a, b;
    noise.evaluate(p, a);
    noise.evaluate(q, b);
    size_t same = 0;
    for (size_t i = 0; i < a.size(); ++i) same += a[i] == b[i];
    return same;
}

}  // namespace

TEST_CASE("periodic solid noise repeats every period_cells cells, bit for bit", "[synth][solid][periodic]") {
    const synth::SolidNoise noise(periodic({4, 3, 2})), control(periodic({0, 0, 0}));
    const std::vector<SolidPoint> p = dyadic_points(4000, 1);
    for (const SolidPoint d : {SolidPoint{32, 0, 0, 0}, SolidPoint{0, 24, 0, 0}, SolidPoint{0, 0, 16, 0},
                               SolidPoint{-64, 48, -32, 0}}) {
        INFO("shift " << d.x << ", " << d.y << ", " << d.z);
        CHECK(unchanged(noise, p, d) == p.size());
        CHECK(unchanged(control, p, d) < p.size() / 100);  // control: no period, other values
    }
    CHECK(unchanged(noise, p, {8, 0, 0, 0}) < p.size() / 100);  // one cell is not a period
}

TEST_CASE("a periodic grid wraps: the sample past the last is the first", "[synth][solid][periodic]") {
    const synth::SolidNoise noise(periodic({4, 4, 2}));
    const std::vector<float> g = noise.grid(32, 32, 16, SolidPoint{});
    const std::vector<float> shifted = noise.grid(32, 32, 16, SolidPoint{32, -32, 16, 0});
    CHECK(g == shifted);
    const synth::SolidNoise control(periodic({0, 0, 0}));
    CHECK(control.grid(32, 32, 16, SolidPoint{}) != control.grid(32, 32, 16, SolidPoint{32, -32, 16, 0}));
}

TEST_CASE("periodic solid noise keeps Campbell's variance", "[synth][solid][periodic][stats]") {
    // One period of 16^3 cells of side 8 (128^3 voxels, 4096 cells): the sample variance of a
    // 64^3 grid at spacing 2 against lambda E[a^2] int h^2. Its sampling error: samples within
    // one kernel diameter (2R = 16, 8 samples) are correlated, so about (64 / 8)^3 = 512
    // effective samples and a relative sd of sqrt(2 / 512) = 0.0625 (a Gaussian field's
    // variance estimator); 5 sd.
    const synth::SolidNoise noise(periodic({16, 16, 16}));
    const std::vector<float> g = noise.grid(64, 64, 64, SolidPoint{}, 2.0);
    const double mean = std::accumulate(g.begin(), g.end(), 0.0) / double(g.size());
    double var = 0;
    for (const float v : g) var += (v - mean) * (v - mean) / double(g.size());
    const double expected = noise.theory().variance, rel_sd = std::sqrt(2.0 / 512.0);
    CHECK(std::abs(var / expected - 1.0) < 5.0 * rel_sd);
}

TEST_CASE("period_cells is checked", "[synth][solid][periodic][errors]") {
    CHECK_THROWS_WITH(synth::SolidNoise(periodic({-1, 0, 0})), Contains("period_cells: expected cells per period in [0, 2^40]"));
    synth::SolidParams p = periodic({4, 4, 4});
    p.metric = {2, 0, 0, 0, 1, 0, 0, 0, 1};
    CHECK_THROWS_WITH(synth::SolidNoise(p), Contains("period_cells: a periodic noise takes the identity metric only"));
}
