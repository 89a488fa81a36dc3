// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "fbm": a fractional Brownian surface as a layer (scenes/sources/source_fbm.cpp on the
// layer-source seam): its measured variance against the stated theory, and its bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/scenes.h"
#include "synth/synth.h"
#include "tests/scene_render.h"

namespace {

using namespace impulse;

/// A 64 x 64 frame whose pixel centres sit on the 64 x 64 samples of one tile (size = samples,
/// so one sample per texture unit; centre 32 + offset puts pixel i at sample i + offset + 0.5 -
/// 0.5).
std::string fbm_scene(const std::string& method, double hurst, int seed, double offset) {
    return "seed = " + std::to_string(seed) + R"(
[output]
size = [64, 64]
[camera]
center = [)" + std::to_string(32.0 + offset) + ", " + std::to_string(32.0 + offset) + R"(]
[[layer]]
source = "fbm"
[layer.fbm]
method = ")" + method + R"("
hurst = )" + std::to_string(hurst) + R"(
samples = 64
)";
}

struct Moments {
    double mean = 0, variance = 0;
};
Moments spatial(const render::Frame& f) {
    double s = 0, q = 0;
    for (float v : f.data) s += v, q += double(v) * v;
    const double n = double(f.data.size());
    return {s / n, q / n - (s / n) * (s / n)};
}

/// Mean over `seeds` realisations of the frame's spatial variance, and its standard error from
/// their scatter.
std::pair<double, double> variance_over_seeds(const std::string& method, double hurst, int seeds,
                                              double offset, double& theory) {
    std::vector<double> v;
    for (int s = 1; s <= seeds; ++s) {
        scenes::Scene scene = scenes::load_scene_string(fbm_scene(method, hurst, s, offset), "f.toml");
        theory = scenes::layer_theory(scene.layers[0]).variance;
        scenes::Renderer r(std::move(scene));
        render::Frame f;
        r.render(0, f);
        v.push_back(spatial(f).variance);
    }
    double m = 0, q = 0;
    for (double x : v) m += x;
    m /= double(v.size());
    for (double x : v) q += (x - m) * (x - m);
    return {m, std::sqrt(q / double(v.size() - 1) / double(v.size()))};
}

}  // namespace

TEST_CASE("an fbm layer's measured variance matches its stated theory",
          "[scenes][source][fbm][stats][slow]") {
    // The frame's pixels sit on the tile's samples (offset 0.5: pixel i at sample i + 1,
    // wrapped, for the periodic Fourier field; offset -0.5: samples 0..63 of the exact method's
    // tile). The spatial variance of one realisation about its mean has expectation R(0)
    // (Fourier, synth::fourier_fbm_variance) or (1/2) E|x - y|^{2H} over the tile (exact fBm,
    // synth::fbm_tile_variance); over 160 seeds the mean is within 5 standard errors (of the 160
    // values' own scatter).
    for (double hurst : {0.3, 0.8}) {
        double theory = 0;
        auto [m, se] = variance_over_seeds("fourier", hurst, 160, 0.5, theory);
        CAPTURE(hurst, m, se, theory);
        CHECK(theory == Approx(synth::fourier_fbm_variance({synth::FbmMethod::Fourier, hurst, 64, true})));
        CHECK(std::abs(m - theory) < 5.0 * se);
        auto [me, see] = variance_over_seeds("exact", hurst, 160, -0.5, theory);
        CAPTURE(me, see, theory);
        CHECK(theory == Approx(synth::fbm_tile_variance(hurst, 64)));
        CHECK(std::abs(me - theory) < 5.0 * see);
    }
}

TEST_CASE("fbm tile variance: (1/2) E|x - y|^{2H} in closed form for H = 1/2 in 1-D terms",
          "[synth][fbm]") {
    // For H = 1/2, |d|^{2H} = |d|: the exact sum, brute-forced over all pairs of a 6 x 6 tile.
    const int n = 6;
    double sum = 0;
    for (int a = 0; a < n * n; ++a)
        for (int b = 0; b < n * n; ++b)
            sum += std::hypot(double(a % n - b % n), double(a / n - b / n));
    CHECK(synth::fbm_tile_variance(0.5, n) == Approx(0.5 * sum / std::pow(n, 4)).epsilon(1e-12));
}

TEST_CASE("an fbm layer's tile mean is removed and its frame is the same in any tiling",
          "[scenes][source][fbm]") {
    scenes::Scene s = scenes::load_scene_string(fbm_scene("incremental", 0.6, 3, -0.5), "f.toml");
    CHECK(scenes::layer_theory(s.layers[0]).mean == 0.0);
    scenes::Renderer r(s);
    render::Frame f;
    r.render(0, f);
    CHECK(std::abs(spatial(f).mean) < 1e-5);
    render::EvalOptions small_tiles;
    small_tiles.tile_size = 8;
    render::Frame g;
    scenes::Renderer(s).render(0, g, small_tiles);
    CHECK(test::same_bits(f, g));
}

TEST_CASE("source layers' tiles are held to limits.max_memory_mib together, as they load",
          "[scenes][source][fbm][errors]") {
    // A default fbm layer (256^2, incremental) needs `need` MiB while it is made and then holds
    // its tile (4 bytes a sample). With the limit at 3.5 tiles + need, layers 0-3 fit beside the
    // tiles held before them and layer 4 does not, although each alone fits (the loader checked
    // each alone, and a scene of many layers held their sum).
    synth::FbmOptions o;
    o.size = 256;
    const double mib = 1024.0 * 1024.0, tile = 4.0 * 256 * 256 / mib;
    const double need = synth::fbm_memory_bytes(o) / mib, limit = 3.5 * tile + need;
    auto scene = [&](int fbm_layers, const std::string& last) {
        std::string t =
            "[output]\nsize = [32, 32]\n[limits]\nmax_memory_mib = " + std::to_string(limit) + "\n";
        for (int i = 0; i < fbm_layers; ++i)
            t += "[[layer]]\nsource = \"fbm\"\nseed = " + std::to_string(i + 1) + "\n";
        return t + last;
    };
    CHECK_NOTHROW(scenes::load_scene_string(scene(4, ""), "held.toml"));
    REQUIRE_THROWS_WITH(
        scenes::load_scene_string(scene(5, ""), "held.toml"),
        Catch::Contains("layer[4].source = \"fbm\": the default 256^2 surface needs an "
                        "estimated 1.51 MiB, over the 1.38 MiB that limits.max_memory_mib "
                        "= 2.38 leaves beside the earlier source layers' tiles (1 MiB)"));
    // A subdivision tile shares the budget: 256^2 samples need 1.5 MiB (3 doubles a sample),
    // which fit the limit alone, not beside four fbm tiles.
    const std::string subdivision =
        "[[layer]]\nsource = \"subdivision\"\n[layer.subdivision]\n"
        "acf = \"markov\"\nlength = 8.0\nsamples = 256\n";
    CHECK_NOTHROW(scenes::load_scene_string(scene(0, subdivision), "held.toml"));
    REQUIRE_THROWS_WITH(
        scenes::load_scene_string(scene(4, subdivision), "held.toml"),
        Catch::Contains(
            "layer[4].subdivision.samples = 256: the field needs an estimated 1.5 MiB, over "
            "the 1.38 MiB that limits.max_memory_mib = 2.38 leaves beside"));
}

TEST_CASE("an fbm layer's bad input is one line at the key", "[scenes][source][fbm][errors]") {
    const std::string base = "[output]\nsize = [64, 64]\n[[layer]]\nsource = \"fbm\"\n";
    auto fails_with = [&](const std::string& text, const std::string& what) {
        CAPTURE(text);
        REQUIRE_THROWS_WITH(scenes::load_scene_string(text, "bad.toml"), Catch::Contains(what));
    };
    fails_with(base + "[layer.fbm]\nhurst = 1.5\n", "bad.toml:6:9: layer[0].fbm.hurst = 1.5");
    fails_with(base + "[layer.fbm]\nsamples = 100\n", "expected a power of two in [2, 4096]");
    fails_with(base + "[layer.fbm]\nmethod = \"wavelet\"\n", "fourier, incremental, exact");
    fails_with("[limits]\nmax_memory_mib = 64\n" + base + "[layer.fbm]\nsamples = 4096\n",
               "layer[0].fbm.samples = 4096: the surface needs an estimated");
    fails_with(base + "density = 4.0\n", "a fbm layer has no density");
    fails_with(base + "[layer.kernel]\ntype = \"cosine\"\n", "a fbm layer has no kernel");
    fails_with("[[layer]]\nsource = \"fbmish\"\n", "impulses, fbm");
    // A stream function must be an impulse layer's field.
    fails_with(base + "name = \"h\"\nvisible = false\n[[layer]]\nlifetime = 2.0\n[[layer.flow]]\ntype = "
                      "\"layer\"\nsource = \"h\"\n",
               "is a fbm layer");
    // Seen through a perspective camera too (tests/scenes/test_source_perspective.cpp).
    CHECK_NOTHROW(scenes::Renderer(scenes::load_scene_string("[camera]\ntype = \"perspective\"\n" + base,
                                                             "p.toml")));
}
