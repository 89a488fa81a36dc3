// SPDX-License-Identifier: Apache-2.0
// Tests of impulse::analysis: exact values on hand-made inputs, statistical checks on seeded
// Gaussian fields with tolerances derived from the sampling error, error paths, determinism.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <thread>
#include <vector>

#include "analysis/analysis.h"
#include "numeric/errors.h"

using namespace impulse::analysis;
using impulse::ValueError;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Standard normal deviates from std::mt19937_64 (whose output the standard fixes) by
// Box–Muller, so the streams are the same with every standard library; std::normal_distribution
// is implementation-defined.
class Gaussian {
public:
    explicit Gaussian(uint64_t seed) : m_rng(seed) {}
    double operator()() {
        if (m_has_spare) {
            m_has_spare = false;
            return m_spare;
        }
        const double u1 = uniform();  // in (0, 1): log(u1) is finite
        const double u2 = uniform();
        const double r = std::sqrt(-2.0 * std::log(u1));
        m_spare = r * std::sin(kTwoPi * u2);
        m_has_spare = true;
        return r * std::cos(kTwoPi * u2);
    }

private:
    double uniform() { return (static_cast<double>(m_rng() >> 11) + 0.5) * 0x1.0p-53; }
    std::mt19937_64 m_rng;
    double m_spare = 0.0;
    bool m_has_spare = false;
};

Image make_image(int w, int h) {
    Image im;
    im.width = w;
    im.height = h;
    im.data.assign(static_cast<size_t>(w) * h, 0.0f);
    return im;
}

Image white_noise(int w, int h, double sigma, uint64_t seed) {
    Image im = make_image(w, h);
    Gaussian g(seed);
    for (float& v : im.data) v = static_cast<float>(sigma * g());
    return im;
}

int signed_lag(int i, int n) { return i < (n + 1) / 2 ? i : i - n; }

double uniform_cdf(double x, const void*) { return std::clamp(x, 0.0, 1.0); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// One-point statistics

TEST_CASE("moments of known arrays", "[analysis]") {
    SECTION("1..8: symmetric, platykurtic") {
        const std::vector<float> v = {1, 2, 3, 4, 5, 6, 7, 8};
        const Moments m = moments(v);
        CHECK(m.mean == 4.5);
        CHECK(m.variance == 5.25);  // sum of d^2 = 2 (0.25 + 2.25 + 6.25 + 12.25) = 42; / 8
        CHECK(m.skewness == 0.0);
        // m4 = 2 (0.0625 + 5.0625 + 39.0625 + 150.0625) / 8 = 48.5625; / 5.25^2 - 3 = -26/21
        CHECK(m.excess_kurtosis == Approx(-26.0 / 21.0).epsilon(1e-14));
        CHECK(m.min == 1.0);
        CHECK(m.max == 8.0);
    }
    SECTION("{0,0,0,1}: Bernoulli(1/4)") {
        const std::vector<float> v = {0, 0, 1, 0};
        const Moments m = moments(v);
        CHECK(m.mean == 0.25);
        CHECK(m.variance == 0.1875);
        // Bernoulli(p): skewness (1 - 2p)/sqrt(p q) = 2/sqrt(3); excess kurtosis
        // (1 - 6 p q)/(p q) = (1 - 9/8) / (3/16) = -2/3.
        CHECK(m.skewness == Approx(2.0 / std::sqrt(3.0)).epsilon(1e-14));
        CHECK(m.excess_kurtosis == Approx(-2.0 / 3.0).epsilon(1e-14));
    }
    SECTION("constant: shape moments reported as 0") {
        const std::vector<float> v(10, 3.0f);
        const Moments m = moments(v);
        CHECK(m.mean == 3.0);
        CHECK(m.variance == 0.0);
        CHECK(m.skewness == 0.0);
        CHECK(m.excess_kurtosis == 0.0);
    }
}

TEST_CASE("histogram counts bins, below and above", "[analysis]") {
    const std::vector<float> v = {-1.0f, 0.0f, 0.24f, 0.25f, 0.5f, 0.99f, 1.0f, 2.0f};
    const Histogram h = histogram(v, 0.0, 1.0, 4);
    CHECK(h.lo == 0.0);
    CHECK(h.hi == 1.0);
    REQUIRE(h.counts.size() == 4);
    CHECK(h.counts[0] == 2);  // 0, 0.24
    CHECK(h.counts[1] == 1);  // 0.25 (bins are closed on the left)
    CHECK(h.counts[2] == 1);  // 0.5
    CHECK(h.counts[3] == 1);  // 0.99
    CHECK(h.below == 1);      // -1
    CHECK(h.above == 2);      // 1 (hi is open) and 2
}

TEST_CASE("ks_distance against the uniform CDF has its exact value", "[analysis]") {
    SECTION("midpoint grid (i + 1/2)/8: D = 1/16") {
        // The ECDF steps by 1/8 at each point and F passes through the middle of every step.
        std::vector<float> v;
        for (int i = 7; i >= 0; --i) v.push_back((i + 0.5f) / 8.0f);  // unsorted on purpose
        CHECK(ks_distance(v, uniform_cdf, nullptr) == 1.0 / 16.0);
    }
    SECTION("left grid i/8: D = 1/8") {
        std::vector<float> v;
        for (int i = 0; i < 8; ++i) v.push_back(i / 8.0f);
        CHECK(ks_distance(v, uniform_cdf, nullptr) == 1.0 / 8.0);
    }
    SECTION("ties: {1/2, 1/2, 1/2, 1}: D = 1/2 at the left limit of the tied step") {
        const std::vector<float> v = {0.5f, 1.0f, 0.5f, 0.5f};
        // F_n jumps 0 -> 3/4 at x = 1/2, where F = 1/2: the gaps are 1/2 (left) and 1/4.
        CHECK(ks_distance(v, uniform_cdf, nullptr) == 0.5);
    }
}

// ---------------------------------------------------------------------------------------------
// Periodogram and radial profile

TEST_CASE("periodogram of a cosine: energy in its two bins, Parseval", "[analysis]") {
    // f = A cos(2 pi (kx0 x / w + ky0 y / h)) has DFT A N/2 at +-(kx0, ky0) and 0 elsewhere, so
    // power = (A N / 2)^2 / N = A^2 N / 4 in each of the two bins. Parseval (no window, mean
    // removed): sum_k power = sum_x (f - mean)^2, i.e. sum power / N = population variance.
    // Non-square and odd sizes catch transposed layouts and errors in the conjugate fill.
    struct Case {
        int w, h, kx0, ky0;
    };
    const Case cases[] = {{64, 48, 5, 3}, {45, 30, 7, 11}, {33, 17, 16, 8}, {40, 40, 0, 9}};
    for (const Case& c : cases) {
        CAPTURE(c.w, c.h, c.kx0, c.ky0);
        const double amp = 1.5;
        Image im = make_image(c.w, c.h);
        for (int y = 0; y < c.h; ++y) {
            for (int x = 0; x < c.w; ++x) {
                const double phase = kTwoPi * (double(c.kx0 * x) / c.w + double(c.ky0 * y) / c.h);
                im.data[static_cast<size_t>(y) * c.w + x] =
                    static_cast<float>(amp * std::cos(phase));
            }
        }
        const Periodogram p = periodogram(im);
        REQUIRE(p.width == c.w);
        REQUIRE(p.height == c.h);
        REQUIRE(p.power.size() == static_cast<size_t>(c.w) * c.h);
        const double n = double(c.w) * c.h;
        const double peak = amp * amp * n / 4.0;
        const size_t i_pos = static_cast<size_t>(c.ky0) * c.w + c.kx0;
        const size_t i_neg = static_cast<size_t>((c.h - c.ky0) % c.h) * c.w + (c.w - c.kx0) % c.w;
        // float storage of f leaves relative errors ~1e-7 in the amplitude.
        CHECK(p.power[i_pos] == Approx(peak).epsilon(1e-6));
        CHECK(p.power[i_neg] == Approx(peak).epsilon(1e-6));
        CHECK(p.power[0] == 0.0);
        double sum = 0.0, off_peak = 0.0;
        for (size_t i = 0; i < p.power.size(); ++i) {
            sum += p.power[i];
            if (i != i_pos && i != i_neg) off_peak = std::max(off_peak, p.power[i]);
        }
        CHECK(off_peak < 1e-9 * peak);
        CHECK(sum / n == Approx(moments(im.data).variance).epsilon(1e-9));
        CHECK(Periodogram::frequency(c.kx0, c.w) == double(c.kx0) / c.w);
    }
}

TEST_CASE("periodogram with a Hann window is normalised by the window energy", "[analysis]") {
    // Parseval for the windowed field g w (g = f - mean): sum_k |F|^2 = N sum_x w^2 g^2, and the
    // DC bin, |sum_x w g|^2, is set to zero. So sum_k power =
    // (N sum w^2 g^2 - |sum w g|^2) / sum w^2 with w the periodic Hann 0.5 - 0.5 cos(2 pi x / n).
    const int w = 48, h = 36;
    const Image im = white_noise(w, h, 1.0, 7);
    const Periodogram p = periodogram(im, Window::Hann);
    double mean = 0.0;
    for (float v : im.data) mean += v;
    mean /= double(w) * h;
    double sw2 = 0.0, sw2g2 = 0.0, swg = 0.0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const double wt =
                (0.5 - 0.5 * std::cos(kTwoPi * x / w)) * (0.5 - 0.5 * std::cos(kTwoPi * y / h));
            const double g = im.at(x, y) - mean;
            sw2 += wt * wt;
            sw2g2 += wt * wt * g * g;
            swg += wt * g;
        }
    }
    double sum = 0.0;
    for (double v : p.power) sum += v;
    CHECK(sum == Approx((double(w) * h * sw2g2 - swg * swg) / sw2).epsilon(1e-9));
    // The periodic Hann window has sum w^2 = 3n/8 per axis.
    CHECK(sw2 == Approx((3.0 * w / 8.0) * (3.0 * h / 8.0)).epsilon(1e-12));
}

TEST_CASE("radial_average geometry", "[analysis]") {
    SECTION("square 16x16") {
        Periodogram p;
        p.width = p.height = 16;
        p.power.assign(256, 1.0);
        const RadialProfile r = radial_average(p);
        REQUIRE(r.power.size() == 8);  // annuli b = 0..7, b/16 < 0.5
        // Annulus 0 would hold only DC, which is skipped.
        CHECK(r.count[0] == 0);
        CHECK(r.power[0] == 0.0);
        CHECK(r.frequency[0] == 0.0);
        // |k|*16 in [1, 2): (+-1, 0), (0, +-1), (+-1, +-1) -> 8 bins, mean |k| (4 + 4 sqrt2)/8/16.
        CHECK(r.count[1] == 8);
        CHECK(r.frequency[1] == Approx((1.0 + std::sqrt(2.0)) / 2.0 / 16.0).epsilon(1e-14));
        // [2, 3): (2,0)x4, (2,1)x8, (2,2)x4 -> 16 bins.
        CHECK(r.count[2] == 16);
        uint64_t total = 0, expected = 0;
        for (size_t b = 0; b < r.count.size(); ++b) {
            total += r.count[b];
            if (r.count[b] > 0) {
                CHECK(r.power[b] == 1.0);
                CHECK(r.frequency[b] >= b / 16.0);
                CHECK(r.frequency[b] < (b + 1) / 16.0);
            }
        }
        for (int y = -8; y < 8; ++y) {
            for (int x = -8; x < 8; ++x) expected += (x * x + y * y > 0 && x * x + y * y < 64);
        }
        CHECK(total == expected);
    }
    SECTION("rectangular 32x16: dk = 1/16, the finer axis fills annulus 0") {
        Periodogram p;
        p.width = 32;
        p.height = 16;
        p.power.assign(512, 2.0);
        const RadialProfile r = radial_average(p);
        REQUIRE(r.power.size() == 8);
        CHECK(r.count[0] == 2);  // kx = +-1: |k| = 1/32
        CHECK(r.frequency[0] == 1.0 / 32.0);
        CHECK(r.power[0] == 2.0);
    }
}

TEST_CASE("white noise: radial average equals the variance", "[analysis][stats]") {
    // For white Gaussian noise of variance s2 each non-DC, non-Nyquist bin is s2 times a unit
    // exponential, the two members of a conjugate pair being equal. An annulus of `count` bins
    // averages count/2 independent exponentials: relative sd 1/sqrt(count/2). Tolerance 5 sd;
    // over the 127 annuli the one-sided Gamma upper tail at 5 sd is at most 5e-4 for the
    // smallest annulus (count 8, Gamma(4)) and ~1e-6 for the large ones, so a failure is a bug.
    const double s2 = 2.5;
    const Image im = white_noise(256, 256, std::sqrt(s2), 20240601);
    const RadialProfile r = radial_average(periodogram(im));
    REQUIRE(r.power.size() == 128);
    CHECK(r.count[0] == 0);
    for (size_t b = 1; b < r.power.size(); ++b) {
        CAPTURE(b, r.count[b], r.power[b]);
        REQUIRE(r.count[b] > 0);
        const double tol = 5.0 / std::sqrt(r.count[b] / 2.0);
        CHECK(std::abs(r.power[b] / s2 - 1.0) < tol);
    }
}

TEST_CASE("white noise with a Hann window: mean power equals the variance", "[analysis][stats]") {
    // By Parseval the mean of all bins is sum w^2 g^2 / sum w^2 (the DC bin, ~s2 / N of the
    // mean, is negligible). E = s2; Var = 2 s2^2 sum w^4 / (sum w^2)^2, and for the separable
    // periodic Hann window sum w^4 / (sum w^2)^2 = (35/(18 n))^2 per pair of axes, so the
    // relative sd is sqrt(2) * 35/18 / sqrt(N) = 0.0107 at 256x256. Tolerance 5 sd = 0.054.
    const double s2 = 0.7;
    const Image im = white_noise(256, 256, std::sqrt(s2), 99);
    const Periodogram p = periodogram(im, Window::Hann);
    double sum = 0.0;
    for (double v : p.power) sum += v;
    const double mean_power = sum / double(p.power.size() - 1);
    CHECK(std::abs(mean_power / s2 - 1.0) < 5.0 * std::sqrt(2.0) * 35.0 / 18.0 / 256.0);
}

TEST_CASE("average of periodograms is the element-wise mean", "[analysis]") {
    Periodogram a, b;
    a.width = b.width = 2;
    a.height = b.height = 2;
    a.power = {0.0, 1.0, 2.0, 3.0};
    b.power = {0.0, 3.0, 4.0, 7.0};
    const std::vector<Periodogram> both = {a, b};
    const Periodogram m = average(both);
    CHECK(m.width == 2);
    CHECK(m.height == 2);
    CHECK(m.power == std::vector<double>{0.0, 2.0, 3.0, 5.0});
}

// ---------------------------------------------------------------------------------------------
// Autocovariance

TEST_CASE("autocovariance equals the direct circular sum", "[analysis]") {
    // acov(dx, dy) = (1/N) sum_x g(x) g(x + tau), g = f - mean, indices mod (w, h).
    const int w = 9, h = 6;
    const Image im = white_noise(w, h, 1.0, 3);
    const std::vector<double> acov = autocovariance(im);
    REQUIRE(acov.size() == static_cast<size_t>(w * h));
    const double mean = moments(im.data).mean;
    for (int dy = 0; dy < h; ++dy) {
        for (int dx = 0; dx < w; ++dx) {
            double s = 0.0;
            for (int y = 0; y < h; ++y) {
                for (int x = 0; x < w; ++x) {
                    s += (im.at(x, y) - mean) * (im.at((x + dx) % w, (y + dy) % h) - mean);
                }
            }
            CAPTURE(dx, dy);
            CHECK(acov[static_cast<size_t>(dy) * w + dx] == Approx(s / (w * h)).margin(1e-12));
        }
    }
}

TEST_CASE("autocovariance of white noise", "[analysis][stats]") {
    // acov[0] is the population variance (to rounding). Ring 1 averages the 8 lags (+-1, 0),
    // (0, +-1), (+-1, +-1): 4 distinct values, since acov(tau) = acov(-tau) on the torus. Each
    // has mean -s2/N (mean removal) and sd s2/sqrt(N), and they are uncorrelated for white
    // noise (Bartlett's formula), so the ring mean has sd s2/(2 sqrt(N)). Tolerance 5 sd.
    const double s2 = 4.0;
    const int n = 256;
    const Image im = white_noise(n, n, std::sqrt(s2), 12345);
    const std::vector<double> acov = autocovariance(im);
    CHECK(acov[0] == Approx(moments(im.data).variance).epsilon(1e-12));
    const std::vector<double> ring = radial_autocovariance(acov, n, n, 4);
    REQUIRE(ring.size() == 5);
    CHECK(ring[0] == acov[0]);
    const double sd = s2 / (2.0 * n);
    for (size_t r = 1; r < ring.size(); ++r) {
        CAPTURE(r, ring[r]);
        CHECK(std::abs(ring[r]) < 5.0 * sd);
    }
}

TEST_CASE("radial_autocovariance rings by round(|tau|) with wrapped lags", "[analysis]") {
    // acov(tau) = |tau|^2 stored in FFT lag order on a 16x12 grid. By hand:
    // ring 1: (1,0)x4 -> 1, (1,1)x4 -> 2: mean 1.5
    // ring 2: (2,0)x4 -> 4, (2,1)x8 -> 5: mean 56/12          ((2,2) = 2.83 rounds to 3)
    // ring 3: (2,2)x4 -> 8, (3,0)x4 -> 9, (3,1)x8 -> 10: mean 148/16   ((3,2) = 3.61 -> 4)
    const int w = 16, h = 12;
    std::vector<double> acov(static_cast<size_t>(w * h));
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int dx = signed_lag(x, w), dy = signed_lag(y, h);
            acov[static_cast<size_t>(y) * w + x] = dx * dx + dy * dy;
        }
    }
    const std::vector<double> ring = radial_autocovariance(acov, w, h, 3);
    REQUIRE(ring.size() == 4);
    CHECK(ring[0] == 0.0);
    CHECK(ring[1] == 1.5);
    CHECK(ring[2] == Approx(56.0 / 12.0).epsilon(1e-15));
    CHECK(ring[3] == 9.25);
    CHECK(radial_autocovariance(acov, w, h, 6).size() == 7);  // min(w, h)/2 is allowed
}

TEST_CASE("AR(1) field: radial autocovariance matches the closed form", "[analysis][stats]") {
    // Separable circular AR(1): u = rho u(x-1) + e along rows, then the same down columns, run
    // two laps round the torus so the start-up transient is rho^512 ~ 0. The field is then
    // stationary on the torus with C(dx, dy) = s_e^2 rho^(|dx|+|dy|) / (1 - rho^2)^2 (wrap terms
    // rho^(n-|d|) are negligible). The circular estimator has E[acov(tau)] = C(tau) - S/N with
    // S = sum_tau C = s_e^2 / (1 - rho)^4 (the mean removal), exactly.
    // Tolerance: Bartlett's formula for a Gaussian field, Var acov(tau) =
    // (1/N) sum_t [C(t)^2 + C(t + tau) C(t - tau)] <= 2 sum C^2 / N (Cauchy–Schwarz), with
    // sum C^2 = sigma^4 ((1 + rho^2)/(1 - rho^2))^2; a ring mean of such values has sd no larger.
    // For rho = 0.5, N = 512^2: sd <= 0.0082 (sigma^2 = 1.78); tolerance 5 sd.
    const int n = 512;
    const double rho = 0.5;
    Gaussian g(777);
    std::vector<double> e(static_cast<size_t>(n) * n);
    for (double& v : e) v = g();
    std::vector<double> u(e.size());
    for (int y = 0; y < n; ++y) {
        double state = 0.0;
        for (int lap = 0; lap < 2; ++lap) {
            for (int x = 0; x < n; ++x) {
                state = rho * state + e[static_cast<size_t>(y) * n + x];
                u[static_cast<size_t>(y) * n + x] = state;
            }
        }
    }
    Image im = make_image(n, n);
    for (int x = 0; x < n; ++x) {
        double state = 0.0;
        for (int lap = 0; lap < 2; ++lap) {
            for (int y = 0; y < n; ++y) {
                state = rho * state + u[static_cast<size_t>(y) * n + x];
                im.data[static_cast<size_t>(y) * n + x] = static_cast<float>(state);
            }
        }
    }
    const int max_lag = 8;
    const std::vector<double> ring = radial_autocovariance(autocovariance(im), n, n, max_lag);
    const double sigma2 = 1.0 / ((1.0 - rho * rho) * (1.0 - rho * rho));
    const double bias = 1.0 / std::pow(1.0 - rho, 4) / (double(n) * n);
    const double sum_c2 = sigma2 * sigma2 * std::pow((1.0 + rho * rho) / (1.0 - rho * rho), 2);
    const double tol = 5.0 * std::sqrt(2.0 * sum_c2 / (double(n) * n));
    for (int r = 0; r <= max_lag; ++r) {
        double sum = 0.0;
        int count = 0;
        for (int dy = -r - 1; dy <= r + 1; ++dy) {
            for (int dx = -r - 1; dx <= r + 1; ++dx) {
                if (std::lround(std::sqrt(double(dx * dx + dy * dy))) != r) continue;
                sum += sigma2 * std::pow(rho, std::abs(dx) + std::abs(dy));
                ++count;
            }
        }
        const double expected = sum / count - bias;
        CAPTURE(r, ring[r], expected, tol);
        CHECK(std::abs(ring[r] - expected) < tol);
    }
}

// ---------------------------------------------------------------------------------------------
// Temporal statistics

TEST_CASE("frame_stats of known frames", "[analysis]") {
    Image f0 = make_image(2, 2), f1 = make_image(2, 2);
    f0.data = {0, 1, 2, 3};
    f1.data = {1, 1, 1, 1};
    const std::vector<Image> frames = {f0, f1};
    const std::vector<FrameStats> s = frame_stats(frames);
    REQUIRE(s.size() == 2);
    CHECK(s[0].mean == 1.5);
    CHECK(s[0].variance == 1.25);
    CHECK(s[0].diff_variance == 0.0);
    CHECK(s[1].mean == 1.0);
    CHECK(s[1].variance == 0.0);
    CHECK(s[1].diff_variance == 1.25);  // f1 - f0 = {1, 0, -1, -2}: mean -1/2, var 5/4
}

TEST_CASE("block_means drops the remainder", "[analysis]") {
    std::vector<double> x;
    for (int i = 0; i < 11; ++i) x.push_back(i);
    CHECK(block_means(x, 3) == std::vector<double>{1.0, 4.0, 7.0});  // 9, 10 dropped
    CHECK(block_means(x, 1) == std::vector<double>{5.0});            // 0..10
}

TEST_CASE("trend of a linear series recovers the slope", "[analysis]") {
    std::vector<double> x;
    for (int i = 0; i < 1000; ++i) x.push_back(3.0 - 0.25 * i);
    const Trend t = trend(x);
    CHECK(t.slope == Approx(-0.25).epsilon(1e-12));
    // The block means lie on the line: the residual scatter is rounding only.
    CHECK(t.stderr_slope < 1e-12);
    CHECK(t.t < -1e6);
}

TEST_CASE("trend standard error from block means, by hand", "[analysis]") {
    // y = {0,0, 2,2, 1,1, 3,3, 100}, 4 blocks of L = 2 (the 100 is a remainder, dropped from the
    // blocks but not from the slope). Full OLS: ibar = 4, sum (i - 4) y_i = 410, Sxx = 60, so
    // slope = 41/6. Block means {0, 2, 1, 3} at centres {0.5, 2.5, 4.5, 6.5}: Scc = 20, fitted
    // slope 0.4, intercept 0.1, residuals {-0.3, 0.9, -0.9, 0.3}, s^2 = 1.8 / (4 - 2) = 0.9,
    // stderr = sqrt(0.9 / 20).
    const std::vector<double> y = {0, 0, 2, 2, 1, 1, 3, 3, 100};
    const Trend t = trend(y, 4);
    CHECK(t.slope == Approx(41.0 / 6.0).epsilon(1e-14));
    CHECK(t.stderr_slope == Approx(std::sqrt(0.045)).epsilon(1e-14));
    CHECK(t.t == Approx(41.0 / 6.0 / std::sqrt(0.045)).epsilon(1e-14));
}

TEST_CASE("trend of stationary white noise is insignificant", "[analysis][stats]") {
    // Under no trend, t = slope / stderr is close to Student t with blocks - 2 = 8 dof:
    // P(|t_8| > 4) = 0.004. The stderr itself is s * sqrt(12 / (n (n^2 - L^2))) with s^2 / sigma^2
    // ~ chi2_8 / 8, whose 1e-4 and 1 - 1e-4 quantiles are 0.075 and 4.0: so stderr over the
    // white-noise OLS error sigma sqrt(12 / (n (n^2 - 1))) lies in [0.27, 2.0] with B^2/(B^2-1)
    // ~ 1 (tested range [0.25, 2.1]).
    const int n = 10000;
    Gaussian g(4242);
    std::vector<double> x(n);
    for (double& v : x) v = g();
    const Trend t = trend(x, 10);
    CAPTURE(t.slope, t.stderr_slope, t.t);
    CHECK(std::abs(t.t) < 4.0);
    const double ols = std::sqrt(12.0 / (double(n) * (double(n) * n - 1.0)));
    CHECK(t.stderr_slope / ols > 0.25);
    CHECK(t.stderr_slope / ols < 2.1);
}

TEST_CASE("trend detects a weak trend in noise", "[analysis][stats]") {
    // Slope 20 sigma sqrt(12/n^3): a 20-sd trend. With stderr / sd in [0.27, 2.0] (above) and
    // the slope's own noise of 1 sd, t > 20/2 - 5 = 5 in all but a ~1e-4 tail.
    const int n = 10000;
    const double slope = 20.0 * std::sqrt(12.0 / (double(n) * n * n));
    Gaussian g(4243);
    std::vector<double> x(n);
    for (int i = 0; i < n; ++i) x[static_cast<size_t>(i)] = slope * i + g();
    CHECK(trend(x).t > 5.0);
}

TEST_CASE("spectral_drift: independent sets agree, a scaled set is detected", "[analysis][stats]") {
    // Null: every compared annulus (63 for 128x128) gives z ~ N(0, 1) (z is a difference of two
    // averages of (count/2) * frames exponentials). Bonferroni: P(max |z| > 4.5) <=
    // 63 * P(|Z| > 4.5) = 63 * 6.8e-6 = 4e-4; the smallest annulus (4 pairs x 4 frames = 16
    // exponentials per set) has a heavier tail than normal but not by orders of magnitude.
    // Scaled by 1.5: P_b = 2.25 P_a, so E z = -1.25 sqrt(m) / sqrt(2.25^2 + 1) = -0.51 sqrt(m),
    // m = pairs * frames; the outer annuli have m ~ 750, E z ~ -14.
    const int w = 128, h = 128, frames = 4;
    std::vector<Image> early, late, scaled;
    for (int f = 0; f < frames; ++f) {
        early.push_back(white_noise(w, h, 1.0, 1000 + f));
        late.push_back(white_noise(w, h, 1.0, 2000 + f));
        scaled.push_back(white_noise(w, h, 1.5, 3000 + f));
    }
    const SpectralDrift same = spectral_drift(early, late);
    REQUIRE(same.z.size() == 63);  // annuli 1..63; annulus 0 holds only DC
    REQUIRE(same.frequency.size() == same.z.size());
    for (size_t i = 0; i < same.frequency.size(); ++i) {
        CHECK(same.frequency[i] > 0.0);
        CHECK(same.frequency[i] < 0.5);
        if (i > 0) CHECK(same.frequency[i] > same.frequency[i - 1]);
    }
    CAPTURE(same.max_abs_z);
    CHECK(same.max_abs_z < 4.5);

    const SpectralDrift grown = spectral_drift(early, scaled);
    CHECK(grown.max_abs_z > 8.0);
    CHECK(*std::min_element(grown.z.begin(), grown.z.end()) == -grown.max_abs_z);
}

TEST_CASE("spectral_drift: z has unit variance under the null", "[analysis][stats]") {
    // Checks the variance model (count/2 independent values per annulus and frame), which the
    // max |z| bound above is too loose to see. 4 repetitions x 127 annuli of 256x256 with 2
    // frames per set: if z ~ N(0, 1), mean z^2 has sd sqrt(2/508) = 0.063; tolerance 5 sd =
    // 0.31. A simulation of the Gamma-distributed annulus means gives E[mean z^2] = 0.99
    // (self-normalisation; empirical) and the normal-theory sd. A factor-2 error in the
    // effective count would put mean z^2 near 0.5 or 2.
    const int n = 256, frames = 2, reps = 4;
    double sum_z2 = 0.0;
    size_t count = 0;
    for (int rep = 0; rep < reps; ++rep) {
        std::vector<Image> early, late;
        for (int f = 0; f < frames; ++f) {
            early.push_back(white_noise(n, n, 1.0, 5000 + 100 * rep + f));
            late.push_back(white_noise(n, n, 1.0, 6000 + 100 * rep + f));
        }
        const SpectralDrift d = spectral_drift(early, late);
        REQUIRE(d.z.size() == 127);
        for (double z : d.z) sum_z2 += z * z;
        count += d.z.size();
    }
    const double mean_z2 = sum_z2 / double(count);
    CHECK(std::abs(mean_z2 - 1.0) < 5.0 * std::sqrt(2.0 / double(count)));
}

// ---------------------------------------------------------------------------------------------
// Errors and determinism

TEST_CASE("invalid input throws ValueError", "[analysis]") {
    using Catch::Matchers::Contains;
    const std::vector<float> none;
    const std::vector<float> some = {1.0f, 2.0f};
    CHECK_THROWS_AS(moments(none), ValueError);
    CHECK_THROWS_WITH(histogram(some, 0.0, 1.0, 0), Contains("bins = 0"));
    CHECK_THROWS_AS(histogram(some, 1.0, 1.0, 4), ValueError);
    CHECK_THROWS_AS(ks_distance(none, uniform_cdf, nullptr), ValueError);
    CHECK_THROWS_AS(ks_distance(some, nullptr, nullptr), ValueError);

    Image empty;
    Image short_data = make_image(4, 4);
    short_data.data.pop_back();
    CHECK_THROWS_AS(periodogram(empty), ValueError);
    CHECK_THROWS_WITH(periodogram(short_data), Contains("15 values, expected 16"));
    CHECK_THROWS_AS(periodogram(make_image(1, 8), Window::Hann), ValueError);
    CHECK_THROWS_AS(autocovariance(empty), ValueError);

    CHECK_THROWS_AS(average(std::vector<Periodogram>{}), ValueError);
    const std::vector<Periodogram> mixed = {periodogram(make_image(4, 4)),
                                            periodogram(make_image(4, 2))};
    CHECK_THROWS_AS(average(mixed), ValueError);
    Periodogram broken;
    broken.width = 4;
    broken.height = 4;
    CHECK_THROWS_AS(radial_average(broken), ValueError);

    const std::vector<double> acov(16, 0.0);
    CHECK_THROWS_AS(radial_autocovariance(acov, 4, 3, 1), ValueError);
    CHECK_THROWS_AS(radial_autocovariance(acov, 4, 4, -1), ValueError);
    CHECK_THROWS_AS(radial_autocovariance(acov, 4, 4, 3), ValueError);

    CHECK_THROWS_AS(frame_stats(std::vector<Image>{}), ValueError);
    CHECK_THROWS_AS(frame_stats(std::vector<Image>{make_image(4, 4), make_image(4, 3)}),
                    ValueError);

    const std::vector<double> series(20, 1.0);
    CHECK_THROWS_AS(block_means(series, 0), ValueError);
    CHECK_THROWS_AS(block_means(series, 21), ValueError);
    CHECK_THROWS_WITH(trend(series, 2), Contains("blocks = 2"));
    CHECK_THROWS_AS(trend(std::vector<double>(5, 1.0), 10), ValueError);

    const std::vector<Image> a = {make_image(8, 8)}, b = {make_image(8, 4)};
    CHECK_THROWS_AS(spectral_drift(a, std::vector<Image>{}), ValueError);
    CHECK_THROWS_AS(spectral_drift(a, b), ValueError);
}

TEST_CASE("periodogram and autocovariance are bit-identical across threads",
          "[analysis][determinism]") {
    // Concurrent calls exercise the planner lock; results must match a serial run exactly.
    const Image im = white_noise(96, 80, 1.0, 55);
    const Periodogram ref_p = periodogram(im, Window::Hann);
    const std::vector<double> ref_a = autocovariance(im);
    constexpr int kThreads = 6;
    std::vector<Periodogram> ps(kThreads);
    std::vector<std::vector<double>> as(kThreads);
    std::vector<std::thread> pool;
    for (int i = 0; i < kThreads; ++i) {
        pool.emplace_back([&, i] {
            for (int rep = 0; rep < 20; ++rep) {
                ps[static_cast<size_t>(i)] = periodogram(im, Window::Hann);
                as[static_cast<size_t>(i)] = autocovariance(im);
            }
        });
    }
    for (std::thread& t : pool) t.join();
    for (int i = 0; i < kThreads; ++i) {
        CHECK(ps[static_cast<size_t>(i)].power == ref_p.power);
        CHECK(as[static_cast<size_t>(i)] == ref_a);
    }
}
