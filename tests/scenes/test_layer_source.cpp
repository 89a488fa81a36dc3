// SPDX-License-Identifier: Apache-2.0
// The layer-source seam (scenes/source.h): a layer drawn by another synthesizer is composed,
// shaded, warped, read for orientation and stated in theory like an impulse layer.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <string>

#include "numeric/gaussian.h"
#include "numeric/rng.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"

namespace {

using namespace impulse;

/// Lattice white noise: f(x) = Z(floor(x / cell), floor(y / cell)), Z standard normal from the
/// counter RNG keyed by the lattice node and time cell (a new field every 1/20 s). A pure
/// function of position and time, as every source must be.
class LatticeNoise final : public scenes::LayerSource {
public:
    explicit LatticeNoise(double cell) : m_cell(cell) {}
    std::string_view kind() const override { return "lattice"; }
    void add(const numeric::View& v, double t_s, numeric::Frame& out) const override {
        const numeric::CounterRng rng(99, 3);
        const int64_t tc = static_cast<int64_t>(std::floor(t_s * 20.0));
        for (int j = 0; j < v.height; ++j)
            for (int i = 0; i < v.width; ++i) {
                const double x = v.x0 + (i + 0.5) * v.scale, y = v.y0 + (j + 0.5) * v.scale;
                out.data[size_t(j) * v.width + i] += static_cast<float>(value(rng, x, y, tc));
            }
    }
    scenes::Theory theory(double) const override { return {0.0, 1.0}; }
    double correlation_length() const override { return m_cell; }

    double value(const numeric::CounterRng& rng, double x, double y, int64_t tc) const {
        const auto u = rng.uniforms(int64_t(std::floor(x / m_cell)),
                                    int64_t(std::floor(y / m_cell)), tc, 0);
        return numeric::normal_quantile(u[0], 1.0 - u[0]);
    }

private:
    double m_cell;
};

/// Two cosine layers, 256^2; layer 0 is then given a source.
std::string two_layers(const std::string& layer0_extra, const std::string& layer1_extra) {
    return R"(
[output]
size = [256, 256]
frames = 4
[[layer]]
seed = 1
)" + layer0_extra + R"(
[layer.kernel]
type = "cosine"
radius = 8.0
[[layer]]
seed = 2
)" + layer1_extra + R"(
[layer.kernel]
type = "cosine"
radius = 8.0
)";
}

scenes::Scene with_source(const std::string& text, double cell = 1.0) {
    scenes::Scene s = scenes::load_scene_string(text, "source.toml");
    s.layers[0].source = std::make_shared<LatticeNoise>(cell);
    return s;
}

render::Frame render_frame(scenes::Scene s, int64_t frame = 0) {
    scenes::Renderer r(std::move(s));
    render::Frame f;
    r.render(frame, f);
    return f;
}

}  // namespace

TEST_CASE("a source layer renders the source's field through its gain and mean",
          "[scenes][source]") {
    scenes::Scene s = with_source(two_layers("gain = 2.5\nmean = 0.75", "visible = false"));
    const numeric::View v = s.camera.view(256, 256, 0.0);
    const render::Frame f = render_frame(s);
    const LatticeNoise noise(1.0);
    const numeric::CounterRng rng(99, 3);
    for (int j = 0; j < 256; j += 17)
        for (int i = 0; i < 256; i += 13) {
            const double x = v.x0 + (i + 0.5) * v.scale, y = v.y0 + (j + 0.5) * v.scale;
            const float expected = static_cast<float>(
                0.75f + static_cast<float>(2.5 * float(noise.value(rng, x, y, 0))));
            CHECK(f.at(i, j) == expected);
        }
    const scenes::Theory th = scenes::layer_theory(s.layers[0]);
    CHECK(th.mean == 0.75);
    CHECK(th.variance == 2.5 * 2.5);
    CHECK(!scenes::is_sum_of_layers(s));
}

TEST_CASE("a source layer's measured moments match its stated theory", "[scenes][source][stats]") {
    // 256^2 independent lattice values (cell = 1 texture unit = 1 pixel): the sample mean has
    // sd g / 256, the sample variance sd g^2 sqrt(2 / 65536); bands of 5 sd.
    scenes::Scene s = with_source(two_layers("gain = 2.0\nmean = 1.0", "visible = false"));
    const scenes::Theory th = scenes::scene_theory(s);
    const render::Frame f = render_frame(s);
    double sum = 0.0, sq = 0.0;
    for (float x : f.data) sum += x, sq += double(x) * x;
    const double n = double(f.data.size()), m = sum / n, var = sq / n - m * m;
    CHECK(std::abs(m - th.mean) < 5.0 * 2.0 / 256.0);
    CHECK(std::abs(var - th.variance) < 5.0 * 4.0 * std::sqrt(2.0 / n));
}

TEST_CASE("a source layer multiplies an impulse layer as any layer does", "[scenes][source]") {
    const std::string text = two_layers("", "blend = \"multiply\"");
    const render::Frame both = render_frame(with_source(text));
    scenes::Scene alone0 = with_source(two_layers("", "visible = false"));
    scenes::Scene alone1 = scenes::load_scene_string(two_layers("visible = false", ""), "b.toml");
    const render::Frame a = render_frame(alone0), b = render_frame(alone1);
    for (size_t p = 0; p < both.data.size(); p += 97) CHECK(both.data[p] == a.data[p] * b.data[p]);
}

TEST_CASE("a source layer shaped by its measured marginal hits a uniform target",
          "[scenes][source][stats]") {
    // cdf = "empirical": F_x is measured on the source itself (calibrate_marginal's source
    // path); the shaped values are uniform on [0, 1]: mean 1/2 and variance 1/12, sampling sd
    // sqrt(1/12 / n) and sqrt(1/180 / n) for n = 65536 independent values; bands of 5 sd.
    const std::string marginal =
        "marginal = { type = \"uniform\", a = 0.0, b = 1.0, cdf = \"empirical\" }";
    scenes::Scene s = with_source(two_layers(marginal, "visible = false"));
    const render::Frame f = render_frame(s);
    double sum = 0.0, sq = 0.0;
    for (float x : f.data) sum += x, sq += double(x) * x;
    const double n = double(f.data.size()), m = sum / n, var = sq / n - m * m;
    CHECK(std::abs(m - 0.5) < 5.0 * std::sqrt(1.0 / 12.0 / n));
    CHECK(std::abs(var - 1.0 / 12.0) < 5.0 * std::sqrt(1.0 / 180.0 / n));
}

TEST_CASE("a source layer warps, orients and animates like an impulse layer",
          "[scenes][source]") {
    // As a warp source of layer 1 and as its orientation source: frames render and differ from
    // the unwarped, unoriented layer; the source's time cells make frames differ in time.
    const std::string text = two_layers(
        "visible = false\nname = \"field\"",
        "warp = { source = [\"field\", \"field\"], amount = 4.0 }\n"
        "orientation = { type = \"layer\", source = \"field\" }");
    const render::Frame warped = render_frame(with_source(text, 16.0));
    scenes::Scene plain = scenes::load_scene_string(two_layers("visible = false", ""), "p.toml");
    CHECK(!test::same_bits(warped, render_frame(plain)));
    scenes::Scene s = with_source(two_layers("", "visible = false"));
    CHECK(!test::same_bits(render_frame(s, 0), render_frame(s, 3)));
    // Frame independence: frame 3 alone equals frame 3 after frames 0..2.
    scenes::Renderer r(with_source(text, 16.0));
    render::Frame f;
    for (int64_t k = 0; k <= 3; ++k) r.render(k, f);
    CHECK(test::same_bits(f, render_frame(with_source(text, 16.0), 3)));
}

TEST_CASE("a source layer under a perspective camera is refused with one line",
          "[scenes][source][errors]") {
    scenes::Scene s = with_source("[camera]\ntype = \"perspective\"\n" + two_layers("", ""));
    REQUIRE_THROWS_WITH(scenes::Renderer(std::move(s)),
                        Catch::Contains("layer[0]: a lattice layer is seen through an "
                                        "orthographic camera only"));
}
