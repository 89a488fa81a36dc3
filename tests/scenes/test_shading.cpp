// SPDX-License-Identifier: Apache-2.0
// [shading]: named and explicit ramps, the colour mapping of a colour exemplar, and the
// shading of a field into display colour.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

using namespace impulse;
namespace fs = std::filesystem;

TEST_CASE("a colour exemplar becomes a ramp ordered by luminance", "[scenes][shading]") {
    const fs::path dir = fs::temp_directory_path() / ("impulse_shading_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    // Half dark red, half bright blue-white: the dark quantiles must be red, the bright ones blue.
    const int w = 32, h = 32;
    std::vector<float> rgb(size_t(w) * h * 3);
    for (int i = 0; i < w * h; ++i) {
        const bool bright = i % 2;
        rgb[3 * i] = bright ? 0.6f : 0.4f;
        rgb[3 * i + 1] = bright ? 0.8f : 0.0f;
        rgb[3 * i + 2] = bright ? 1.0f : 0.0f;
    }
    output::write_rgb_image((dir / "ex.png").string(), w, h, rgb, {});
    const std::string text = "[[layer]]\n[shading]\nramp = { exemplar = \"ex.png\", stops = 4 }\n";
    const scenes::Scene s = scenes::load_scene_string(text, (dir / "scene.toml").string());
    REQUIRE(s.shading.ramp.size() == 4);
    for (size_t i = 1; i < 4; ++i) CHECK(s.shading.ramp[i].t > s.shading.ramp[i - 1].t);
    // Stops at (Phi^-1((i + 1/2)/4) + 3) / 6: symmetric about the middle of the display range.
    CHECK(s.shading.ramp[0].t + s.shading.ramp[3].t == Approx(1.0).margin(1e-9));
    CHECK(s.shading.ramp[0].r == Approx(0.4f).margin(1.0 / 255));  // 8-bit quantised colours
    CHECK(s.shading.ramp[0].b == Approx(0.0f).margin(1.0 / 255));
    CHECK(s.shading.ramp[3].b == Approx(1.0f).margin(1.0 / 255));
    CHECK(s.shading.ramp[3].g == Approx(0.8f).margin(1.0 / 255));
    CHECK_THROWS_WITH(scenes::load_scene_string("[[layer]]\n[shading]\nramp = { exemplar = \"missing.png\" }\n",
                                                (dir / "scene.toml").string()),
                      Catch::Contains("scene.toml:3:") && Catch::Contains("shading.ramp.exemplar = \"missing.png\": cannot read"));
    fs::remove_all(dir);
}

TEST_CASE("shading maps the field through the ramp and composites alpha over the sky", "[render][shading]") {
    render::Frame f;
    f.resize(3, 2);
    f.data = {-1.0f, 0.0f, 1.0f, -1.0f, 0.0f, 1.0f};
    output::Shading sh;
    sh.ramp = {{0.0, 1, 0, 0, 0}, {1.0, 0, 0, 1, 1}};  // transparent red -> opaque blue
    std::vector<float> rgb;
    output::shade(f, {-1.0, 1.0}, sh, rgb);
    // t = 0: fully transparent: the background's top colour on row 0, bottom on row 1.
    CHECK(rgb[0] == Approx(sh.top[0]).margin(1e-6));
    CHECK(rgb[3 * 3 + 2] == Approx(sh.bottom[2]).margin(1e-6));
    // t = 1: opaque blue.
    CHECK(rgb[3 * 2 + 0] == Approx(0.0f).margin(1e-6));
    CHECK(rgb[3 * 2 + 2] == Approx(1.0f).margin(1e-6));
    // t = 1/2: half-transparent purple over the sky, alpha 1/2 (table step 1/4095).
    CHECK(rgb[3 * 1 + 0] == Approx(0.25f + 0.5f * sh.top[0]).margin(1e-3));
    // Grey without a ramp is the display value itself.
    output::shade(f, {-1.0, 1.0}, output::Shading{}, rgb);
    CHECK(rgb[3] == Approx(0.5f).margin(1e-6));
}

TEST_CASE("a Shader shades any band of rows exactly as shade does", "[render][shading]") {
    // The video path shades a frame band by band (output::Shader) into the encoder's input; its
    // pixels must be shade's, bit for bit, for every shading (grey, ramp with alpha, relief,
    // whose central differences reach into the neighbouring rows of a band).
    render::Frame f;
    f.resize(37, 23);
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x)
            f.data[size_t(y) * f.width + x] = std::sin(0.3f * x) * std::cos(0.2f * y) * 1.3f;
    output::Shading grey, ramp, relief;
    ramp.ramp = {{0.0, 1, 0, 0, 0}, {0.4, 0.2f, 0.8f, 0.1f, 0.6f}, {1.0, 0, 0, 1, 1}};
    relief = ramp;
    relief.relief = 3.0;
    for (const output::Shading* sh : {&grey, &ramp, &relief}) {
        std::vector<float> whole;
        output::shade(f, {-1.0, 1.0}, *sh, whole);
        const output::Shader shader({-1.0, 1.0}, *sh);
        std::vector<float> banded(whole.size(), -1.0f);
        const size_t row = size_t(f.width) * 3;
        for (int y0 : {0, 5, 6, 13, 22}) {  // uneven bands: [0,5) [5,6) [6,13) [13,22) [22,23)
            const int y1 = y0 == 0 ? 5 : y0 == 5 ? 6 : y0 == 6 ? 13 : y0 == 13 ? 22 : 23;
            shader.rows(f, y0, y1, banded.data() + y0 * row);
        }
        CHECK(std::memcmp(whole.data(), banded.data(), whole.size() * sizeof(float)) == 0);
    }
}
