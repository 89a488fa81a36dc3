// SPDX-License-Identifier: Apache-2.0
// Issue 35: no built-in scene's frame 0 has more than 0.5 % of its pixels clipped white (every
// channel at the top 8-bit code), measured as a new user would, on the CLI's PNG. cloudvolume's
// ray-marched preview clamped its linear radiance (9.8 % of frame 0 white before the shoulder of
// volume/march.cpp); the 2-D scenes roll their ramps off with toe and shoulder. The fraction is
// of the frame's area, so the 2-D scenes are measured at 480x270 (`--size`: the same view); the
// preview at its own 640x360.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "output/output.h"
#include "scenes/scenes.h"
#include "tests/support.h"

namespace fs = std::filesystem;
using namespace impulse;

TEST_CASE("no built-in scene clips more than 0.5 % of frame 0 to white", "[scenes][slow]") {
    const test::TempDir dir("clip");
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(scenes::builtin_scene_dir()))
        if (e.path().extension() == ".toml") names.push_back(e.path().stem().string());
    REQUIRE(names.size() >= 10);
    for (const auto& name : names) {
        const fs::path png = dir.path() / (name + ".png");
        const std::string size = name == "cloudvolume" ? "" : " --size 480x270";
        const auto r = test::shell(dir, test::quote(IMPULSE_BINARY) + " render " + name + " -q -o " +
                                            test::quote(png.string()) + " --frames 0-0" + size);
        INFO(name << ": " << r.err);
        REQUIRE(r.status == 0);
        // Luminance of 8-bit RGB: at or above 254.5/255 only when every channel is 255.
        const output::Frame f = output::read_image(png.string());
        size_t white = 0;
        for (float v : f.data) white += v >= 254.5f / 255.0f;
        const double fraction = double(white) / double(f.data.size());
        INFO(name << ": " << 100.0 * fraction << " % of the pixels white");
        CHECK(fraction < 0.005);
    }
}
