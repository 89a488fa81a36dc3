// SPDX-License-Identifier: Apache-2.0
// [shading]: named and explicit ramps, the colour mapping of a colour exemplar, and the
// shading of a field into display colour.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "output/io_module.h"
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

namespace {

/// A smooth w x h test field spanning about [-1.3, 1.3].
render::Frame wave_frame(int w, int h) {
    render::Frame f;
    f.resize(w, h);
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x)
            f.data[size_t(y) * f.width + x] = std::sin(0.3f * x) * std::cos(0.2f * y) * 1.3f;
    return f;
}

/// Grey, a ramp with alpha, and the same ramp with relief.
std::tuple<output::Shading, output::Shading, output::Shading> three_shadings() {
    output::Shading grey, ramp, relief;
    ramp.ramp = {{0.0, 1, 0, 0, 0}, {0.4, 0.2f, 0.8f, 0.1f, 0.6f}, {1.0, 0, 0, 1, 1}};
    relief = ramp;
    relief.relief = 3.0;
    return {grey, ramp, relief};
}

}  // namespace

TEST_CASE("a Shader shades any band of rows exactly as shade does", "[render][shading]") {
    // The video path shades a frame band by band (output::Shader) into the encoder's input; its
    // pixels must be shade's, bit for bit, for every shading (grey, ramp with alpha, relief,
    // whose central differences reach into the neighbouring rows of a band).
    const render::Frame f = wave_frame(37, 23);
    const auto [grey, ramp, relief] = three_shadings();
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

namespace {

/// BT.709 limited range (ITU-R BT.709-6 items 3.2-3.4) in double, the reference the encoder's
/// input is checked against: Y' = 16 + 219 Ey, Cb = 128 + 224 (B - Ey) / 1.8556,
/// Cr = 128 + 224 (R - Ey) / 1.5748, rounded to nearest.
struct RefYuv {
    double y, cb, cr;
};
RefYuv bt709_limited(double r, double g, double b) {
    const double ey = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    return {16.0 + 219.0 * ey, 128.0 + 224.0 * (b - ey) / 1.8556, 128.0 + 224.0 * (r - ey) / 1.5748};
}
int code(double v) { return int(std::floor(v + 0.5)); }

/// A w x h 4:2:0 picture in three tight planes.
struct Picture {
    int w, h;
    std::vector<uint8_t> y, cb, cr;
    Picture(int width, int height)
        : w(width), h(height), y(size_t(w) * h), cb(size_t(w / 2) * (h / 2)), cr(cb.size()) {}
    output::Yuv420Planes planes(int y0 = 0) {
        return {y.data() + size_t(y0) * w, cb.data() + size_t(y0 / 2) * (w / 2),
                cr.data() + size_t(y0 / 2) * (w / 2), w, w / 2, w / 2};
    }
};

/// Largest |code - reference| over the three planes of `pic` against the float RGB `rgb`:
/// luma per pixel, chroma from the mean colour of each 2x2 block (centre-sited).
int worst_code_error(const Picture& pic, const std::vector<float>& rgb) {
    int worst = 0;
    const int w = pic.w;
    auto px = [&](int x, int y, int c) { return double(rgb[(size_t(y) * w + x) * 3 + c]); };
    for (int y = 0; y < pic.h; ++y)
        for (int x = 0; x < w; ++x)
            worst = std::max(worst, std::abs(pic.y[size_t(y) * w + x] -
                                             code(bt709_limited(px(x, y, 0), px(x, y, 1), px(x, y, 2)).y)));
    for (int j = 0; j < pic.h / 2; ++j)
        for (int k = 0; k < w / 2; ++k) {
            double m[3];
            for (int c = 0; c < 3; ++c)
                m[c] = (px(2 * k, 2 * j, c) + px(2 * k + 1, 2 * j, c) + px(2 * k, 2 * j + 1, c) +
                        px(2 * k + 1, 2 * j + 1, c)) / 4.0;
            const RefYuv ref = bt709_limited(m[0], m[1], m[2]);
            const size_t i = size_t(j) * (w / 2) + k;
            worst = std::max({worst, std::abs(pic.cb[i] - code(ref.cb)), std::abs(pic.cr[i] - code(ref.cr))});
        }
    return worst;
}

}  // namespace

TEST_CASE("BT.709 limited range with centre-sited chroma from known colours", "[render][shading]") {
    // Four columns red | blue | green | green over two rows: the first chroma sample is the mean
    // of red and blue, the second pure green. The codes are the standard ones (white 235/128/128,
    // black 16, red 63/102/240); full range (white 255), BT.601 weights (red Y' 81) or left-sited
    // chroma (a [1 2 1] filter mixing blue into the second sample) would each miss them.
    const float red[3] = {1, 0, 0}, blue[3] = {0, 0, 1}, green[3] = {0, 1, 0};
    std::vector<float> rgb;
    for (int y = 0; y < 2; ++y)
        for (const float* c : {red, blue, green, green}) rgb.insert(rgb.end(), c, c + 3);
    Picture pic(4, 2);
    output::rgb_rows_to_yuv420(rgb.data(), 4, 2, pic.planes());
    CHECK(std::vector<int>(pic.y.begin(), pic.y.begin() + 4) == std::vector<int>{63, 32, 173, 173});
    CHECK(int(pic.cb[0]) == code(128.0 + 0.5 * (-224.0 * 0.2126 / 1.8556) + 0.5 * 112.0));  // 171
    CHECK(int(pic.cr[0]) == code(128.0 + 0.5 * 112.0 + 0.5 * (-224.0 * 0.0722 / 1.5748)));  // 179
    CHECK(int(pic.cb[1]) == code(128.0 - 224.0 * 0.7152 / 1.8556));                          // 42
    CHECK(int(pic.cr[1]) == code(128.0 - 224.0 * 0.7152 / 1.5748));                          // 26
    const float white[12] = {1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0};
    std::vector<float> grey(white, white + 12);
    grey.insert(grey.end(), white, white + 12);
    output::rgb_rows_to_yuv420(grey.data(), 4, 2, pic.planes());
    CHECK(std::vector<int>(pic.y.begin(), pic.y.end()) ==
          std::vector<int>{235, 235, 16, 16, 235, 235, 16, 16});
    CHECK(std::vector<int>(pic.cb.begin(), pic.cb.end()) == std::vector<int>{128, 128});
    CHECK(std::vector<int>(pic.cr.begin(), pic.cr.end()) == std::vector<int>{128, 128});
}

TEST_CASE("a Shader shades straight into YUV 4:2:0 within one code value of the reference",
          "[render][shading]") {
    // Shader::rows_yuv420 (the video path: no float RGB frame) against the double-precision
    // BT.709 conversion of shade's float RGB, for grey, a ramp with alpha over the sky (the
    // table held in Y'CbCr), relief (through rows) and drift's own shading; bands of even rows.
    const render::Frame f = wave_frame(38, 24);
    const auto [grey, ramp, relief] = three_shadings();
    const output::Shading drift = scenes::load_scene(scenes::resolve_scene("drift")).shading;
    for (const output::Shading* sh : {&grey, &ramp, &relief, &drift}) {
        std::vector<float> rgb;
        output::shade(f, {-1.0, 1.0}, *sh, rgb);
        const output::Shader shader({-1.0, 1.0}, *sh);
        Picture pic(f.width, f.height);
        const int bands[] = {0, 6, 8, 20, 24};
        for (int b = 0; b < 4; ++b) shader.rows_yuv420(f, bands[b], bands[b + 1], pic.planes(bands[b]));
        CHECK(worst_code_error(pic, rgb) <= 1);
        // And rgb_rows_to_yuv420 of the same RGB (the writer's conversion of float frames).
        Picture from_rgb(f.width, f.height);
        output::rgb_rows_to_yuv420(rgb.data(), f.width, f.height, from_rgb.planes());
        CHECK(worst_code_error(from_rgb, rgb) <= 1);
    }
}

namespace {

/// The ramp of a colour exemplar by a full sort of its pixels by luminance: the reference the
/// loader's quantile selection must reproduce.
std::vector<output::ColorStop> ramp_by_full_sort(const std::string& path, int stops) {
    output::Pixels image;
    std::string error;
    REQUIRE(output::read_pixels(path, image, error));
    const int c = image.channels;
    const size_t n = image.values.size() / size_t(c);
    std::vector<std::pair<float, size_t>> order;
    for (size_t i = 0; i < n; ++i) {
        const float* p = image.values.data() + i * size_t(c);
        order.emplace_back(c >= 3 ? 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2] : p[0], i);
    }
    std::sort(order.begin(), order.end());
    std::vector<output::ColorStop> ramp;
    for (int b = 0; b < stops; ++b) {
        const size_t i0 = n * size_t(b) / size_t(stops),
                     i1 = std::max(i0 + 1, n * size_t(b + 1) / size_t(stops));
        double sum[3] = {0, 0, 0};
        for (size_t k = i0; k < i1; ++k)
            for (int ch = 0; ch < 3; ++ch)
                sum[ch] += image.values[order[k].second * size_t(c) + size_t(c >= 3 ? ch : 0)];
        output::ColorStop s;
        s.r = float(sum[0] / double(i1 - i0)), s.g = float(sum[1] / double(i1 - i0));
        s.b = float(sum[2] / double(i1 - i0));
        ramp.push_back(s);
    }
    return ramp;
}

}  // namespace

TEST_CASE("an exemplar ramp's quantile bins hold what a full sort puts in them", "[scenes][shading]") {
    const fs::path dir = fs::temp_directory_path() / ("impulse_ramp_bins_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    // Random colours with many ties (8-bit PNG), at more and fewer pixels than stops.
    uint32_t state = 12345u;
    const auto next = [&] { state = state * 1664525u + 1013904223u; return float(state >> 8) / 16777216.0f; };
    for (const auto& [w, h, stops] : {std::tuple{61, 37, 16}, std::tuple{61, 37, 256}, std::tuple{3, 3, 16},
                                      std::tuple{1, 1, 2}}) {
        std::vector<float> rgb(size_t(w) * h * 3);
        for (float& v : rgb) v = next();
        const std::string path = (dir / "ex.png").string();
        output::write_rgb_image(path, w, h, rgb, {});
        const std::string text = "[[layer]]\n[shading]\nramp = { exemplar = \"ex.png\", stops = " +
                                 std::to_string(stops) + " }\n";
        const scenes::Scene s = scenes::load_scene_string(text, (dir / "scene.toml").string());
        const auto expected = ramp_by_full_sort(path, stops);
        REQUIRE(s.shading.ramp.size() == expected.size());
        for (size_t b = 0; b < expected.size(); ++b) {
            CAPTURE(w, h, stops, b);
            CHECK(s.shading.ramp[b].r == Approx(expected[b].r).margin(1e-6));
            CHECK(s.shading.ramp[b].g == Approx(expected[b].g).margin(1e-6));
            CHECK(s.shading.ramp[b].b == Approx(expected[b].b).margin(1e-6));
        }
    }
    fs::remove_all(dir);
}

TEST_CASE("a wide one-channel JPEG exemplar (fuzzing's slow unit) reads as a grey ramp", "[scenes][shading]") {
    // fuzz_image's reproducer: 1189 bytes of JPEG declaring 8198x164 grey pixels; the full sort
    // of 1.3 million (luminance, pixel) pairs took 14 s under the sanitizers, over a minute on a
    // loaded machine (libFuzzer's timeout). Selection of the bins on packed integer keys
    // (numeric::order_into_quantile_bins) takes it to under a second.
    const std::string path = std::string(IMPULSE_SOURCE_DIR) + "/tests/scenes/images/exemplar_8198x164.jpg";
    const std::string text = "[[layer]]\n[shading]\nramp = { exemplar = \"" + path + "\", stops = 16 }\n";
    const scenes::Scene s = scenes::load_scene_string(text, "scene.toml");
    const auto expected = ramp_by_full_sort(path, 16);
    REQUIRE(s.shading.ramp.size() == 16);
    for (size_t b = 0; b < 16; ++b) {
        CHECK(s.shading.ramp[b].r == Approx(expected[b].r).margin(1e-6));
        CHECK(s.shading.ramp[b].g == s.shading.ramp[b].r);  // grey: one channel
        if (b > 0) CHECK(s.shading.ramp[b].r >= s.shading.ramp[b - 1].r);
    }
}
