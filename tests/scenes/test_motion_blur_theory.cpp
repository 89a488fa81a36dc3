// SPDX-License-Identifier: Apache-2.0
// Motion blur's theory (docs/motion_blur.md "Theory"): rendered blurred frames have the blurred
// closed-form variance, each kernel replaced by its mean along its path (here a segment of 5
// sigma: the variance falls to 0.55 of the unblurred one), and not the unblurred one; shutter = 0
// is the unblurred frame bit for bit.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"

using namespace impulse;

namespace {

// Gaussian sigma 2 in a uniform wind of 240 units/s at 24 fps, a full shutter: b = 10 units.
std::string scene(double shutter) {
    return R"(
[output]
size = [256, 256]
fps = 24
frames = 400

[camera]
shutter = )" + std::to_string(shutter) + R"(

[[layer]]
seed = 5
density = 8.0
amplitude = "sign"
lifetime = 1.0
[layer.kernel]
type = "gaussian"
radius = 6.0
sigma = 2.0
[[layer.flow]]
type = "uniform"
velocity = [240.0, 0.0]
)";
}

double frame_variance(const render::Frame& f) {
    double m = 0, v = 0;
    for (float x : f.data) m += x;
    m /= double(f.data.size());
    for (float x : f.data) v += (x - m) * (x - m);
    return v / double(f.data.size());
}

}  // namespace

TEST_CASE("a blurred frame's variance is the closed form's for kernels averaged along their paths",
          "[scenes][blur][stats]") {
    const scenes::Scene s = scenes::load_scene_string(scene(1.0), "blur.toml");
    const double blurred = scenes::blurred_scene_theory(s).variance;
    const double sharp = scenes::scene_theory(s).variance;
    scenes::Renderer r(s);
    // Frames one lifetime (24 frames) apart share no impulse: independent. The band is the
    // Student t at 0.1 % two-sided on 11 degrees of freedom (4.44) of their standard error.
    std::vector<double> v;
    for (int64_t frame = 0; frame < 12 * 24; frame += 24) {
        render::Frame f;
        r.render(frame, f);
        v.push_back(frame_variance(f));
    }
    double mean = 0, var = 0;
    for (double x : v) mean += x / double(v.size());
    for (double x : v) var += (x - mean) * (x - mean) / double(v.size() - 1);
    const double se = std::sqrt(var / double(v.size()));
    INFO("measured " << mean << " +- " << se << ", blurred theory " << blurred << ", unblurred "
                     << sharp);
    CHECK(blurred / sharp == Approx(0.55).margin(0.02));
    CHECK(std::abs(mean - blurred) <= 4.44 * se);
    CHECK(std::abs(mean - sharp) > 4.44 * se);  // the unblurred theory is rejected
}

TEST_CASE("shutter = 0 renders the unblurred frame bit for bit", "[scenes][blur]") {
    const std::string text = scene(0.0);
    std::string without = text;
    without.erase(without.find("[camera]"), std::string("[camera]\nshutter = 0.000000\n").size());
    REQUIRE(without.find("shutter") == std::string::npos);
    CHECK(test::same_bits(test::render_scene_text(text, 7), test::render_scene_text(without, 7)));
    CHECK_FALSE(test::same_bits(test::render_scene_text(scene(0.5), 7),
                                test::render_scene_text(without, 7)));
}
