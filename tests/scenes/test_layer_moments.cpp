// SPDX-License-Identifier: Apache-2.0
// scenes::layer_moments: the excess kurtosis of an impulse layer in closed form (Campbell's
// fourth cumulant over the kernel's effective area) against the kurtosis measured on rendered
// frames, for cosine and gaussian kernels and normal, uniform and sign amplitudes.

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"

TEST_CASE("layer excess kurtosis in closed form matches rendered frames", "[scenes][stats]") {
    struct Case {
        const char* kernel;
        const char* amplitude;
        double density;
    };
    // 3 pi / 16 = 0.589 (cosine, normal); the gaussian r = 16, sigma = 5 has 2 pi sigma^2 of
    // effective area in its 256 pi disc (0.96 at density 16).
    const Case cases[] = {{"type = \"cosine\"\nradius = 8.0", "normal", 16.0},
                          {"type = \"cosine\"\nradius = 8.0", "uniform", 8.0},
                          {"type = \"cosine\"\nradius = 8.0", "sign", 16.0},
                          {"type = \"gaussian\"\nradius = 16.0\nsigma = 5.0", "normal", 16.0}};
    for (const Case& c : cases) {
        std::vector<double> k;
        double theory = 0;
        for (int seed = 1; seed <= 12; ++seed) {
            const std::string text = "[output]\nsize = [256, 256]\n[[layer]]\nseed = " +
                                     std::to_string(seed) + "\ndensity = " +
                                     std::to_string(c.density) + "\namplitude = \"" +
                                     c.amplitude + "\"\n[layer.kernel]\n" + c.kernel + "\n";
            const auto scene = impulse::scenes::load_scene_string(text, "k.toml");
            theory = impulse::scenes::layer_moments(scene.layers.front()).excess_kurtosis;
            const auto f = impulse::test::render_scene_text(text, 0, "k.toml");
            k.push_back(impulse::analysis::moments(f.data).excess_kurtosis);
        }
        double m = 0, v = 0;
        for (double x : k) m += x / double(k.size());
        for (double x : k) v += (x - m) * (x - m) / double(k.size() - 1);
        // The seeds are independent: the mean of 12 has sd sqrt(v / 12); 4 sd, plus the
        // estimator's O(1/N) bias on 65536 correlated pixels (below 0.02 here).
        INFO(c.kernel << ", " << c.amplitude << ", density " << c.density << ": theory " << theory
                      << ", measured " << m << " +- " << std::sqrt(v / 12));
        CHECK(std::abs(m - theory) < 4.0 * std::sqrt(v / 12.0) + 0.02);
    }
}
