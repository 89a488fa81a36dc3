// SPDX-License-Identifier: Apache-2.0
// Every built-in scene renders: 3 frames at 256x256, finite and non-degenerate.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;
namespace fs = std::filesystem;

TEST_CASE("each gallery scene renders 3 frames at 256x256 with sensible statistics",
          "[scenes][gallery][slow]") {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(fs::path(IMPULSE_SOURCE_DIR) / "scenes"))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    REQUIRE(files.size() >= 4);
    for (const auto& file : files) {
        INFO(file.filename().string());
        // The scene's whole view at 256 x 256 (as --size renders it), not a crop of its corner:
        // fire's bed and ink's drop are regions away from the corner.
        scenes::Scene scene = scenes::load_scene(file.string(), {}, {256, 256});
        REQUIRE(scene.output.width == 256);
        // A volume scene is not a 2-D field: tests/app/test_volume_cli.cpp renders it.
        if (scene.volume) continue;
        const int64_t frames = std::min<int64_t>(scene.output.frames, 3);
        REQUIRE(frames >= 1);
        scenes::Renderer renderer(std::move(scene));
        const output::ValueMapping map = renderer.mapping();
        const double span = map.hi - map.lo;
        REQUIRE(span > 0.0);
        render::Frame f;
        for (int64_t i = 0; i < frames; ++i) {
            INFO("frame " << i);
            renderer.render(i, f);
            double sum = 0.0, sum2 = 0.0;
            size_t clipped = 0, finite = 0;
            for (float v : f.data) {
                if (!std::isfinite(v)) continue;
                ++finite;
                sum += v;
                sum2 += double(v) * v;
                clipped += (v < map.lo || v > map.hi);
            }
            REQUIRE(finite == f.data.size());
            const double n = double(f.data.size());
            const double mean = sum / n, sd = std::sqrt(std::max(0.0, sum2 / n - mean * mean));
            // Non-degenerate on screen: the frame's spread covers a visible part of the display
            // range (a flat or nearly flat frame would be < 1 % of it) ...
            CHECK(sd > 0.01 * span);
            // ... and most of it is inside the range rather than clipped to black or white.
            CHECK(double(clipped) < 0.5 * n);
        }
    }
}
