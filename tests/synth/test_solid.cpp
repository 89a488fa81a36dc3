// SPDX-License-Identifier: Apache-2.0
// Solid noise (issue 17 item 5): Campbell's mean and variance in 3-D and 4-D, the spectrum
// along lines against the projection of lambda E[a^2] |H(k)|^2, isotropy (sparse within its
// band, Perlin's anisotropy reported), points equal to the grid path bit for bit whatever the
// order or thread count, independent vector components, the metric, Wiener interpolation's
// realized variance against its confidence measure and the lattice-compatibility refusal,
// 2-D slices against the 3-D autocovariance, and a slice's impulses (slice_impulses) summing to it.

#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "numeric/errors.h"
#include "synth/synth.h"

using namespace impulse;
using synth::SolidPoint;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kZ = 5.0;  // |z| beyond which a check fails (two-sided 6e-7 per check)

synth::SolidParams cosine(double R, double density, int dims = 3) {
    synth::SolidParams p;
    p.kernel.radius = R;
    p.density = density;
    p.dims = dims;
    p.seed = 7;
    return p;
}

/// Points on a lattice of spacing 2R + 1: their values are independent (the kernel reaches R).
std::vector<SolidPoint> independent_points(int n_side, double R, double t = 0.0) {
    std::vector<SolidPoint> pts;
    const double s = 2.0 * R + 1.0;
    for (int k = 0; k < n_side; ++k)
        for (int j = 0; j < n_side; ++j)
            for (int i = 0; i < n_side; ++i) pts.push_back({i * s + 0.37, j * s - 0.21, k * s + 0.11, t + 0.3 * k});
    return pts;
}

struct Moments {
    double mean = 0, var = 0, se_mean = 0, se_var = 0;
};
/// Sample mean and variance with their standard errors from the sample's own fourth moment.
Moments moments(const std::vector<float>& v) {
    const double n = double(v.size());
    double s = 0;
    for (float x : v) s += x;
    Moments m;
    m.mean = s / n;
    double s2 = 0, s4 = 0;
    for (float x : v) {
        const double d = x - m.mean;
        s2 += d * d, s4 += d * d * d * d;
    }
    m.var = s2 / (n - 1);
    m.se_mean = std::sqrt(m.var / n);
    m.se_var = std::sqrt((s4 / n - m.var * m.var) / n);
    return m;
}

void check_campbell(const synth::SolidParams& p) {
    const synth::SolidNoise noise(p);
    const auto pts = independent_points(36, p.kernel.radius);
    std::vector<float> v;
    noise.evaluate(pts, v);
    const Moments m = moments(v);
    const auto th = noise.theory();
    INFO("kernel " << kernels::to_string(p.kernel.type) << " dims " << p.dims << ": mean " << m.mean
                   << " +- " << m.se_mean << ", variance " << m.var << " +- " << m.se_var
                   << ", Campbell " << th.variance);
    CHECK(std::abs(m.mean - th.mean) <= kZ * m.se_mean);
    CHECK(std::abs(m.var - th.variance) <= kZ * m.se_var);
}

}  // namespace

TEST_CASE("solid noise: mean and variance follow Campbell's theorem in 3-D and 4-D", "[synth][solid][stats]") {
    check_campbell(cosine(3.0, 16.0));
    check_campbell(cosine(3.0, 2.0));
    synth::SolidParams g = cosine(3.0, 16.0);
    g.kernel.type = kernels::KernelType::Gaussian;
    g.kernel.sigma = 1.0;
    check_campbell(g);
    synth::SolidParams gb = cosine(3.0, 16.0);
    gb.kernel.type = kernels::KernelType::Gabor;
    gb.kernel.frequency = 0.4;
    check_campbell(gb);
    check_campbell(cosine(3.0, 16.0, 4));
}

TEST_CASE("solid noise: a 10 % error in the theory's variance is caught", "[synth][solid][stats]") {
    // Guards check_campbell's band: the same samples against 0.9 x Campbell fail.
    const synth::SolidNoise noise(cosine(3.0, 16.0));
    std::vector<float> v;
    noise.evaluate(independent_points(36, 3.0), v);
    const Moments m = moments(v);
    CHECK(std::abs(m.var - 0.9 * noise.theory().variance) > kZ * m.se_var);
}

namespace {

/// |DFT|^2 / N of lines of N samples along x, averaged over lines spaced 2R + 1 apart in y, z.
std::vector<double> line_periodogram(const synth::SolidNoise& noise, int N, int lines_side) {
    const double s = 2.0 * noise.kernel().radius() + 1.0;
    std::vector<SolidPoint> pts;
    for (int c = 0; c < lines_side; ++c)
        for (int b = 0; b < lines_side; ++b)
            for (int i = 0; i < N; ++i) pts.push_back({double(i), b * s, c * s, 0.0});
    std::vector<float> v;
    noise.evaluate(pts, v);
    std::vector<double> P(N / 2 + 1, 0.0);
    const int L = lines_side * lines_side;
    // Hann taper (leakage from the peak would bias the tail), normalised by sum w^2.
    std::vector<double> w(N);
    double w2 = 0;
    for (int i = 0; i < N; ++i) w[i] = 0.5 - 0.5 * std::cos(2 * kPi * i / N), w2 += w[i] * w[i];
    for (int l = 0; l < L; ++l) {
        const float* x = v.data() + size_t(l) * N;
        for (int f = 0; f <= N / 2; ++f) {
            double re = 0, im = 0;
            for (int i = 0; i < N; ++i) {
                re += w[i] * x[i] * std::cos(2 * kPi * f * i / N);
                im -= w[i] * x[i] * std::sin(2 * kPi * f * i / N);
            }
            P[f] += (re * re + im * im) / w2 / L;
        }
    }
    return P;
}

/// The 1-D spectrum of a line through isotropic 3-D noise, S1(k) = 2 pi int_k^inf S3(k') k' dk'
/// (the projection of S3 onto one axis), aliased at unit sample spacing; S3 tabulated once.
struct LineSpectrum {
    static constexpr double kDk = 0.002, kTop = 8.0;
    std::vector<double> tail;  // tail[i] = 2 pi int_{i dk}^top S3(k) k dk
    explicit LineSpectrum(const synth::SolidNoise& noise) {
        const int n = int(kTop / kDk);
        tail.assign(n + 1, 0.0);
        for (int i = n - 1; i >= 0; --i) {
            const double k = (i + 0.5) * kDk;
            tail[i] = tail[i + 1] + 2 * kPi * noise.radial_power_spectrum(k) * k * kDk;
        }
    }
    double S1(double k) const {
        const double x = std::abs(k) / kDk;
        const int i = std::min(int(x), int(tail.size()) - 2);
        return tail[i] + (x - i) * (tail[i + 1] - tail[i]);
    }
    double operator()(double k) const {
        double a = 0;
        for (int m = -3; m <= 3; ++m) a += S1(k + m);
        return a;
    }
};

}  // namespace

TEST_CASE("solid noise: spectrum along lines is the projection of lambda E[a^2] |H|^2", "[synth][solid][stats]") {
    const synth::SolidNoise noise(cosine(4.0, 16.0));
    const LineSpectrum line_spectrum(noise);
    const int N = 128, side = 32, L = side * side;
    const auto P = line_periodogram(noise, N, side);
    double peak = 0;
    for (int f = 1; f < N / 2; ++f) peak = std::max(peak, line_spectrum(double(f) / N));
    int checked = 0;
    double chi = 0;
    for (int f = 1; f + 6 < N / 2; f += 8) {
        // Bins f, f+2, f+4, f+6 pooled: each bin's average over L lines has relative sd
        // 1 / sqrt(L) (chi^2_2 per line); Hann-tapered bins two apart are nearly uncorrelated.
        double meas = 0, theo = 0;
        for (int j = f; j < f + 8; j += 2) meas += P[j], theo += line_spectrum(double(j) / N);
        if (theo < 0.01 * 4 * peak) continue;
        const double z = (meas - theo) / (theo / std::sqrt(4.0 * L));
        INFO("bins " << f << ".." << f + 3 << ": measured " << meas << ", theory " << theo << ", z " << z);
        CHECK(std::abs(z) <= kZ);
        chi += z * z;
        ++checked;
    }
    CHECK(checked >= 4);
    INFO("chi^2 = " << chi << " over " << checked << " pooled bins");
    CHECK(chi <= checked + kZ * std::sqrt(2.0 * checked));
}

namespace {

/// Variogram E[(f(x + tau e) - f(x))^2] / 2 along the three axes and the four body diagonals
/// at |tau| = tau, from pairs far apart; returns {axes, diagonals, standard error of the ratio}.
template <class Noise>
std::array<double, 3> axis_vs_diagonal(const Noise& eval, double tau, double spacing, int side) {
    const double e = 1.0 / std::sqrt(3.0);
    const std::array<std::array<double, 3>, 7> dirs = {
        {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {e, e, e}, {e, e, -e}, {e, -e, e}, {-e, e, e}}};
    std::vector<SolidPoint> base;
    for (int k = 0; k < side; ++k)
        for (int j = 0; j < side; ++j)
            for (int i = 0; i < side; ++i)
                base.push_back({i * spacing + 0.123 * k, j * spacing + 0.311 * i, k * spacing + 0.177 * j, 0});
    std::vector<float> v0, v1;
    eval(base, v0);
    std::array<double, 2> sum{}, sum2{};
    std::array<double, 2> count{};
    for (size_t d = 0; d < dirs.size(); ++d) {
        std::vector<SolidPoint> moved = base;
        for (auto& p : moved) p.x += tau * dirs[d][0], p.y += tau * dirs[d][1], p.z += tau * dirs[d][2];
        eval(moved, v1);
        const int c = d < 3 ? 0 : 1;
        for (size_t i = 0; i < base.size(); ++i) {
            const double g = 0.5 * double(v1[i] - v0[i]) * double(v1[i] - v0[i]);
            sum[c] += g, sum2[c] += g * g, count[c] += 1;
        }
    }
    const double a = sum[0] / count[0], b = sum[1] / count[1];
    const double va = (sum2[0] / count[0] - a * a) / count[0], vb = (sum2[1] / count[1] - b * b) / count[1];
    // Ratio's standard error by the delta method (pairs from the same base point in different
    // directions are correlated: counted as independent, the band is a little narrow).
    const double se = (a / b) * std::sqrt(va / (a * a) + vb / (b * b));
    return {a, b, se};
}

}  // namespace

TEST_CASE("solid noise: isotropic within its band (Perlin's ratio reported)", "[synth][solid][stats]") {
    const synth::SolidNoise noise(cosine(4.0, 16.0));
    const auto sp = axis_vs_diagonal(
        [&](const auto& p, auto& v) { noise.evaluate(p, v); }, 4.0, 9.0, 24);
    INFO("sparse: axes " << sp[0] << ", diagonals " << sp[1] << ", ratio " << sp[0] / sp[1] << " +- " << sp[2]);
    CHECK(std::abs(sp[0] / sp[1] - 1.0) <= kZ * sp[2]);

    synth::LatticeParams lp;
    lp.method = synth::LatticeMethod::Perlin;
    lp.spacing = 4.0;
    const synth::LatticeNoise perlin(lp);
    const auto pe = axis_vs_diagonal(
        [&](const auto& p, auto& v) { perlin.evaluate(p, v); }, 4.0, 9.0, 24);
    WARN("Perlin (lattice spacing 4, lag 4): variogram along the axes / along the diagonals = "
         << pe[0] / pe[1] << " +- " << pe[2]);
    // The check can see anisotropy: noise squeezed to half along z (metric diag(1, 1, 2)) fails it.
    synth::SolidParams q = cosine(4.0, 16.0);
    q.metric = {1, 0, 0, 0, 1, 0, 0, 0, 2};
    const synth::SolidNoise squeezed(q);
    const auto sq = axis_vs_diagonal(
        [&](const auto& p, auto& v) { squeezed.evaluate(p, v); }, 4.0, 9.0, 24);
    INFO("squeezed: ratio " << sq[0] / sq[1] << " +- " << sq[2]);
    CHECK(std::abs(sq[0] / sq[1] - 1.0) > kZ * sq[2]);
}

TEST_CASE("solid noise: points equal the grid bit for bit, in any order and thread count", "[synth][solid][determinism]") {
    // R = 3: the batches group by whole cells; R = 8: by half cells (many points per cell), while
    // a lone point still uses a whole cell: the same bits either way.
    for (const auto& [dims, R] : {std::pair{3, 3.0}, std::pair{4, 3.0}, std::pair{3, 8.0}}) {
        const synth::SolidNoise noise(cosine(R, 16.0, dims));
        const SolidPoint origin{-5.5, 2.25, -1.0, 0.75};
        const std::vector<float> g = noise.grid(20, 17, 13, origin);
        std::vector<SolidPoint> pts;
        for (int k = 0; k < 13; ++k)
            for (int j = 0; j < 17; ++j)
                for (int i = 0; i < 20; ++i) pts.push_back({origin.x + i, origin.y + j, origin.z + k, origin.t});
        std::vector<size_t> order(pts.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::mt19937 rng(3);
        std::shuffle(order.begin(), order.end(), rng);
        std::vector<SolidPoint> shuffled;
        for (size_t i : order) shuffled.push_back(pts[i]);
        std::vector<float> v1, v2;
        {
            tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
            noise.evaluate(shuffled, v1);
        }
        noise.evaluate(shuffled, v2);
        size_t differ = 0;
        for (size_t i = 0; i < order.size(); ++i) {
            differ += std::memcmp(&v1[i], &g[order[i]], 4) != 0;
            differ += std::memcmp(&v2[i], &g[order[i]], 4) != 0;
        }
        CHECK(differ == 0);
        // One point alone (its own batch) has the same bits too.
        CHECK(noise.evaluate(pts[123]) == g[123]);
        // The values are a real field (guards a vacuous pass on zeros).
        CHECK(moments(g).var > 0.1 * noise.theory().variance);
    }
}

TEST_CASE("solid noise: the brick grid equals the points bit for bit", "[synth][solid][determinism]") {
    // The grid path splats impulses into bricks of samples (diagonal metrics); the points take
    // the batch path. Cases: bricks cut within a cell (R = 20: 20 samples a cell, pieces of 8
    // in y and z), a diagonal stretch with a fractional spacing and origin, a gaussian kernel
    // (more terms), component 2, and a rotated metric (no bricks: the points path itself).
    struct Case {
        synth::SolidParams p;
        double spacing;
        int component;
    };
    std::vector<Case> cases;
    cases.push_back({cosine(20.0, 16.0), 1.0, 0});
    cases.push_back({cosine(4.0, 30.0), 0.37, 2});
    cases.back().p.metric = {1.7, 0, 0, 0, 0.6, 0, 0, 0, 2.3};
    cases.push_back({cosine(5.0, 16.0), 1.0, 1});
    cases.back().p.kernel.type = kernels::KernelType::Gaussian;
    cases.push_back({cosine(6.0, 16.0), 1.0, 0});
    cases.back().p.metric = {0.8, 0.6, 0, -0.6, 0.8, 0, 0, 0, 1};
    const SolidPoint origin{-13.3, 7.71, -2.05, 0.0};
    const int w = 45, h = 23, d = 19;
    for (const Case& c : cases) {
        const synth::SolidNoise noise(c.p);
        const std::vector<float> g = noise.grid(w, h, d, origin, c.spacing, c.component);
        std::vector<SolidPoint> pts;
        for (int k = 0; k < d; ++k)
            for (int j = 0; j < h; ++j)
                for (int i = 0; i < w; ++i)
                    pts.push_back({origin.x + i * c.spacing, origin.y + j * c.spacing, origin.z + k * c.spacing, 0.0});
        std::vector<float> v;
        noise.evaluate(pts, v, c.component);
        size_t differ = 0;
        for (size_t i = 0; i < v.size(); ++i) differ += std::memcmp(&v[i], &g[i], 4) != 0;
        INFO("radius " << c.p.kernel.radius << " spacing " << c.spacing);
        CHECK(differ == 0);
        CHECK(moments(g).var > 0.1 * noise.theory().variance);
    }
}

TEST_CASE("solid noise: vector components are independent noises", "[synth][solid][stats]") {
    const synth::SolidNoise noise(cosine(3.0, 16.0));
    const auto pts = independent_points(30, 3.0);
    std::vector<float> a, b;
    noise.evaluate(pts, a, 0);
    noise.evaluate(pts, b, 1);
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < a.size(); ++i) sab += a[i] * b[i], saa += a[i] * a[i], sbb += b[i] * b[i];
    const double r = sab / std::sqrt(saa * sbb);
    INFO("correlation of components 0 and 1: " << r);
    CHECK(std::abs(r) <= kZ / std::sqrt(double(a.size())));
    CHECK(a != b);
}

TEST_CASE("solid noise: a metric stretches the noise and keeps its variance", "[synth][solid][stats]") {
    // f(x) = g(M x), M = diag(1/2, 1, 1): f at (2 x, y, z) is g at (x, y, z), the same bits.
    synth::SolidParams p = cosine(3.0, 16.0);
    const synth::SolidNoise g(p);
    p.metric = {0.5, 0, 0, 0, 1, 0, 0, 0, 1};
    const synth::SolidNoise f(p);
    const auto pts = independent_points(12, 3.0);
    std::vector<SolidPoint> stretched = pts;
    for (auto& q : stretched) q.x *= 2.0;
    std::vector<float> vg, vf;
    g.evaluate(pts, vg);
    f.evaluate(stretched, vf);
    double diff = 0;
    for (size_t i = 0; i < vg.size(); ++i) diff = std::max(diff, double(std::abs(vg[i] - vf[i])));
    CHECK(diff <= 1e-5);
    CHECK(f.theory().variance == g.theory().variance);
    // Spectrum: S_f(k) = S_g(M^-T k) / |det M| = 2 S_g(2 kx, ky, kz).
    CHECK(f.power_spectrum(0.05, 0.02, 0.0) ==
          Approx(2.0 * g.power_spectrum(0.1, 0.02, 0.0)).epsilon(1e-9));
}

TEST_CASE("solid noise: a 2-D slice has the 3-D autocovariance at in-plane lags", "[synth][solid][stats]") {
    // The slice z = z0 of a field with covariance C(tau) has covariance C(tau_x, tau_y, 0):
    // C(r) = (2 / r) int S(k) sin(2 pi k r) k dk (the 3-D inverse transform of the radial S).
    const synth::SolidNoise noise(cosine(4.0, 16.0));
    auto C = [&](double r) {
        const int n = 4000;
        const double top = 3.0, dk = top / n;
        double s = 0;
        for (int i = 0; i < n; ++i) {
            const double k = (i + 0.5) * dk, x = 2 * kPi * k * r;
            s += noise.radial_power_spectrum(k) * k * k * (r == 0 ? 1.0 : std::sin(x) / x);
        }
        return 4 * kPi * s * dk;
    };
    CHECK(C(0.0) == Approx(noise.theory().variance).epsilon(2e-3));
    for (double lag : {1.0, 2.0, 3.0}) {
        // Pairs (x, x + lag e_x) in the plane z = 1.5, bases 9 apart: independent pairs.
        std::vector<SolidPoint> a, b;
        for (int j = 0; j < 80; ++j)
            for (int i = 0; i < 80; ++i) {
                a.push_back({i * 9.0, j * 9.0, 1.5, 0});
                b.push_back({i * 9.0 + lag, j * 9.0, 1.5, 0});
            }
        std::vector<float> va, vb;
        noise.evaluate(a, va);
        noise.evaluate(b, vb);
        double s = 0, s2 = 0;
        for (size_t i = 0; i < va.size(); ++i) {
            const double p = double(va[i]) * vb[i];
            s += p, s2 += p * p;
        }
        const double n = double(va.size()), m = s / n, se = std::sqrt((s2 / n - m * m) / n);
        INFO("lag " << lag << ": measured " << m << " +- " << se << ", theory " << C(lag));
        CHECK(std::abs(m - C(lag)) <= kZ * se);
    }
}

TEST_CASE("solid noise: a slice's impulses sum to the noise on the plane in 3-D and 4-D", "[synth][solid]") {
    // eta(x, y, z) = sum_i a_i h(sqrt(r_i^2 + d2_i)) over slice_impulses (docs/perspective.md
    // §10): the same impulses evaluate() sums, so the two agree to the batch path's float sums
    // and kernel polynomial; an impulse left out would cost a h(r) >= exp(-4.5) |a| within reach.
    for (int dims : {3, 4}) {
        synth::SolidParams p = cosine(4.0, 16.0, dims);
        p.kernel.type = kernels::KernelType::Gaussian;
        p.kernel.sigma = 4.0 / 3.0;
        const synth::SolidNoise noise(p);
        const double z = -7.3, t = dims == 4 ? 2.9 : 0.0;
        std::vector<std::array<int64_t, 2>> columns;
        for (int64_t cx = -3; cx <= 7; ++cx)  // the points' reach: x in [-6, 25.3], y in [-3, 19.5]
            for (int64_t cy = -3; cy <= 7; ++cy) columns.push_back({cx, cy});
        synth::SliceImpulses s;
        noise.slice_impulses(columns, z, t, s);
        REQUIRE(s.size() > 100);
        std::vector<SolidPoint> pts;
        for (int k = 0; k < 64; ++k) pts.push_back({0.37 * k - 2.0, 0.23 * k + 1.0, z, t});
        std::vector<float> values;
        noise.evaluate(pts, values);
        double worst = 0.0;
        for (size_t k = 0; k < pts.size(); ++k) {
            double sum = 0.0;
            for (size_t i = 0; i < s.size(); ++i) {
                const double dx = pts[k].x - s.x[i], dy = pts[k].y - s.y[i];
                sum += s.a[i] * noise.kernel().evaluate({dx, dy, std::sqrt(double(s.d2[i])), 0.0});
            }
            worst = std::max(worst, std::abs(sum - values[k]));
        }
        CAPTURE(dims, worst);
        CHECK(worst < 1e-5);  // measured 3.7e-7 (3-D) and 2.3e-7 (4-D)
    }
    synth::SolidParams p = cosine(4.0, 16.0);
    p.metric[0] = 2.0;
    synth::SliceImpulses s;
    CHECK_THROWS_WITH(synth::SolidNoise(p).slice_impulses({{0, 0}}, 0.0, 0.0, s),
                      Catch::Contains("identity metric"));
}

TEST_CASE("lattice noises: value noise variance, Wiener confidence, compatibility", "[synth][solid][lattice]") {
    synth::LatticeParams lp;
    lp.method = synth::LatticeMethod::Value;
    lp.spacing = 1.0;
    // Over many seeds the cell-averaged variance is (26/35)^3 E[v^2], E[v^2] = 1/3.
    double s = 0, s2 = 0;
    int n = 0;
    for (uint64_t seed = 0; seed < 40; ++seed) {
        lp.seed = seed;
        const synth::LatticeNoise value(lp);
        std::vector<SolidPoint> pts;
        for (int i = 0; i < 4000; ++i) pts.push_back({(i % 16) * 5.3, (i / 16 % 16) * 5.7, (i / 256) * 6.1, 0});
        std::vector<float> v;
        value.evaluate(pts, v);
        for (float x : v) s += x * x, s2 += double(x) * x * x * x, ++n;
        CHECK(value.mean_variance() == Approx(std::pow(26.0 / 35.0, 3) / 3.0).epsilon(1e-3));
    }
    const double m = s / n, se = std::sqrt((s2 / n - m * m) / n);
    INFO("value noise: E f^2 = " << m << " +- " << se);
    CHECK(std::abs(m - std::pow(26.0 / 35.0, 3) / 3.0) <= kZ * se);

    // Wiener: a covariance that vanishes at the lattice offsets (spherical, range 1) is
    // accepted; the realized variance at u is sum a_j^2 = C(0) - confidence (C = I).
    lp.method = synth::LatticeMethod::Wiener;
    lp.covariance = synth::wiener_covariance("spherical", 1.0);
    lp.neighbourhood = 4;
    const synth::LatticeNoise w(lp);
    for (const std::array<double, 3>& u : {std::array<double, 3>{0, 0, 0}, {0.5, 0.5, 0.5}, {0.25, 0.1, 0.7}}) {
        const auto a = w.weights(u);
        double sa = 0;
        for (double x : a) sa += x * x;
        CHECK(sa == Approx(1.0 - w.confidence(u)).margin(1e-9));
        // Measured over many realizations (seeds) at the same u.
        double sv = 0, sv2 = 0;
        const int R = 3000;
        for (int r = 0; r < R; ++r) {
            synth::LatticeParams q = lp;
            q.seed = 100 + r;
            const synth::LatticeNoise wr(q);
            const double x = wr.evaluate(SolidPoint{3 + u[0], -2 + u[1], 5 + u[2], 0});
            sv += x * x, sv2 += x * x * x * x;
        }
        const double mv = sv / R, sev = std::sqrt((sv2 / R - mv * mv) / R);
        INFO("u = (" << u[0] << ", " << u[1] << ", " << u[2] << "): realized variance " << mv << " +- "
                     << sev << ", C(0) - confidence " << sa);
        CHECK(std::abs(mv - sa) <= kZ * sev + 1e-6);
    }
    // At a lattice point the specified covariance is reproduced exactly (zero error).
    CHECK(w.confidence({0, 0, 0}) == Approx(0.0).margin(1e-9));
    CHECK(w.confidence({0.5, 0.5, 0.5}) > 0.1);

    // A covariance the lattice cannot realize is refused, saying why.
    lp.covariance = synth::wiener_covariance("gaussian", 1.0);
    REQUIRE_THROWS_WITH(synth::LatticeNoise(lp), Catch::Contains("C(1, 0, 0) = 0.367") &&
                                                     Catch::Contains("cannot realize"));
}
