// SPDX-License-Identifier: Apache-2.0
// Filtering after shading (docs/shading.md): the averaged ramp against the ramp's mean over the
// sub-pixel distribution, and the bias of shaded frames against a supersampled shaded reference
// with the remedy and without.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/shaded_bias.h"

using namespace impulse;

namespace {

/// The ramp's premultiplied colour and alpha at display value t (stops sorted; held at the
/// ends), as the shading's ramp defines it (docs/scenes.md "[shading]").
void ramp_premultiplied(const std::vector<output::ColorStop>& ramp, double t, double out[4]) {
    double c[4];
    const output::ColorStop *a = &ramp.front(), *b = &ramp.front();
    double s = 0.0;
    if (t >= ramp.back().t) {
        a = b = &ramp.back();
    } else if (t > ramp.front().t) {
        size_t i = 1;
        while (t > ramp[i].t) ++i;
        a = &ramp[i - 1], b = &ramp[i], s = (t - a->t) / (b->t - a->t);
    }
    c[0] = a->r + s * (b->r - a->r), c[1] = a->g + s * (b->g - a->g);
    c[2] = a->b + s * (b->b - a->b), c[3] = a->a + s * (b->a - a->a);
    for (int k = 0; k < 3; ++k) out[k] = c[3] * c[k];
    out[3] = c[3];
}

}  // namespace

TEST_CASE("the averaged ramp is the ramp's mean over the sub-pixel distribution within its "
          "predicted error", "[scenes][shading]") {
    // A frame whose rows hold values across the range and past it, each row with its own
    // sub-pixel sd (0.01 to 0.5 field units over a range of 2: 1/200 to 1/4 of the display
    // range). Reference: the premultiplied ramp after the tone curve averaged over
    // N(value, sd^2) by the trapezoid rule at sd/64 over +-8 sd (error about
    // (sd/64)^2 / 12 J phi(0) / sd <= 1e-5), composited over the background. Predicted: the
    // Shader's level_error (interpolating between its tables) plus half a table entry (1/8192
    // of the display range) times the largest slope of the premultiplied ramp (J = 5 per
    // display unit: alpha 0 -> 0.85 over 0.17), 6.1e-4, plus the tables' own trapezoid error
    // (5e-4 J sd <= 6.3e-4 at sd = 1/4, docs/shading.md "The averaged ramp").
    output::Shading sh;
    sh.ramp = {{0.0, 1, 1, 1, 0}, {0.45, 1, 1, 1, 0}, {0.62, 0.88f, 0.90f, 0.95f, 0.85f},
               {0.8, 0.95f, 0.96f, 0.98f, 1}, {1.0, 1, 1, 1, 1}};
    sh.toe = 0.1, sh.shoulder = 0.2;
    const float bg[3] = {0.25f, 0.45f, 0.85f};
    for (int k = 0; k < 3; ++k) sh.top[k] = sh.bottom[k] = bg[k];
    const output::ValueMapping mapping{-1.0, 1.0};
    const int W = 97, H = 24;
    for (int j = 0; j < H; ++j) sh.subpixel_sd.push_back(float(0.01 * std::pow(50.0, j / (H - 1.0))));
    render::Frame f;
    f.resize(W, H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) f.data[size_t(j) * W + i] = float(-1.6 + 3.2 * i / (W - 1));
    const output::Shader shader(mapping, sh);
    std::vector<float> rgb(size_t(W) * H * 3);
    shader.rows(f, 0, H, rgb.data());
    const double predicted = shader.level_error() + 5.0 / 8192 + 6.3e-4;
    INFO("tables " << shader.levels() << ", level error " << shader.level_error());
    CHECK(shader.levels() > 1);
    CHECK(shader.level_error() < 1e-3);
    double worst = 0.0, worst_unaveraged = 0.0;
    std::vector<float> plain(rgb.size());
    output::Shading unaveraged = sh;
    unaveraged.subpixel_sd.clear();
    output::Shader(mapping, unaveraged).rows(f, 0, H, plain.data());
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double v = f.at(i, j), sd = sh.subpixel_sd[size_t(j)];
            double acc[4] = {0, 0, 0, 0}, wsum = 0.0;
            for (int k = -512; k <= 512; ++k) {
                const double z = k / 64.0, w = std::exp(-0.5 * z * z);
                const double x = (v + sd * z - mapping.lo) / (mapping.hi - mapping.lo);
                double c[4];
                ramp_premultiplied(sh.ramp, output::tone_curve(x, sh.toe, sh.shoulder), c);
                for (int q = 0; q < 4; ++q) acc[q] += w * c[q];
                wsum += w;
            }
            for (int q = 0; q < 3; ++q) {
                const double want = acc[q] / wsum + (1.0 - acc[3] / wsum) * bg[q];
                const size_t p = (size_t(j) * W + i) * 3 + q;
                worst = std::max(worst, std::abs(rgb[p] - want));
                worst_unaveraged = std::max(worst_unaveraged, std::abs(plain[p] - want));
            }
        }
    INFO("largest error " << worst << " (predicted " << predicted << "), unaveraged " << worst_unaveraged);
    CHECK(worst <= predicted);
    // Control: shading each pixel at its value misses the mean by far more (checked by hand:
    // with the Shader not building the averaged tables, the first check fails, 0.23 > 9e-4).
    CHECK(worst_unaveraged > 10.0 * predicted);
}

TEST_CASE("a shaded frame has no bias against its supersampled shaded reference with filter "
          "= \"after\", and has one without", "[scenes][shading][slow]") {
    // ridges (an orthographic sum of three layers under a ramp with a toe and a shoulder) at
    // 64 x 36, 1/20 of its size, so its camera filters (zoom 0.05 < 1): against the same frame
    // rendered unfiltered at 8 x 8 samples per pixel, every sample shaded and filtered with the
    // camera's Gaussian pixel filter (tests/shaded_bias.h). The relief is off: its lighting
    // scales with the pixel (docs/scenes.md "[shading]"), which no filtering makes consistent.
    // The bias over the frame in units of the reference's sd, its standard error from the
    // scatter of 4 x 4-pixel block means (16 x 9 = 144 blocks, each 8 filter sds wide, nearly
    // independent). Measured (frame 0): "before" -0.062, "after" -0.007 (se 0.007); rms 0.170
    // -> 0.125. With the remedy the bias is within 4 se and 0.10 of the sd (the issue's bound);
    // without it (the control) it is beyond 4 se. Checked by hand: with Scene::shading_at not
    // filling subpixel_sd, the first assertion fails (0.062 > 4 se = 0.033).
    const std::vector<std::string> sets = {"shading.relief=0"};
    const int W = 64, H = 36, n = 8;
    const scenes::Renderer coarse(scenes::load_scene(scenes::resolve_scene("ridges"), sets, {W, H}));
    REQUIRE(coarse.scene().shading.filter_after);
    const std::string path = scenes::resolve_scene("ridges");
    const std::vector<double> ref = test::shaded_reference(path, sets, W, H, n, 0, coarse.mapping());
    const test::ShadedBand after = test::shaded_bias(path, sets, W, H, 0, ref, true).bands.at(0);
    const test::ShadedBand before = test::shaded_bias(path, sets, W, H, 0, ref, false).bands.at(0);
    INFO("after: bias " << after.bias << " se " << after.bias_se << " rms " << after.rms);
    INFO("before: bias " << before.bias << " se " << before.bias_se << " rms " << before.rms);
    CHECK(std::abs(after.bias) <= 4.0 * after.bias_se);
    CHECK(std::abs(after.bias) <= 0.10);
    CHECK(after.rms < before.rms);
    CHECK(std::abs(before.bias) > 4.0 * before.bias_se);  // the control
}

TEST_CASE("[shading] filter chooses the averaged ramp; \"before\" and unfiltered frames shade as "
          "they are", "[scenes][shading]") {
    const std::string base = "[output]\nsize = [64, 64]\n[camera]\nzoom = 0.25\n[[layer]]\n"
                             "[layer.kernel]\nradius = 8.0\n[shading]\nramp = \"fire\"\n";
    const scenes::Scene after = scenes::load_scene_string(base, "after.toml");
    REQUIRE(after.shading_at(0.0).subpixel_sd.size() == 1);
    // A cosine kernel of radius 8 under a Gaussian filter of 0.5 px = 2 texture units keeps
    // most of its variance: the sub-pixel sd is a positive fraction of the layer's sd.
    const double sd = std::sqrt(scenes::scene_theory(after).variance);
    CHECK(after.shading_at(0.0).subpixel_sd[0] > 0.05 * sd);
    CHECK(after.shading_at(0.0).subpixel_sd[0] < 0.8 * sd);
    CHECK(scenes::load_scene_string(base + "filter = \"before\"\n", "before.toml")
              .shading_at(0.0).subpixel_sd.empty());
    // Zoom 1: the orthographic camera does not filter, each pixel is a point sample whose
    // distribution is the field's: nothing to average.
    CHECK(scenes::load_scene_string(base, "one.toml", {"camera.zoom=1"}).shading_at(0.0).subpixel_sd.empty());
    CHECK_THROWS_WITH(scenes::load_scene_string(base + "filter = \"later\"\n", "bad.toml"),
                      Catch::Contains("bad.toml:10:10:") && Catch::Contains("shading.filter = \"later\"") &&
                          Catch::Contains("after, before"));
}

TEST_CASE("clouds' sky has no bias beyond 0.10 of its bands' sd against its supersampled shaded "
          "reference with filter = \"after\"", "[scenes][shading][slow]") {
    // clouds (a perspective sky: the sub-pixel sd per row, docs/shading.md "The sub-pixel sd")
    // at 128 x 72 against 8 x 8 samples per pixel, frame 0, eight bands of rows from the top;
    // rows 54-72 are the sea (bands 6 and 7), which the remedy does not reach (docs/shading.md
    // "What it leaves"). Measured, bias / band sd before -> after: 0.008 -> -0.007,
    // 0.020 -> 0.005, 0.012 -> 0.004, -0.050 -> -0.043, -0.055 -> -0.019 and, in the band above
    // the horizon, -0.248 -> 0.072 (se 0.020, from 4 x 4-pixel block means). The bound is the
    // issue's, 0.10 of the band's sd, in every sky band; the rms falls in every sky band. The
    // control: without the remedy the band above the horizon is off by more than 0.10 (and by
    // 12 se). Checked by hand: with Scene::shading_at not filling subpixel_sd, the band above
    // the horizon fails the bound.
    const std::string path = scenes::resolve_scene("clouds");
    const int W = 128, H = 72, n = 8;
    const scenes::Renderer coarse(scenes::load_scene(path, {}, {W, H}));
    const std::vector<double> ref = test::shaded_reference(path, {}, W, H, n, 0, coarse.mapping());
    const test::ShadedBias after = test::shaded_bias(path, {}, W, H, 0, ref, true);
    const test::ShadedBias before = test::shaded_bias(path, {}, W, H, 0, ref, false);
    REQUIRE(after.bands.size() == 8);
    CHECK(after.levels > 1);
    for (size_t b = 0; b < 6; ++b) {
        const test::ShadedBand &a = after.bands[b], &z = before.bands[b];
        INFO("band " << b << " rows " << a.row0 << "-" << a.row1 << ": bias " << z.bias << " -> "
                     << a.bias << " (se " << a.bias_se << "), rms " << z.rms << " -> " << a.rms);
        CHECK(std::abs(a.bias) <= 0.10);
        CHECK(a.rms < z.rms);
    }
    CHECK(std::abs(before.bands[5].bias) > 0.10);  // the control
}

TEST_CASE("the coverage of an averaged ramp is the alpha its colours are composited with",
          "[scenes][shading]") {
    // The RGBA channels output writes shade() over black with shading_alpha() as A: with a
    // sub-pixel sd both come from the averaged ramp. Over black a pixel is E[a c], over white
    // E[a c] + 1 - E[a]; their difference gives E[a], which shading_alpha must return (float
    // rounding: 1e-5). Control: the ramp's own alpha (without the sub-pixel sd) misses by far
    // more.
    output::Shading sh;
    sh.ramp = {{0.0, 1, 1, 1, 0}, {0.45, 1, 1, 1, 0}, {0.62, 0.9f, 0.9f, 0.95f, 0.85f}, {1.0, 1, 1, 1, 1}};
    const int W = 41, H = 6;
    for (int j = 0; j < H; ++j) sh.subpixel_sd.push_back(float(0.05 * (j + 1)));
    render::Frame f;
    f.resize(W, H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) f.data[size_t(j) * W + i] = float(-1.2 + 2.4 * i / (W - 1));
    std::vector<float> black, white, alpha;
    for (int k = 0; k < 3; ++k) sh.top[k] = sh.bottom[k] = 0.0f;
    output::shade(f, {-1.0, 1.0}, sh, black);
    for (int k = 0; k < 3; ++k) sh.top[k] = sh.bottom[k] = 1.0f;
    output::shade(f, {-1.0, 1.0}, sh, white);
    output::shading_alpha(f, {-1.0, 1.0}, sh, alpha);
    double worst = 0.0;
    for (size_t p = 0; p < alpha.size(); ++p)
        worst = std::max(worst, std::abs(double(alpha[p]) - (1.0 - (white[3 * p] - black[3 * p]))));
    CHECK(worst < 1e-5);
    std::vector<float> unaveraged;
    output::Shading plain = sh;
    plain.subpixel_sd.clear();
    output::shading_alpha(f, {-1.0, 1.0}, plain, unaveraged);
    double miss = 0.0;
    for (size_t p = 0; p < alpha.size(); ++p)
        miss = std::max(miss, std::abs(double(unaveraged[p]) - (1.0 - (white[3 * p] - black[3 * p]))));
    INFO("unaveraged alpha misses by " << miss);
    CHECK(miss > 0.1);
}
