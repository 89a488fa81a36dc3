// SPDX-License-Identifier: Apache-2.0
// The normal amplitude's own Box–Muller (sim/normal.h): its accuracy against the C library's
// log and sin in long double, on a dense grid of the uniforms Philox gives, their extremes and
// random doubles; and the AVX2 lanes against the scalar function, bit for bit.

#include <algorithm>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "sim/normal.h"
#include "numeric/rng.h"

namespace {

using impulse::sim::detail::normal_from_uniforms;

/// sqrt(-2 ln u) cos(2 pi v) in long double (64-bit significand on x86-64). cos(2 pi v) is
/// taken as sin(2 pi d), d = 1/4 - min(v, 1 - v), both subtractions exact in long double: the
/// argument 2 pi v itself would carry an absolute error of ~1e-19, which near the zeros
/// (v = 1/4, 3/4 to within 2^-33) is not small next to the value.
long double reference(double u, double v) {
    const long double a = v > 0.5 ? 1.0L - v : static_cast<long double>(v);
    const long double d = 0.25L - a;
    return std::sqrt(-2.0L * std::log(static_cast<long double>(u))) *
           std::sin(2.0L * std::numbers::pi_v<long double> * d);
}

/// Uniforms as the simulator draws them: Philox words k as (k + 1/2) 2^-32 (Random123's u01).
double grid(uint32_t k) { return impulse::numeric::CounterRng::u01(k); }

/// Inputs: every 4099th grid word (about a million), their extremes, the points where the
/// reductions switch (m = sqrt(2), v = 1/2, d = 0) and their neighbours, then random doubles.
std::vector<double> inputs(bool angle) {
    std::vector<double> x;
    for (uint64_t k = 0; k < (uint64_t(1) << 32); k += 4099) x.push_back(grid(uint32_t(k)));
    for (uint32_t k = 0; k < 64; ++k) x.push_back(grid(k)), x.push_back(grid(~k));
    for (double p : {1.0, 0.5, 0.25, 0.75, std::sqrt(0.5), std::sqrt(0.125), 0.125, 1.0 / 3}) {
        double y = p;
        for (int i = 0; i < 8; ++i) x.push_back(y), y = std::nextafter(y, 0.0);
        y = p;
        for (int i = 0; i < 8 && y < 1.0; ++i) x.push_back(y), y = std::nextafter(y, 2.0);
    }
    if (angle) x.push_back(0.0);
    std::mt19937_64 gen(20261201);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    std::uniform_int_distribution<int> exponent(angle ? -60 : -1000, 0);  // normal doubles
    for (int i = 0; i < 200000; ++i) {
        const double y = std::ldexp(uniform(gen), exponent(gen));
        if (y > 0.0 && y <= 1.0) x.push_back(y);
    }
    return x;
}

}  // namespace

TEST_CASE("normal amplitude: accuracy against the C library in long double", "[sim][stats]") {
    // The bound derived (unit roundoff e = 2^-53). ln: f = m - 1 exact, s = f / (2 + f) within
    // 2e (two roundings); 2 s (1 + z Q) adds about 1e (z Q < 1 %); e ln 2 + ln m two more
    // roundings. As |ln m| <= ln 2 / 2 <= |ln u| whenever e != 0, ln u is within about 5e. The
    // square root halves that and rounds: 3.5e. cos: d exact where |d| < 1/8 (Sterbenz), within
    // 1e elsewhere; d^2 and the Estrin steps about 4e. The product: 1e. In all about 9e; allowed
    // 16e = 1.8e-15 for the slack of this accounting. Measured: 6.3e (7.0e-16) over these 3.5
    // million pairs, and no float off the float of the long-double value.
    const double tol = 16 * std::ldexp(1.0, -53);
    const std::vector<double> us = inputs(false), vs = inputs(true);
    // Every u with v at a 1/3 (cos = -1/2), and every v with u at a grid word near e^-1/2
    // (sqrt(-2 ln u) near 1), then random pairs.
    double worst = 0, worst_u = 0, worst_v = 0;
    size_t float_off = 0, n = 0;
    auto check = [&](double u, double v) {
        const double got = normal_from_uniforms(u, v);
        const long double want = reference(u, v);
        ++n;
        if (want == 0) {
            CHECK(got == 0);
            return;
        }
        const double err = static_cast<double>(std::abs((got - want) / want));
        if (err > worst) worst = err, worst_u = u, worst_v = v;
        // The float amplitude is the float nearest the exact value or, within tol of a halfway
        // point, its neighbour.
        const float f = static_cast<float>(got), g = static_cast<float>(want);
        if (f != g) {
            ++float_off;
            CHECK((std::nextafter(f, g) == g));
        }
    };
    for (double u : us) check(u, 1.0 / 3);
    for (double v : vs) check(grid(0x9B4597E3u), v);
    std::mt19937_64 gen(7);
    for (int i = 0; i < 1000000; ++i) {
        const uint64_t w = gen();
        check(grid(uint32_t(w)), grid(uint32_t(w >> 32)));
    }
    INFO(n << " pairs; worst relative error " << worst << " = " << worst / std::ldexp(1.0, -53)
           << " e at u = " << worst_u << ", v = " << worst_v
           << "; floats off by one ulp: " << float_off);
    CHECK(worst <= tol);
}

TEST_CASE("normal amplitude: extremes of u", "[sim]") {
    CHECK(normal_from_uniforms(1.0, 0.3) == 0.0);
    // The smallest Philox uniform, 2^-33: sqrt(66 ln 2) = 6.7636...
    const double smallest = grid(0);
    CHECK(smallest == std::ldexp(1.0, -33));
    CHECK(normal_from_uniforms(smallest, 1.0) ==
          Approx(std::sqrt(66.0 * std::numbers::ln2)).epsilon(1e-15));
    CHECK(normal_from_uniforms(smallest, 0.5) ==
          Approx(-std::sqrt(66.0 * std::numbers::ln2)).epsilon(1e-15));
    // The largest, 1 - 2^-33: sqrt(-2 ln(1 - 2^-33)) = 2^-16 (1 + 2^-35 + O(2^-68)).
    CHECK(normal_from_uniforms(grid(0xFFFFFFFFu), 0.0) ==
          Approx(std::ldexp(1.0, -16) * (1.0 + std::ldexp(1.0, -35))).epsilon(1e-15));
}

TEST_CASE("normal amplitude: AVX2 lanes give the scalar function's bits", "[sim][determinism]") {
    if (!impulse::numeric::cpu_has_avx2()) {
        WARN("no AVX2 on this CPU: only the scalar function is checked");
        return;
    }
    std::vector<double> u = inputs(false), v = inputs(true);
    std::mt19937_64 gen(3);
    std::shuffle(u.begin(), u.end(), gen);
    std::shuffle(v.begin(), v.end(), gen);
    const size_t n = std::min(u.size(), v.size());
    std::vector<double> got(n);
    std::vector<float> got_f(n);
    // Every length up to 40 (whole registers, the 16-lane steps and every tail), then all.
    for (size_t len = 1; len <= 40; ++len) {
        impulse::sim::detail::normals_from_uniforms_avx2(len, u.data(), v.data(), got.data());
        for (size_t j = 0; j < len; ++j)
            REQUIRE(std::bit_cast<uint64_t>(got[j]) ==
                    std::bit_cast<uint64_t>(normal_from_uniforms(u[j], v[j])));
    }
    impulse::sim::detail::normals_from_uniforms_avx2(n, u.data(), v.data(), got.data());
    impulse::sim::detail::normals_from_uniforms_avx2(n, u.data(), v.data(), got_f.data());
    size_t diff = 0, diff_f = 0;
    for (size_t j = 0; j < n; ++j) {
        const double want = normal_from_uniforms(u[j], v[j]);
        diff += std::bit_cast<uint64_t>(got[j]) != std::bit_cast<uint64_t>(want);
        diff_f +=
            std::bit_cast<uint32_t>(got_f[j]) != std::bit_cast<uint32_t>(static_cast<float>(want));
    }
    INFO(n << " pairs");
    CHECK(diff == 0);
    CHECK(diff_f == 0);
    // NormalBatch (the still path's) chooses the AVX2 lanes here: the same floats.
    impulse::sim::detail::NormalBatch batch;
    for (size_t j = 0; j < 1001; ++j) batch.add(u[j], v[j]);
    std::vector<float> out(1001);
    batch.run(out.data());
    for (size_t j = 0; j < 1001; ++j) CHECK(out[j] == got_f[j]);
}
