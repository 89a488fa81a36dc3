// SPDX-License-Identifier: Apache-2.0
// The filmic tone curve of [shading] (toe, shoulder): its shape, its keys, and the gallery's
// promise that a built-in frame keeps at most 0.5 % of its pixels at the top code value.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>

#include "numeric/errors.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;

namespace {

/// Share of pixels with some channel at the 8-bit top code value (rounded display value 255).
double top_code_share(const std::vector<float>& rgb) {
    size_t top = 0;
    for (size_t i = 0; i + 2 < rgb.size(); i += 3) {
        const float m = std::max({rgb[i], rgb[i + 1], rgb[i + 2]});
        top += std::lround(m * 255.0f) == 255;
    }
    return double(top) / double(rgb.size() / 3);
}

/// Frame `frame` of built-in scene `name` at `width` x `height`, shaded as `impulse render`
/// shades it, with `overrides`.
std::vector<float> shaded_builtin(const std::string& name, int64_t frame, int width, int height,
                                  const std::vector<std::string>& overrides = {}) {
    scenes::Renderer r(scenes::load_scene(scenes::resolve_scene(name), overrides, {width, height}));
    render::Frame f;
    r.render(frame, f);
    std::vector<float> rgb;
    output::shade(f, r.mapping(), r.scene().shading_at(r.scene().frame_time(frame)), rgb);
    return rgb;
}

}  // namespace

TEST_CASE("the tone curve is the identity between its roll-offs, C1 and monotonic", "[scenes][shading]") {
    const double toe = 0.1, shoulder = 0.2;
    for (double x : {0.1, 0.3, 0.5, 0.8}) CHECK(output::tone_curve(x, toe, shoulder) == Approx(x));
    // Value and slope meet at the joins: the one-sided slopes agree to O(h).
    const double h = 1e-6;
    for (double knee : {toe, 1.0 - shoulder}) {
        const double left = (output::tone_curve(knee, toe, shoulder) - output::tone_curve(knee - h, toe, shoulder)) / h;
        const double right = (output::tone_curve(knee + h, toe, shoulder) - output::tone_curve(knee, toe, shoulder)) / h;
        CHECK(left == Approx(1.0).margin(1e-4));
        CHECK(right == Approx(1.0).margin(1e-4));
    }
    double last = -1.0;
    for (int i = 0; i <= 4000; ++i) {
        const double y = output::tone_curve(-1.0 + i * 1e-3, toe, shoulder);
        REQUIRE(y > last);  // strictly increasing: no two field values share a plate
        REQUIRE(y > 0.0);
        REQUIRE(y < 1.0);
        last = y;
    }
    // The roll-off is the documented exponential: 1 - shoulder exp(-(x - 0.8) / shoulder).
    CHECK(output::tone_curve(1.5, toe, shoulder) == Approx(1.0 - 0.2 * std::exp(-0.7 / 0.2)));
    // Zero widths are the hard clip.
    CHECK(output::tone_curve(1.3, 0.0, 0.0) == 1.0);
    CHECK(output::tone_curve(-0.3, 0.0, 0.0) == 0.0);
    CHECK(output::tone_curve(0.42, 0.0, 0.0) == 0.42);
}

TEST_CASE("a shoulder keeps the gradation of values past the mapping instead of a plate", "[scenes][shading]") {
    // Field values from the middle of the mapping [-1, 1] to half its width past its top: linear
    // display values x = (v + 1) / 2 from 0.5 to 1.5.
    render::Frame f;
    f.resize(512, 1);
    for (int x = 0; x < 512; ++x) f.data[x] = float(x) / 511.0f * 2.0f;
    const auto shade = [&](double shoulder) {
        output::Shading sh;
        sh.shoulder = shoulder;
        sh.ramp = {{0.0, 0, 0, 0, 1}, {1.0, 1, 1, 1, 1}};
        std::vector<float> rgb;
        output::shade(f, {-1.0, 1.0}, sh, rgb);
        return rgb;
    };
    // 8-bit codes of the pixels past the mapping's top (x > 1).
    const auto tail_codes = [&](const std::vector<float>& rgb) {
        std::set<long> distinct;
        for (int x = 0; x < 512; ++x)
            if (f.data[x] > 1.0f) distinct.insert(std::lround(rgb[3 * x] * 255.0f));
        return distinct.size();
    };
    const std::vector<float> clip = shade(0.0), tone = shade(0.2);
    CHECK(top_code_share(clip) == Approx(0.5).margin(0.01));  // x > 1: half the ramp at 255
    // The shoulder reaches within half a code of 1 only at x = 0.8 + 0.2 ln(0.2 * 510) = 1.72.
    CHECK(top_code_share(tone) == 0.0);
    CHECK(tail_codes(clip) == 1);   // one flat plate
    CHECK(tail_codes(tone) >= 17);  // 255 x 0.2 (e^-1 - e^-3.5) = 17.4 codes from x = 1 to 1.5
}

TEST_CASE("toe and shoulder are read from [shading] and checked", "[scenes][shading]") {
    const scenes::Scene s = scenes::load_scene_string("[[layer]]\n[shading]\ntoe = 0.05\nshoulder = 0.3\n", "t.toml");
    CHECK(s.shading.toe == 0.05);
    CHECK(s.shading.shoulder == 0.3);
    CHECK(scenes::load_scene_string("[[layer]]\n", "t.toml").shading.shoulder == 0.0);
    CHECK_THROWS_WITH(scenes::load_scene_string("[[layer]]\n[shading]\nshoulder = 0.7\n", "t.toml"),
                      Catch::Contains("t.toml:3:") && Catch::Contains("shading.shoulder = 0.7") &&
                          Catch::Contains("[0, 0.5]"));
    CHECK_THROWS_WITH(
        scenes::load_scene_string("[[layer]]\n[shading]\ntoe = { keys = [[0, 0.1], [1, 0.2]] }\n", "t.toml"),
        Catch::Contains("t.toml:3:") && Catch::Contains("the tone curve is the same in every frame"));
}

TEST_CASE("built-in cloud frames keep at most 0.5 % of pixels at the top code value",
          "[scenes][shading][gallery][slow]") {
    // Frames 0 and 60 at a quarter of the scenes' size (the same view, fewer pixels). Before
    // the tone curve 3.7 % and 5.8 % of drift's pixels sat at 255 (white plates, the old ramp
    // white from t = 0.8). With the shoulder switched off the tail past the mapping's top is a
    // plate again (a Gaussian field puts 0.13 % past mean + 3 sd; drift's, 0.25 % at frame 60).
    for (int64_t frame : {0, 60}) {
        INFO("drift frame " << frame);
        CHECK(top_code_share(shaded_builtin("drift", frame, 480, 270)) <= 0.005);
    }
    const double with = top_code_share(shaded_builtin("drift", 60, 480, 270));
    const double without = top_code_share(shaded_builtin("drift", 60, 480, 270, {"shading.shoulder=0"}));
    INFO("top code share at frame 60: " << with << " with the shoulder, " << without << " without");
    // Since this stop's scene changes (Gaussian radii at 3.717 sigma, issue 34) drift's tail
    // past the mapping's top is 0.037 % of the pixels without the shoulder at frame 60 (0.25 %
    // before), none with it.
    CHECK(without > 0.0002);
    CHECK(with < 0.2 * without);
}
