// SPDX-License-Identifier: Apache-2.0
// Shaping hits its target at ordinary densities (issue 18): with the default F_x, the layer's
// own shot-noise law (kernels/shot_noise.h), a still cosine layer (R = 4) shaped to a
// lognormal and to a uniform target is within KS 0.01 of the target at densities 8, 16 and 64
// on every seed, for normal, uniform and sign amplitudes; the old Gaussian F_x (cdf =
// "gaussian") is not, at density 8.
//
// Independent samples: the frame is 256^2 pixels at zoom 1/8 (anti-aliasing off), so pixels are
// 8 texture units = 2 R apart. A compact kernel of radius R makes the field at points 2 R apart
// depend on disjoint sets of impulses, and a Poisson process's counts on disjoint sets are
// independent: the 65 536 pixels are exactly independent samples (effective sample size =
// 65 536). The KS statistic then has its textbook law: critical value 1.949 / sqrt(65 536) =
// 0.0076 at alpha = 0.001, and P(D > 0.01) = P(sqrt(n) D > 2.56) = 4e-6 for a right F_x. KS is
// invariant under the monotone g, so the two targets see the same sampling error; what differs
// is the transfer table. The shaped values are the scene's own transform applied to the
// unshaped frame (the renderer applies exactly that, pixel by pixel: test_shaping.cpp).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "kernels/kernels.h"
#include "tests/scene_render.h"

namespace {

namespace K = impulse::kernels;
constexpr double kN = 65536.0;
constexpr double kCritical = 1.949 / 256.0;  // alpha 0.001 at n = 65 536

std::string scene_text(double density, const char* amplitude, int seed,
                       const std::string& marginal) {
    return "[output]\nsize = [256, 256]\n[camera]\nzoom = 0.125\nantialias = \"off\"\n"
           "[[layer]]\nseed = " +
           std::to_string(seed) + "\ndensity = " + std::to_string(density) + "\namplitude = \"" +
           amplitude + "\"\n" + marginal + "\n[layer.kernel]\ntype = \"cosine\"\nradius = 4.0\n";
}

/// KS distance of `values` shaped by the scene's transform to the transform's target.
double shaped_ks(const std::vector<float>& raw, const K::MarginalTransform& g) {
    std::vector<float> y = raw;
    g.apply(y);
    std::sort(y.begin(), y.end());
    double d = 0.0;
    for (size_t i = 0; i < y.size(); ++i) {
        const double p = g.target().cdf(y[i]);
        d = std::max({d, std::abs(p - double(i) / kN), std::abs(p - double(i + 1) / kN)});
    }
    return d;
}

const char* const kTargets[] = {
    "marginal = { type = \"lognormal\", mu = 0.0, sigma = 1.0 }",
    "marginal = { type = \"uniform\", a = 0.0, b = 1.0 }",
};

}  // namespace

TEST_CASE("default shaping is within KS 0.01 of lognormal and uniform targets from density 8",
          "[scenes][shaping][stats][slow]") {
    for (const char* amplitude : {"normal", "uniform", "sign"})
        for (double density : {4.0, 8.0, 16.0, 64.0})
            for (int seed = 1; seed <= 3; ++seed) {
                const auto raw =
                    impulse::test::render_scene_text(scene_text(density, amplitude, seed, ""));
                REQUIRE(raw.data.size() == size_t(kN));
                for (const char* target : kTargets) {
                    const auto scene = impulse::scenes::load_scene_string(
                        scene_text(density, amplitude, seed, target), "shaped.toml");
                    const auto& g = *scene.layers[0].marginal;
                    REQUIRE(g.source() == K::SourceCdf::ShotNoise);
                    const double d = shaped_ks(raw.data, g);
                    CAPTURE(amplitude, density, seed, target, d, kCritical);
                    if (density >= 8.0) {
                        CHECK(d <= 0.01);
                    } else {
                        // Density 4: a fraction exp(-4) = 1.8 % of the plane has no impulse in
                        // reach and sits at the mean; g maps that atom to the middle of its
                        // step, half a atom from the target on each side.
                        CHECK(d <= 0.5 * std::exp(-4.0) + kCritical);
                    }
                }
            }
}

TEST_CASE("the Gaussian F_x misses the same targets at density 8 (mechanism off)",
          "[scenes][shaping][stats][slow]") {
    // Excess kurtosis (E[a^4] / E[a^2]^2) pi / 8: normal 1.18, uniform 0.71, so the Gaussian is
    // ~0.023 x that = 0.027 and 0.016 off in KS (Edgeworth), beyond 0.01 + the sampling error.
    for (const char* amplitude : {"normal", "uniform"})
        for (int seed = 1; seed <= 3; ++seed) {
            const auto raw = impulse::test::render_scene_text(scene_text(8.0, amplitude, seed, ""));
            const std::string m =
                "marginal = { type = \"lognormal\", mu = 0.0, sigma = 1.0, cdf = \"gaussian\" }";
            const auto scene =
                impulse::scenes::load_scene_string(scene_text(8.0, amplitude, seed, m), "g.toml");
            const auto& g = *scene.layers[0].marginal;
            REQUIRE(g.source() == K::SourceCdf::Gaussian);
            const double d = shaped_ks(raw.data, g);
            CAPTURE(amplitude, seed, d);
            CHECK(d > 0.01);
        }
}
