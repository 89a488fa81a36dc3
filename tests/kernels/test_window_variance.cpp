// SPDX-License-Identifier: Apache-2.0
// The impulse population's share of the scatter of a frame's sample variance
// (kernels/window_variance.h): the FFT correlation against a direct sum over the window's
// pixels, its limit (int h^2)^2 / N for kernels small against the window, and the variance of
// simulated frames' sample variances against lambda E[m^4] int A^2 plus the Gaussian part.

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "kernels/kernels.h"

namespace {

using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelType;

Kernel gaussian(double sigma) {
    KernelParams p;
    p.type = KernelType::Gaussian;
    p.sigma = sigma;
    p.radius = 3.0 * sigma;
    return Kernel(p);
}

/// int A(u)^2 du by the definition: for each sub-pixel phase and each u of the integer grid
/// that any pixel's kernel reaches, A(u) = (1/N) sum_i h(x_i - u)^2 - hbar(u)^2 summed over the
/// pixels one by one (the taps h(t - phase) tabulated once per phase).
double direct_integral(const Kernel& k, double zoom, int w, int h) {
    const double R = k.radius() * zoom;
    const int r = int(std::ceil(R)) + 1, s = impulse::kernels::window_population_phases(R, w, h);
    const int taps = 2 * r + 1;
    const double N = double(w) * h;
    double total = 0.0;
    for (int q = 0; q < s; ++q)
        for (int p = 0; p < s; ++p) {
            std::vector<double> g(size_t(taps) * taps);
            for (int b = 0; b < taps; ++b)
                for (int a = 0; a < taps; ++a)
                    g[size_t(b) * taps + a] =
                        k.evaluate((a - r - double(p) / s) / zoom, (b - r - double(q) / s) / zoom);
            for (int my = -r; my < h + r; ++my)
                for (int mx = -r; mx < w + r; ++mx) {
                    double s1 = 0.0, s2 = 0.0;
                    for (int y = std::max(0, my - r); y < std::min(h, my + r + 1); ++y)
                        for (int x = std::max(0, mx - r); x < std::min(w, mx + r + 1); ++x) {
                            const double v = g[size_t(y - my + r) * taps + (x - mx + r)];
                            s1 += v;
                            s2 += v * v;
                        }
                    const double A = s2 / N - (s1 / N) * (s1 / N);
                    total += A * A;
                }
        }
    return total / (double(s) * s);
}

/// The formula for kernels small against the window: (int h^2)^2 / N, pixel units.
double small_kernel_limit(const Kernel& k, double zoom, int w, int h) {
    const double i2 = k.integral_sq() * zoom * zoom;
    return i2 * i2 / (double(w) * h);
}

}  // namespace

TEST_CASE("window population integral: FFT correlation equals the direct sum over pixels",
          "[kernels][stats]") {
    // Kernels from a pixel and a half (four sub-pixel phases per axis) to wider than the window.
    struct Case { double sigma, zoom; int w, h; };
    for (const Case c : {Case{0.5, 1.0, 32, 32}, Case{1.5, 1.0, 32, 32}, Case{4.0, 1.0, 32, 24},
                         Case{12.0, 1.0, 32, 32}, Case{20.0, 2.0, 24, 32}}) {
        const Kernel k = gaussian(c.sigma);
        const double fft = impulse::kernels::window_population_integral(k, c.zoom, c.w, c.h);
        const double direct = direct_integral(k, c.zoom, c.w, c.h);
        INFO("sigma " << c.sigma << " zoom " << c.zoom << ": FFT " << fft << ", direct " << direct);
        CHECK(fft == Approx(direct).epsilon(1e-9));
    }
}

TEST_CASE("window population integral: the small-kernel limit and far below it for wide kernels",
          "[kernels][stats]") {
    // A 256^2 window: the border strip a kernel overhangs is about 4 R / 256 of the area, so a
    // kernel of sigma 1.5 pixels is within 3 % of (int h^2)^2 / N, below it. A kernel narrower
    // than a pixel puts more into the pixel it lands on than between pixels: the lattice sum
    // sum_n h^2(n - u) varies with the sub-pixel position u, and its mean square is
    // (int h^2)^2 sum_k |FT(h^2)(k)|^2 / (int h^2)^2 = (int h^2)^2 theta^2,
    // theta = sum_k exp(-2 pi^2 sigma^2 k^2) (Poisson summation, k over the integers), 1.80 for
    // sigma 0.3 (8 phases per axis), 1 to 1e-19 for sigma 1.5.
    for (double sigma : {0.3, 1.5}) {
        const Kernel k = gaussian(sigma);
        double theta = 0.0;
        for (int j = -10; j <= 10; ++j)
            theta += std::exp(-2.0 * std::numbers::pi * std::numbers::pi * sigma * sigma * j * j);
        const double ratio = impulse::kernels::window_population_integral(k, 1.0, 256, 256) /
                             (small_kernel_limit(k, 1.0, 256, 256) * theta * theta);
        INFO("sigma " << sigma << ": ratio to (int h^2)^2 theta^2 / N " << ratio);
        CHECK(ratio < 1.005);  // the truncation at 3 sigma moves theta by less
        CHECK(ratio > 0.97);
    }
    // sigma 120 in drift's 192^2 analysis window: the frame mean takes most of each impulse (the
    // calibration's finding: 183 times smaller than the small-kernel formula).
    const Kernel wide = gaussian(120.0);
    const double ratio = impulse::kernels::window_population_integral(wide, 1.0, 192, 192) /
                         small_kernel_limit(wide, 1.0, 192, 192);
    INFO("sigma 120 in 192^2: ratio " << ratio);
    CHECK(ratio < 1.0 / 100.0);
}

namespace {

/// Var(V) for Gaussian fields, 2 (lambda E[m^2])^2 int int Q^2 = 2 (lambda E[m^2])^2
/// ||P C P||_F^2 / N^2 with C_ij = (h * h~)(x_i - x_j) and P the centring projector, expanded as
/// sum C_ij^2 - (2 / N) sum_i r_i^2 + (sum_i r_i)^2 / N^2, r_i = sum_j C_ij. h * h~ is the
/// untruncated Gaussian's pi sigma^2 exp(-tau^2 / (4 sigma^2)): the cut at 3 sigma holds
/// exp(-9) = 1.2e-4 of int h^2, far below the test's tolerance (Kernel::autocorrelation's
/// quadrature would take a minute for the 63^2 lags).
double gaussian_part(const Kernel& k, int w, double lambda) {
    const double sigma = k.params().sigma;
    const int n = w * w;
    std::vector<double> c(size_t(2 * w - 1) * (2 * w - 1));
    for (int dy = -(w - 1); dy < w; ++dy)
        for (int dx = -(w - 1); dx < w; ++dx)
            c[size_t(dy + w - 1) * (2 * w - 1) + (dx + w - 1)] =
                std::numbers::pi * sigma * sigma *
                std::exp(-(dx * dx + dy * dy) / (4.0 * sigma * sigma));
    double sum_sq = 0.0, sum_r2 = 0.0, sum_r = 0.0;
    for (int i = 0; i < n; ++i) {
        double r = 0.0;
        for (int j = 0; j < n; ++j) {
            const int dx = j % w - i % w, dy = j / w - i / w;
            const double v = c[size_t(dy + w - 1) * (2 * w - 1) + (dx + w - 1)];
            r += v;
            sum_sq += v * v;
        }
        sum_r2 += r * r;
        sum_r += r;
    }
    const double norm = sum_sq - 2.0 * sum_r2 / n + sum_r * sum_r / (double(n) * n);
    return 2.0 * lambda * lambda * norm / (double(n) * n);
}

/// Means and sample variances (1/N normalisation) of `count` w x w frames of random-sign shot
/// noise with intensity lambda per pixel^2, impulses in the window grown by the kernel's radius.
std::vector<std::array<double, 2>> simulated_moments(const Kernel& k, int w, double lambda,
                                                     int count, unsigned seed) {
    std::mt19937_64 rng(seed);
    const double R = k.radius(), side = w - 1 + 2 * R;
    std::poisson_distribution<int> impulses(lambda * side * side);
    std::uniform_real_distribution<double> position(-R, w - 1 + R);
    std::vector<std::array<double, 2>> out;
    std::vector<double> f(size_t(w) * w);
    for (int t = 0; t < count; ++t) {
        std::fill(f.begin(), f.end(), 0.0);
        for (int j = impulses(rng); j > 0; --j) {
            const double px = position(rng), py = position(rng);
            const double sign = (rng() & 1) ? 1.0 : -1.0;
            for (int y = 0; y < w; ++y)
                for (int x = 0; x < w; ++x)
                    f[size_t(y) * w + x] += sign * k.evaluate(x - px, y - py);
        }
        double mean = 0.0, var = 0.0;
        for (double v : f) mean += v / f.size();
        for (double v : f) var += (v - mean) * (v - mean) / f.size();
        out.push_back({mean, var});
    }
    return out;
}

std::vector<double> simulated_variances(const Kernel& k, int w, double lambda, int count,
                                        unsigned seed) {
    std::vector<double> out;
    for (const auto& m : simulated_moments(k, w, lambda, count, seed)) out.push_back(m[1]);
    return out;
}

}  // namespace

TEST_CASE("window population integral: simulated frames' variance scatter matches it",
          "[kernels][stats][slow]") {
    // 32^2 frames of random-sign Gaussian impulses (E[m^2] = E[m^4] = 1), sparse enough that
    // the population term is most of Var(V). The estimate of Var(V) from n frames has the
    // standard error sqrt((m4 - s^4) / n) (m4: the fourth central moment of V, from the same
    // frames); the closed form must lie within 4 of them. The small-kernel formula
    // lambda (int h^2)^2 / N lies outside for both: 16 standard errors for sigma 3 (a 32^2
    // window's border strip is wide against it), far more for sigma 24 (wider than the window).
    const int w = 32, n = 20000;
    struct Case { double sigma, lambda; };
    for (const Case c : {Case{3.0, 4e-3}, Case{24.0, 6e-5}}) {
        const Kernel k = gaussian(c.sigma);
        const std::vector<double> v = simulated_variances(k, w, c.lambda, n, 18u);
        double mean = 0.0;
        for (double x : v) mean += x / n;
        double s2 = 0.0, m4 = 0.0;
        for (double x : v) {
            s2 += (x - mean) * (x - mean) / (n - 1);
            m4 += std::pow(x - mean, 4) / n;
        }
        const double se = std::sqrt((m4 - s2 * s2) / n);
        const double gauss = gaussian_part(k, w, c.lambda);
        const double theory =
            gauss + c.lambda * impulse::kernels::window_population_integral(k, 1.0, w, w);
        const double old_theory = gauss + c.lambda * small_kernel_limit(k, 1.0, w, w);
        INFO("sigma " << c.sigma << ": Var(V) " << s2 << " +- " << se << ", closed form " << theory
                      << " (Gaussian part " << gauss << "), small-kernel formula " << old_theory);
        CHECK(std::abs(s2 - theory) < 4.0 * se);
        CHECK(std::abs(s2 - old_theory) > 4.0 * se);
    }
}

namespace {

/// Frames 0, d_1, d_2, ... of space-time shot noise in a w x w window: random-sign Gaussian
/// impulses (sigma, cut at 3 sigma) born as a Poisson process at beta = lambda / T per pixel^2 per
/// frame, each alive for T frames at full weight (a box envelope) and carried at v pixels per
/// frame. Returns each frame's sample variance, run after run (frames.size() values per run).
struct FlowSim {
    int w;
    double sigma, lambda, lifetime, vx, vy;
    std::vector<int> frames;

    std::vector<double> run(int runs, unsigned seed) const {
        std::mt19937_64 rng(seed);
        const double R = 3.0 * sigma, last = frames.back();
        // Positions at frame 0 that any frame's window reaches, births over (-T, last].
        const double x0 = -R - std::max(0.0, vx * last), x1 = w - 1 + R - std::min(0.0, vx * last);
        const double y0 = -R - std::max(0.0, vy * last), y1 = w - 1 + R - std::min(0.0, vy * last);
        std::poisson_distribution<int> count(lambda / lifetime * (x1 - x0) * (y1 - y0) *
                                             (lifetime + last));
        std::uniform_real_distribution<double> ux(x0, x1), uy(y0, y1), ub(-lifetime, last);
        std::vector<double> out;
        std::vector<std::vector<double>> f(frames.size(), std::vector<double>(size_t(w) * w));
        for (int r = 0; r < runs; ++r) {
            for (auto& g : f) std::fill(g.begin(), g.end(), 0.0);
            for (int j = count(rng); j > 0; --j) {
                const double qx = ux(rng), qy = uy(rng), b = ub(rng);
                const double a = (rng() & 1) ? 1.0 : -1.0;
                for (size_t t = 0; t < frames.size(); ++t)
                    if (b <= frames[t] && b > frames[t] - lifetime)
                        splat(f[t], qx + vx * frames[t], qy + vy * frames[t], a, R);
            }
            for (const auto& g : f) out.push_back(variance(g));
        }
        return out;
    }
    void splat(std::vector<double>& g, double px, double py, double a, double R) const {
        for (int y = std::max(0, int(std::ceil(py - R))); y <= std::min(w - 1, int(py + R)); ++y)
            for (int x = std::max(0, int(std::ceil(px - R))); x <= std::min(w - 1, int(px + R));
                 ++x) {
                const double r2 = (x - px) * (x - px) + (y - py) * (y - py);
                if (r2 < R * R) g[size_t(y) * w + x] += a * std::exp(-r2 / (2.0 * sigma * sigma));
            }
    }
    static double variance(const std::vector<double>& g) {
        double mean = 0.0, v = 0.0;
        for (double x : g) mean += x / double(g.size());
        for (double x : g) v += (x - mean) * (x - mean) / double(g.size());
        return v;
    }
};

/// lambda |H|^2 of the Gaussian exp(-r^2 / 2 sigma^2) aliased onto a P x P DFT grid (images
/// |m| <= 2 per axis): |H(k)|^2 = 4 pi^2 sigma^4 exp(-4 pi^2 sigma^2 |k|^2).
std::vector<double> gaussian_grid(double sigma, double lambda, int P) {
    std::vector<double> g(size_t(P) * P, 0.0);
    const double pi2 = std::numbers::pi * std::numbers::pi;
    for (int ky = 0; ky < P; ++ky)
        for (int kx = 0; kx < P; ++kx) {
            const double fx = (kx <= P / 2 ? kx : kx - P) / double(P);
            const double fy = (ky <= P / 2 ? ky : ky - P) / double(P);
            for (int my = -2; my <= 2; ++my)
                for (int mx = -2; mx <= 2; ++mx) {
                    const double k2 = (fx + mx) * (fx + mx) + (fy + my) * (fy + my);
                    g[size_t(ky) * P + kx] += lambda * 4.0 * pi2 * std::pow(sigma, 4) *
                                              std::exp(-4.0 * pi2 * sigma * sigma * k2);
                }
        }
    return g;
}

/// 2 ||P C P||^2 / N^2 by the definition for C(x_i, x_j) = lambda (h * h~)(x_j - x_i - s) of the
/// untruncated Gaussian (pi sigma^2 exp(-tau^2 / 4 sigma^2)) at a fractional shift s.
double direct_shifted_gaussian(int w, double sigma, double lambda, double sx, double sy) {
    const int n = w * w;
    std::vector<double> C(size_t(n) * n), row(n, 0.0), col(n, 0.0);
    double total = 0.0, sum_sq = 0.0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
            const double dx = j % w - i % w - sx, dy = j / w - i / w - sy;
            const double c = lambda * std::numbers::pi * sigma * sigma *
                             std::exp(-(dx * dx + dy * dy) / (4.0 * sigma * sigma));
            row[i] += c, col[j] += c, total += c, sum_sq += c * c;
        }
    double r2 = 0.0, c2 = 0.0;
    for (int i = 0; i < n; ++i) r2 += row[i] * row[i], c2 += col[i] * col[i];
    return 2.0 * (sum_sq - (r2 + c2) / n + total * total / (double(n) * n)) / (double(n) * n);
}

}  // namespace

TEST_CASE(
    "frame variances under a uniform flow: Cov(V_0 V_d) with the window in the time correlation",
    "[kernels][stats]") {
    // 24^2 window, sigma 2, 0.01 impulses per pixel^2 alive, box lifetime 12 frames, carried at
    // (1.3, 0.45) pixels a frame: frame 4 is moved by (5.2, 1.8) and frame 8 by (10.4, 3.6)
    // pixels, almost half the window. Both impulse terms decorrelate with the box's overlap
    // 1 - d / T and with the window: the population term as int A(u) A(u + s) du, the Gaussian
    // term as 2 ||P C_d P||^2 / N^2, C_d the shifted covariance (kernels/window_variance.h).
    const FlowSim sim{24, 2.0, 0.01, 12.0, 1.3, 0.45, {0, 4, 8}};
    const int runs = 12000, n = int(sim.frames.size());
    const std::vector<double> v = sim.run(runs, 7u);
    const Kernel k = gaussian(sim.sigma);
    const int P = 64;  // holds the window (24) plus the reach (2 R = 12) plus the shift (11)
    impulse::kernels::WindowCovariance wc(sim.w, sim.w, P, P);
    wc.add(gaussian_grid(sim.sigma, sim.lambda, P));
    std::vector<std::array<double, 2>> shifts;
    for (int d : sim.frames) shifts.push_back({sim.vx * d, sim.vy * d});
    const std::vector<double> pop =
        impulse::kernels::window_population_correlation(k, 1.0, sim.w, sim.w, 1, shifts);
    const double gauss0 =
        wc.gaussian_term(std::vector<double>{1.0}, std::vector<std::array<int, 2>>{{0, 0}});
    for (int t = 1; t < n; ++t) {
        // Sample covariance of (V_0, V_d) over the runs and its standard error from the
        // products' own scatter.
        double m0 = 0.0, md = 0.0;
        for (int r = 0; r < runs; ++r) {
            m0 += v[size_t(r) * n] / runs;
            md += v[size_t(r) * n + t] / runs;
        }
        double c = 0.0, c2 = 0.0;
        for (int r = 0; r < runs; ++r) {
            const double p = (v[size_t(r) * n] - m0) * (v[size_t(r) * n + t] - md);
            c += p / runs;
            c2 += p * p / runs;
        }
        const double se = std::sqrt((c2 - c * c) / runs);
        const double overlap = 1.0 - sim.frames[t] / sim.lifetime;
        const double gauss = wc.gaussian_term(std::vector<double>{overlap},
                                              std::vector<std::array<double, 2>>{shifts[t]});
        const double theory = gauss + sim.lambda * overlap * pop[t];
        // The envelopes alone (the old model): the unshifted terms times the overlap.
        const double envelope_only = gauss0 * overlap * overlap + sim.lambda * overlap * pop[0];
        // Bilinear between integer shifts against the definition at the fractional one: the term
        // varies on the kernel's scale (sigma 2), so within a fraction of a percent.
        const double direct =
            overlap * overlap *
            direct_shifted_gaussian(sim.w, sim.sigma, sim.lambda, shifts[t][0], shifts[t][1]);
        INFO("d = " << sim.frames[t] << ": Cov(V_0, V_d) " << c << " +- " << se << ", closed form "
                    << theory << " (Gaussian " << gauss << ", by definition " << direct
                    << "), envelopes only " << envelope_only);
        CHECK(gauss == Approx(direct).epsilon(0.01));
        CHECK(std::abs(c - theory) < 4.0 * se);
        CHECK(std::abs(c - envelope_only) > 4.0 * se);
    }
}

TEST_CASE("frame mean over a window: Var(frame mean) is the window's sum of covariances",
          "[kernels][stats]") {
    // A Gaussian kernel (sigma 12, cut at 5 sigma so the cut is negligible) wider than the 24^2
    // window, 2e-4 random-sign impulses per pixel^2 (about 2 reach the window). Var(frame mean)
    // = (1/N^2) sum_ij C_ij and E[V] = C(0) - that; S(0) / N (exact only for frames periodic
    // over the window) is 3 times a pixel's variance here, which a mean of pixels cannot exceed.
    // Standard errors from the simulated frames' own fourth moments; the closed forms within 4.
    const int w = 24, n = 20000, P = 128;  // P holds the window plus the reach 2 R = 120
    const double sigma = 12.0, lambda = 2e-4;
    KernelParams p;
    p.type = KernelType::Gaussian;
    p.sigma = sigma;
    p.radius = 5.0 * sigma;
    const auto grid = gaussian_grid(sigma, lambda, P);
    impulse::kernels::WindowCovariance wc(w, w, P, P);
    wc.add(grid);
    // The definition: C_ij = lambda (h * h~)(x_j - x_i) of the untruncated Gaussian.
    double direct = 0.0;
    for (int i = 0; i < w * w; ++i)
        for (int j = 0; j < w * w; ++j) {
            const double dx = j % w - i % w, dy = j / w - i / w;
            direct += lambda * std::numbers::pi * sigma * sigma *
                      std::exp(-(dx * dx + dy * dy) / (4.0 * sigma * sigma));
        }
    direct /= double(w * w) * (w * w);
    CHECK(wc.frame_mean_variance() == Approx(direct).epsilon(1e-6));
    CHECK(wc.pixel_variance() == Approx(lambda * std::numbers::pi * sigma * sigma).epsilon(1e-6));

    const auto m = simulated_moments(Kernel(p), w, lambda, n, 5u);
    double mean_v = 0.0, var_m = 0.0, m4 = 0.0, var_v = 0.0;
    for (const auto& x : m) mean_v += x[1] / n;
    for (const auto& x : m) {
        var_m += x[0] * x[0] / n;  // the field's mean is 0: no degree of freedom lost
        m4 += std::pow(x[0], 4) / n;
        var_v += (x[1] - mean_v) * (x[1] - mean_v) / (n - 1);
    }
    const double se_var_m = std::sqrt((m4 - var_m * var_m) / n), se_mean_v = std::sqrt(var_v / n);
    const double periodic = grid[0] / double(w * w);
    const double expected_v = wc.pixel_variance() - wc.frame_mean_variance();
    INFO("Var(frame mean) " << var_m << " +- " << se_var_m << ", window sum "
                            << wc.frame_mean_variance() << ", S(0) / N " << periodic << "; E[V] "
                            << mean_v << " +- " << se_mean_v << ", closed form " << expected_v
                            << ", with S(0) / N " << wc.pixel_variance() - periodic);
    CHECK(std::abs(var_m - wc.frame_mean_variance()) < 4.0 * se_var_m);
    CHECK(std::abs(var_m - periodic) > 4.0 * se_var_m);
    CHECK(std::abs(mean_v - expected_v) < 4.0 * se_mean_v);
}
