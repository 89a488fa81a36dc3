// SPDX-License-Identifier: Apache-2.0
// The 3-D process's second-order statistics (docs/volume.md "Theory"): the frame variance of
// the unshaped density field against Campbell's theorem, and its stationarity in time in
// uniformly divergent 3-D flows, which needs the sqrt(J) weighting: each flow test runs with it
// on (must pass) and off (must fail), so the test is shown able to fail.

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <vector>

#include "volume/volume.h"

using namespace impulse;

namespace {

constexpr int kN = 48;            // grid edge, voxels
constexpr double kRadius = 6.0;   // cosine kernel radius, voxels
constexpr double kFps = 6.0;
constexpr double kLife = 1.0;     // seconds
const std::array<double, 3> kCentre = {kN / 2.0, kN / 2.0, kN / 2.0};

volume::CloudConfig config(std::shared_ptr<volume::Flow3> flow, bool jacobian) {
    volume::CloudConfig c;
    c.seed = 11;
    c.size = {kN, kN, kN};
    c.kernel.type = kernels::KernelType::Cosine;
    c.kernel.radius = kRadius;
    c.density = 8.0;
    c.octaves = 1;
    c.lifetime_s = kLife;
    c.fps = kFps;
    c.substeps = 2;
    c.jacobian = jacobian;
    c.flow = std::move(flow);
    c.shape.enabled = false;
    return c;
}

/// Second moment about the known mean 0 (zero-mean amplitudes) of one frame.
double frame_m2(const volume::DensityGrid& g) {
    double s = 0.0;
    for (float v : g.values) s += double(v) * v;
    return s / double(g.values.size());
}

/// Frame variances of frames 0, stride, 2 stride, ... (`count` of them), rendered in order.
std::vector<double> run(const volume::CloudConfig& c, int count, int stride) {
    volume::CloudVolume cloud(c);
    std::vector<double> v;
    for (int f = 0; f < count; ++f) v.push_back(frame_m2(cloud.field(int64_t(f) * stride)));
    return v;
}

struct Estimate {
    double mean = 0, sd = 0;  ///< of the values
    double se() const { return sd; }
};
/// Means of `blocks` consecutive blocks of `v`, then their mean and sample standard deviation.
Estimate blocks_of(const std::vector<double>& v, size_t blocks) {
    const size_t len = v.size() / blocks;
    std::vector<double> m(blocks, 0.0);
    for (size_t b = 0; b < blocks; ++b)
        for (size_t i = 0; i < len; ++i) m[b] += v[b * len + i] / double(len);
    Estimate e;
    e.mean = std::accumulate(m.begin(), m.end(), 0.0) / double(blocks);
    for (double x : m) e.sd += (x - e.mean) * (x - e.mean) / double(blocks - 1);
    e.sd = std::sqrt(e.sd);
    return e;
}

// Frames one lifetime apart share no impulse: their variances are independent draws. The mean of
// 40 such against a known value gives t with 39 degrees of freedom; |t| < 5.09 has P = 1e-5
// under the null (Student's t quantile, computed with mpmath's incomplete beta).
constexpr int kIndependent = 40;
constexpr double kT39 = 5.09;
// Block means of runs with 40 blocks: their variance ratio is F(39, 39) under the null, 0.999
// quantile 2.76 (the same computation).
constexpr double kF39 = 2.76;

}  // namespace

TEST_CASE("volume: frame variance of the 3-D field matches Campbell's theorem", "[volume][stats]") {
    // Campbell: lambda E[a^2] (int w^2 dt / T) int h^2 d^3x with lambda = 8 / (4/3 pi R^3),
    // E[a^2] = 1 (normal), int w^2 / T = 3/8 (Hann).
    const volume::CloudConfig c = config(nullptr, true);
    const double theory = volume::CloudVolume(c).theory().variance;
    const int stride = int(kLife * kFps);  // one lifetime: independent frames
    const std::vector<double> v = run(c, kIndependent, stride);
    const Estimate e = blocks_of(v, kIndependent);
    const double t = (e.mean - theory) / (e.sd / std::sqrt(double(kIndependent)));
    std::printf("[volume]   still: mean frame variance %.5f vs Campbell %.5f (%+.2f %%), t = %+.2f "
                "(band %.2f), one frame's sd %.1f %%\n",
                e.mean, theory, 100.0 * (e.mean / theory - 1.0), t, kT39, 100.0 * e.sd / theory);
    CHECK(std::abs(t) < kT39);
}

TEST_CASE("volume: uniform 3-D divergence keeps the frame variance only with sqrt(J)",
          "[volume][stats]") {
    // v = 0.15 (x - c): div v = 0.45/s, J = e^{0.45 age}. Without sqrt(J) the impulses thin out
    // by 1/J as they age: variance sigma^2 int w^2 e^{-0.45 a} da / int w^2 ~ 0.80 sigma^2.
    const int stride = int(kLife * kFps);
    const double theory = volume::CloudVolume(config(nullptr, true)).theory().variance;
    for (bool jacobian : {true, false}) {
        auto flow = std::shared_ptr<volume::Flow3>(volume::make_divergent_flow3(kCentre, 0.15));
        const std::vector<double> v = run(config(flow, jacobian), kIndependent, stride);
        const Estimate e = blocks_of(v, kIndependent);
        const double t = (e.mean - theory) / (e.sd / std::sqrt(double(kIndependent)));
        std::printf("[volume]   divergence 0.45/s, sqrt(J) %-3s: mean frame variance %.5f vs "
                    "Campbell %.5f (%+.1f %%), t = %+.2f (band %.2f)\n",
                    jacobian ? "on" : "off", e.mean, theory, 100.0 * (e.mean / theory - 1.0), t, kT39);
        if (jacobian)
            CHECK(std::abs(t) < kT39);
        else
            CHECK(t < -kT39);  // the mechanism is what keeps it in the band
    }
}

TEST_CASE("volume: pulsing 3-D divergence keeps block means steady only with sqrt(J)",
          "[volume][stats]") {
    // div v = 3 (0.25 sin(2 pi t / 4 s)), lifetime 1 s. Blocks of 2 s (12 frames) = half a
    // period, so an uncompensated pulse shows as block means alternating high and low. F = the
    // pulsing run's block-mean variance over a no-flow run's (same process, 40 blocks each):
    // F(39, 39) under the null. Without sqrt(J), J swings by ~e^{+-0.5} within a lifetime.
    constexpr int kBlocks = 40, kFrames = 480;
    const Estimate ref = blocks_of(run(config(nullptr, true), kFrames, 1), kBlocks);
    for (bool jacobian : {true, false}) {
        auto flow = std::shared_ptr<volume::Flow3>(
            volume::make_divergent_flow3(kCentre, 0.0, 0.25, 4.0));
        const Estimate b = blocks_of(run(config(flow, jacobian), kFrames, 1), kBlocks);
        const double F = (b.sd * b.sd) / (ref.sd * ref.sd);
        std::printf("[volume]   pulsing divergence, sqrt(J) %-3s: block-mean variance F = %.2f "
                    "(band %.2f); mean %.5f vs still %.5f\n",
                    jacobian ? "on" : "off", F, kF39, b.mean, ref.mean);
        if (jacobian)
            CHECK(F < kF39);
        else
            CHECK(F > kF39);
    }
}

TEST_CASE("volume: stretched, randomly turned kernels keep Campbell's variance times the aspect",
          "[volume][stats][orientation]") {
    // h(x) = k(|S^-1 R^T x|), S = diag(2.5, 1, 1): int h^2 d^3x = det S int k^2 = 2.5 int k^2
    // for every rotation R, so the variance is 2.5 times the radial kernel's (the same lambda).
    // Random axes (uniform on the sphere) test the rotation invariance. The same t test as
    // above (40 frames a lifetime apart, |t| < 5.09); shown able to fail: against the theory
    // that ignores the aspect (theory / 2.5) t is far outside the band, checked below.
    volume::CloudConfig c = config(nullptr, true);
    c.aspect = 2.5;
    c.orientation = sim::OrientationMode::Random;
    const double theory = volume::CloudVolume(c).theory().variance;
    const double radial = volume::CloudVolume(config(nullptr, true)).theory().variance;
    CHECK(theory == Approx(2.5 * radial).epsilon(1e-12));
    const std::vector<double> v = run(c, kIndependent, int(kLife * kFps));
    const Estimate e = blocks_of(v, kIndependent);
    const double se = e.sd / std::sqrt(double(kIndependent));
    const double t = (e.mean - theory) / se, t_radial = (e.mean - radial) / se;
    std::printf("[volume]   aspect 2.5, random axes: mean frame variance %.5f vs Campbell x aspect "
                "%.5f (%+.2f %%), t = %+.2f (band %.2f); against the radial theory t = %+.1f\n",
                e.mean, theory, 100.0 * (e.mean / theory - 1.0), t, kT39, t_radial);
    CHECK(std::abs(t) < kT39);
    CHECK(t_radial > kT39);  // the aspect is what the theory needs
}
