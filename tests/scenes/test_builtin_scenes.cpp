// SPDX-License-Identifier: Apache-2.0
// The built-in scenes (scenes/*.toml, what `impulse scenes` lists and scripts/gallery.sh
// renders): each loads without warnings, starts with its one-line description, keeps a modest
// default size and length, and a looped one repeats — frame `loop * fps` equals frame 0, bit
// for bit (rendered small).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"

namespace fs = std::filesystem;

TEST_CASE("built-in scenes load, describe themselves, stay modest, and loops repeat",
          "[scenes][builtin]") {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(fs::path(IMPULSE_SOURCE_DIR) / "scenes"))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    REQUIRE(files.size() >= 8);
    for (const auto& f : files) {
        INFO(f.filename().string());
        std::ifstream in(f);
        std::string first;
        std::getline(in, first);
        CHECK(first.rfind("# ", 0) == 0);  // the description `impulse scenes` prints
        const auto scene = impulse::scenes::load_scene(f.string());
        CHECK(scene.warnings.empty());
        if (f.stem() == "clouds" || f.stem() == "drift") continue;  // 1080p by design
        CHECK(double(scene.output.width) * scene.output.height <= 1280.0 * 1024.0);
        CHECK(scene.output.frames / scene.output.fps <= 10.0);

        double loop = 0;
        bool all_loop = !scene.layers.empty();
        for (const auto& l : scene.layers) {
            loop = std::max(loop, l.process.loop_s);
            all_loop = all_loop && l.process.loop_s > 0 && l.process.loop_s == scene.layers[0].process.loop_s;
        }
        if (!all_loop) continue;
        const int64_t period = std::llround(loop * scene.output.fps);
        const auto small = impulse::scenes::load_scene(
            f.string(), {"output.size=[96,64]", "output.frames=" + std::to_string(period + 1)});
        impulse::scenes::Renderer r(small);
        impulse::render::Frame a, b;
        r.render(0, a);
        r.render(period, b);
        CHECK(std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0);
        // ... and it moves in between.
        r.render(period / 2, b);
        CHECK(std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) != 0);
    }
}
