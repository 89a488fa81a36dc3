// SPDX-License-Identifier: Apache-2.0
// The base library: keyed counter streams, the FFT wrapper, the normal distribution.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "numeric/numeric.h"

namespace numeric = impulse::numeric;

TEST_CASE("keyed sub-streams are deterministic, distinct and leave the plain stream alone",
          "[numeric][rng]") {
    const numeric::CounterRng rng(0x0123456789ABCDEFull, 7);
    const numeric::CounterRng z3 = rng.keyed(3), z3_again = rng.keyed(3), z4 = rng.keyed(4);
    CHECK(z3.uniforms(1, 2, 3, 4) == z3_again.uniforms(1, 2, 3, 4));
    CHECK(z3.uniforms(1, 2, 3, 4) != z4.uniforms(1, 2, 3, 4));
    CHECK(z3.uniforms(1, 2, 3, 4) != rng.uniforms(1, 2, 3, 4));
    // Coordinates 2^32 apart are different sub-streams (the high word is in the key).
    CHECK(rng.keyed(5).uniforms(0, 0, 0, 0) != rng.keyed(5 + (int64_t(1) << 32)).uniforms(0, 0, 0, 0));
    // keyed() of keyed() adds a coordinate: (a, b) and (b, a) differ.
    CHECK(rng.keyed(1).keyed(2).uniforms(0, 0, 0, 0) != rng.keyed(2).keyed(1).uniforms(0, 0, 0, 0));
}

TEST_CASE("keyed sub-streams are uniform: chi-square over 16 bins within its 5-sigma band",
          "[numeric][rng][stats]") {
    // 4 * 2^14 uniforms from 2^14 sub-streams (z = 0 .. 2^14 - 1, one counter each): chi-square
    // with 15 degrees of freedom has mean 15 and sd sqrt(30) = 5.5; a 5 sd band is 15 + 27.4.
    const numeric::CounterRng rng(42, 1);
    std::vector<double> count(16, 0.0);
    const int n = 1 << 14;
    for (int z = 0; z < n; ++z)
        for (double u : rng.keyed(z).uniforms(0, 0, 0, 0)) count[std::min(15, int(u * 16))] += 1;
    const double expected = 4.0 * n / 16.0;
    double chi2 = 0.0;
    for (double c : count) chi2 += (c - expected) * (c - expected) / expected;
    CHECK(chi2 < 15.0 + 5.0 * std::sqrt(30.0));
}

TEST_CASE("RealFft2d: forward then inverse multiplies by rows * cols", "[numeric][fft]") {
    numeric::RealFft2d fft(6, 10, numeric::FftPlans::Both);
    std::vector<double> f(60);
    for (size_t i = 0; i < f.size(); ++i) f[i] = std::sin(0.7 * double(i)) + 0.1 * double(i % 7);
    std::copy(f.begin(), f.end(), fft.real());
    fft.forward();
    // DC = sum of the values.
    double sum = 0.0;
    for (double v : f) sum += v;
    CHECK(fft.spectrum()[0].real() == Approx(sum).epsilon(1e-12));
    fft.inverse();
    for (size_t i = 0; i < f.size(); ++i) CHECK(fft.real()[i] / 60.0 == Approx(f[i]).margin(1e-12));
}

TEST_CASE("normal quantile inverts the CDF to 1e-13 in both tails", "[numeric][normal]") {
    for (double z = -8.0; z <= 8.0; z += 0.25) {
        const double p = numeric::normal_cdf(z), q = numeric::normal_cdf(-z);
        CHECK(numeric::normal_quantile(p, q) == Approx(z).margin(1e-13 * std::max(1.0, std::abs(z))));
    }
    CHECK(numeric::normal_quantile(0.5) == Approx(0.0).margin(1e-15));
    CHECK(numeric::normal_pdf(0.0) == Approx(1.0 / std::sqrt(2.0 * 3.141592653589793)));
}

TEST_CASE("Region: bounds, area and emptiness of a union of boxes", "[numeric][box]") {
    numeric::Region r;
    r.boxes = {{0, 0, 2, 1}, {5, -1, 6, 3}, {1, 1, 0, 0}};  // the last is empty
    const numeric::Box b = r.bounds();
    CHECK(b.x0 == 0);
    CHECK(b.y0 == -1);
    CHECK(b.x1 == 6);
    CHECK(b.y1 == 3);
    CHECK(r.area() == 6.0);
    CHECK(!r.empty());
    CHECK(numeric::Region(numeric::Box{1, 1, 0, 0}).empty());
}

TEST_CASE("Keyframed integral: the closed form matches Simpson's rule for every ease",
          "[numeric][keyframed]") {
    for (numeric::Ease ease : {numeric::Ease::Linear, numeric::Ease::Smooth, numeric::Ease::Step}) {
        numeric::Keyframed k;
        k.keys = {{-1.0, 2.0}, {0.5, -3.0}, {2.0, 4.0}, {3.5, 1.0}};
        k.ease = ease;
        for (double t : {-2.0, -0.4, 0.0, 0.7, 2.0, 2.9, 5.0}) {
            // Composite Simpson on each piece between keys and t: the integrand is a cubic
            // there (smoothstep), so Simpson is exact up to rounding; step's jumps sit at keys.
            std::vector<double> cuts = {0.0, t};
            for (const auto& key : k.keys)
                if (key.first > std::min(0.0, t) && key.first < std::max(0.0, t)) cuts.push_back(key.first);
            std::sort(cuts.begin(), cuts.end());
            double ref = 0.0;
            for (size_t c = 1; c < cuts.size(); ++c) {
                const double a = cuts[c - 1], b = cuts[c], m = 0.5 * (a + b), e = 1e-12;
                // Just inside the piece, so a step's held value is the piece's own.
                ref += (b - a) / 6.0 * (k.value(a + e) + 4.0 * k.value(m) + k.value(b - e));
            }
            if (t < 0) ref = -ref;
            CAPTURE(int(ease), t);
            CHECK(k.integral(t) == Approx(ref).margin(1e-9));
        }
    }
    CHECK(numeric::Keyframed(2.5).integral(3.0) == 7.5);  // a constant: v t
}

TEST_CASE("quantile bins by selection hold what a full sort by (key, index) puts in each",
          "[numeric][quantile]") {
    // Keys with many ties (16 levels), both signs and both zeros, at more and fewer keys than
    // bins; each bin's set of indices, and each bin start's own index, against a full sort.
    uint32_t state = 777u;
    const auto next = [&] { state = state * 1664525u + 1013904223u; return state >> 8; };
    for (const auto& [n, bins] : {std::pair{1000, 16}, std::pair{1001, 7}, std::pair{5, 16},
                                  std::pair{1, 2}, std::pair{0, 4}, std::pair{4096, 256}}) {
        std::vector<float> key(static_cast<size_t>(n));
        for (float& k : key) k = float(int(next() % 16) - 8) * 0.25f;
        for (size_t i = 0; i < key.size(); i += 5) key[i] = (i / 5) % 2 ? -0.0f : 0.0f;
        std::vector<size_t> sorted(static_cast<size_t>(n));
        for (size_t i = 0; i < sorted.size(); ++i) sorted[i] = i;
        // -0 and +0 are one key: compare by value, then by index.
        std::sort(sorted.begin(), sorted.end(), [&](size_t a, size_t b) {
            return key[a] < key[b] || (key[a] == key[b] && a < b);
        });
        const std::vector<size_t> order = numeric::order_into_quantile_bins(key, bins);
        REQUIRE(order.size() == size_t(n));
        for (int b = 0; b < bins; ++b) {
            const size_t i0 = numeric::quantile_bin_start(size_t(n), b, bins);
            const size_t i1 = numeric::quantile_bin_start(size_t(n), b + 1, bins);
            CAPTURE(n, bins, b);
            std::vector<size_t> got(order.begin() + long(i0), order.begin() + long(i1));
            std::vector<size_t> want(sorted.begin() + long(i0), sorted.begin() + long(i1));
            std::sort(got.begin(), got.end());
            std::sort(want.begin(), want.end());
            CHECK(got == want);
            if (i0 < size_t(n)) CHECK(order[i0] == sorted[i0]);
        }
    }
}
