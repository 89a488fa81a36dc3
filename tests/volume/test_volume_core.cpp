// SPDX-License-Identifier: Apache-2.0
// The 3-D process's mechanics: the same bits for any thread count and frame order, births keyed
// by identity, and the curl-noise flow (divergence-free, its RMS speed from Campbell's theorem,
// its speed bound).

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "volume/volume.h"

using namespace impulse;

namespace {

volume::CloudConfig small_cloud() {
    volume::CloudConfig c;
    c.seed = 5;
    c.size = {40, 32, 24};
    c.kernel.radius = 10.0;
    c.density = 6.0;
    c.octaves = 2;
    c.lifetime_s = 1.0;
    c.fps = 12.0;
    auto sum = std::make_shared<volume::FlowSum3>();
    sum->push(volume::make_uniform_flow3({5.0, 0.0, 1.0}));
    sum->push(volume::make_curl_flow3(3, 12.0, 4.0));
    sum->push(volume::make_divergent_flow3({20, 16, 12}, 0.05));
    c.flow = sum;
    return c;
}

bool same_bits(const volume::DensityGrid& a, const volume::DensityGrid& b) {
    return a.size == b.size &&
           std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("volume: a frame has the same bits in any frame order and thread count",
          "[volume][determinism]") {
    volume::CloudVolume sequential(small_cloud());
    volume::DensityGrid last;
    for (int f = 0; f <= 7; ++f) last = sequential.density(f);  // steps particles on
    volume::CloudVolume direct(small_cloud());
    const volume::DensityGrid random_access = direct.density(7);  // integrates from birth
    CHECK(same_bits(last, random_access));
    double sum = 0;
    for (float v : last.values) sum += v;
    CHECK(sum > 0.0);  // not an empty cloud
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        volume::CloudVolume serial(small_cloud());
        CHECK(same_bits(serial.density(7), random_access));
    }
    // And a different frame is a different field.
    CHECK_FALSE(same_bits(direct.density(8), random_access));
}

TEST_CASE("volume: curl noise is divergence-free with its stated RMS speed", "[volume][flows]") {
    // v = curl psi: div v = 0 analytically; the central-difference divergence must be at the
    // level of the difference's truncation error (O(h^2) of |grad v|), far below |grad v|.
    const double s = 16.0, speed = 3.0;
    auto flow = volume::make_curl_flow3(9, s, speed);
    flow->prepare({-50, -50, -50, 250, 250, 250});
    std::mt19937_64 gen(4);
    std::uniform_real_distribution<double> U(0.0, 200.0);
    constexpr int kPoints = 100000;
    double sum2 = 0.0, worst = 0.0, div_rms = 0.0, grad_rms = 0.0;
    const double h = 1e-3;
    for (int i = 0; i < kPoints; ++i) {
        const double p[3] = {U(gen), U(gen), U(gen)};
        double v[3] = {0, 0, 0};
        flow->add(0.0, 1, &p[0], &p[1], &p[2], &v[0], &v[1], &v[2], nullptr);
        const double m2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        sum2 += m2;
        worst = std::max(worst, std::sqrt(m2));
        if (i % 100) continue;  // the divergence at every 100th point
        double d = 0.0;
        for (int a = 0; a < 3; ++a) {
            double q[2][3] = {{p[0], p[1], p[2]}, {p[0], p[1], p[2]}};
            q[0][a] -= h, q[1][a] += h;
            double w[2][3] = {};
            for (int k = 0; k < 2; ++k)
                flow->add(0.0, 1, &q[k][0], &q[k][1], &q[k][2], &w[k][0], &w[k][1], &w[k][2], nullptr);
            const double g = (w[1][a] - w[0][a]) / (2 * h);
            d += g;
            grad_rms += g * g;
        }
        div_rms += d * d;
    }
    const double rms = std::sqrt(sum2 / kPoints);
    // RMS of 10^5 correlated samples: the field decorrelates over ~s, so the 200^3 box holds
    // ~(200/16)^3 ~ 2000 independent regions: relative sd of the mean square ~ sqrt(2/2000) ~ 3 %
    // (E|v|^4 / (E|v|^2)^2 ~ 5/3 for a Gaussian 3-vector; 5 sd band = 15 % on |v|^2, 7.5 % on rms).
    INFO("rms " << rms << " worst " << worst << " div_rms " << std::sqrt(div_rms) << " grad "
                << std::sqrt(grad_rms));
    CHECK(std::abs(rms / speed - 1.0) < 0.075);
    CHECK(worst < 3.5 * speed);  // the flow's max_speed bound (kSpeedBound in volume/flows.cpp)
    CHECK(std::sqrt(div_rms) < 1e-4 * std::sqrt(grad_rms));
}

TEST_CASE("volume: the impulses of a frame do not depend on the view they are asked for",
          "[volume][determinism]") {
    // Births are keyed by (seed, octave, time cell, cell): a bigger view holds the smaller
    // view's impulses among its own.
    volume::Process3 p;
    p.intensity = 1e-3;
    p.cell_size = 8.0;
    p.lifetime_s = 1.0;
    p.fps = 10;
    auto flow = std::shared_ptr<volume::Flow3>(volume::make_uniform_flow3({3, 1, 0}));
    volume::Simulator3 a(p, flow, 8.0), b(p, flow, 8.0);
    volume::Impulses3 small, big;
    a.impulses_at(13, {0, 0, 0, 32, 32, 32}, small);
    b.impulses_at(13, {-40, -40, -40, 80, 80, 80}, big);
    REQUIRE(small.size() > 10);
    size_t found = 0;
    for (size_t i = 0; i < small.size(); ++i)
        for (size_t j = 0; j < big.size(); ++j)
            if (small.x[i] == big.x[j] && small.y[i] == big.y[j] && small.z[i] == big.z[j] &&
                small.weight[i] == big.weight[j]) {
                ++found;
                break;
            }
    CHECK(found == small.size());
}

TEST_CASE("volume: oriented, stretched frames have the same bits for any frame range and threads",
          "[volume][orientation][determinism]") {
    // docs/volume.md "Orientation": the axis is integrated on the positions' Heun steps, so a
    // frame range started anywhere, in any order, on one thread or many, gives the same bits.
    auto oriented = [](sim::OrientationMode mode) {
        volume::CloudConfig c = small_cloud();
        c.aspect = 2.5;
        c.orientation = mode;
        return c;
    };
    for (auto mode : {sim::OrientationMode::Vorticity, sim::OrientationMode::Flow,
                      sim::OrientationMode::Random}) {
        INFO("orientation " << sim::kOrientationModeNames[size_t(mode)]);
        volume::CloudVolume whole(oriented(mode));  // frames 0-9 as one range
        std::vector<volume::DensityGrid> one;
        for (int f = 0; f <= 9; ++f) one.push_back(whole.field(f));
        volume::CloudVolume first(oriented(mode)), second(oriented(mode));  // 0-4, then 5-9
        for (int f = 0; f <= 4; ++f) CHECK(same_bits(first.field(f), one[size_t(f)]));
        for (int f = 5; f <= 9; ++f) CHECK(same_bits(second.field(f), one[size_t(f)]));
        {
            tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
            volume::CloudVolume serial(oriented(mode));
            CHECK(same_bits(serial.field(9), one[9]));
            CHECK(same_bits(serial.field(3), one[3]));  // backwards: from birth again
        }
        CHECK_FALSE(same_bits(one[8], one[9]));
    }
    // A radial kernel (aspect 1) in any orientation is today's field, bit for bit (its axes are
    // not carried: docs/volume.md "Orientation").
    for (auto mode : {sim::OrientationMode::Vorticity, sim::OrientationMode::Flow,
                      sim::OrientationMode::Random}) {
        volume::CloudConfig c = small_cloud();
        c.orientation = mode;
        volume::CloudVolume turned(c), plain(small_cloud());
        CHECK(same_bits(turned.density(6), plain.density(6)));
    }
    // The orientation reaches the field: kernels stretched along other axes differ.
    volume::CloudVolume vort(oriented(sim::OrientationMode::Vorticity));
    volume::CloudVolume fixed(oriented(sim::OrientationMode::Fixed));
    CHECK_FALSE(same_bits(vort.field(9), fixed.field(9)));
}
