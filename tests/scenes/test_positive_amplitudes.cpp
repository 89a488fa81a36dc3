// SPDX-License-Identifier: Apache-2.0
// Exponential (positive) amplitudes: a frame's mean and variance against Campbell's theorem,
// Mean = lambda E[a] int h (1/T) int w, Var = lambda E[a^2] int h^2 (1/T) int w^2, with
// E[a] = 1 and E[a^2] = 2; and the combinations that assume a zero-mean train are refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/scenes.h"

namespace S = impulse::scenes;

namespace {

/// Mean and variance (about `mean`) of a set of frames, each with its standard error from the
/// scatter of B x B block statistics (blocks several kernel widths apart are nearly
/// independent: design.md §5, bands from the run itself).
struct BlockStats {
    double mean = 0, mean_se = 0, variance = 0, variance_se = 0;
};
BlockStats block_stats(const std::vector<impulse::render::Frame>& frames, double mean, int B) {
    std::vector<double> m, v;
    for (const auto& f : frames)
        for (int by = 0; by + B <= f.height; by += B)
            for (int bx = 0; bx + B <= f.width; bx += B) {
                double s1 = 0, s2 = 0;
                for (int y = by; y < by + B; ++y)
                    for (int x = bx; x < bx + B; ++x) {
                        const double d = f.at(x, y) - mean;
                        s1 += f.at(x, y), s2 += d * d;
                    }
                m.push_back(s1 / (double(B) * B));
                v.push_back(s2 / (double(B) * B));
            }
    auto mean_and_se = [](const std::vector<double>& x, double& mu, double& se) {
        mu = 0;
        for (double a : x) mu += a / double(x.size());
        double ss = 0;
        for (double a : x) ss += (a - mu) * (a - mu);
        se = std::sqrt(ss / double(x.size() - 1) / double(x.size()));
    };
    BlockStats r;
    mean_and_se(m, r.mean, r.mean_se);
    mean_and_se(v, r.variance, r.variance_se);
    return r;
}

std::string scene_text(const std::string& amplitude) {
    return R"(
[output]
size = [512, 512]
fps = 2
frames = 12
[[layer]]
density = 12.0
amplitude = ")" + amplitude + R"("
lifetime = 2.0
[layer.kernel]
type = "gaussian"
radius = 15.0
sigma = 5.0
)";
}

}  // namespace

TEST_CASE("exponential amplitudes give Campbell's mean and variance", "[scenes][stats]") {
    const S::Scene scene = S::load_scene_string(scene_text("exponential"), "positive.toml");
    const S::LayerConfig& L = scene.layers[0];
    // The closed form from its parts: lambda live impulses per unit area, int h and int h^2 of
    // the kernel, hann's (1/T) int w = 1/2 and (1/T) int w^2 = 3/8, E[a] = 1, E[a^2] = 2.
    const impulse::kernels::Kernel k(L.kernel);
    const double lambda = L.process.intensity;
    const double mean = lambda * 1.0 * k.integral() * 0.5;
    const double variance = lambda * 2.0 * k.integral_sq() * 0.375;
    const S::Theory th = S::layer_theory(L, 0.0);
    CHECK(th.mean == Approx(mean).epsilon(1e-9));
    CHECK(th.variance == Approx(variance).epsilon(1e-9));
    // Frames 2 s apart (the lifetime): no impulse lives in two of them.
    S::Renderer r(scene);
    std::vector<impulse::render::Frame> frames(3);
    for (int i = 0; i < 3; ++i) r.render(8 * i / 2 + 2, frames[i]);
    // 64 x 64 blocks are over four kernel radii wide; bands are 5 standard errors (4 would do
    // for independent blocks; neighbours share a kernel-wide strip).
    const BlockStats b = block_stats(frames, mean, 64);
    CAPTURE(mean, variance, b.mean, b.mean_se, b.variance, b.variance_se);
    CHECK(std::abs(b.mean - mean) < 5.0 * b.mean_se);
    CHECK(std::abs(b.variance - variance) < 5.0 * b.variance_se);
    // Teeth: the band is tight enough to tell the positive mean from a zero-mean law's 0, and
    // E[a^2] = 2 from the sign law's 1.
    CHECK(mean > 20.0 * b.mean_se);
    CHECK(0.5 * variance > 10.0 * b.variance_se);
    // A zero-mean law on the same seed has mean 0.
    const S::Scene sign = S::load_scene_string(scene_text("sign"), "sign.toml");
    CHECK(S::layer_theory(sign.layers[0], 0.0).mean == 0.0);
}

TEST_CASE("exponential amplitudes with a marginal or a perspective camera are refused",
          "[scenes][errors]") {
    const std::string marginal = scene_text("exponential") + "[layer.marginal]\ntype = \"uniform\"\n";
    CHECK_THROWS_WITH(S::load_scene_string(marginal, "m.toml"),
                      Catch::Contains("m.toml:8:13: layer[0].amplitude = \"exponential\"") &&
                          Catch::Contains("no shot-noise marginal"));
    const std::string camera = R"(
[camera]
type = "perspective"
height = 100.0
pitch = 30.0
)" + scene_text("exponential");
    CHECK_THROWS_WITH(S::load_scene_string(camera, "c.toml"),
                      Catch::Contains("c.toml:13:13: layer[0].amplitude") &&
                          Catch::Contains("faded to the mean by a perspective camera"));
}
