// SPDX-License-Identifier: Apache-2.0
// Frame independence and consistency of animated scenes (design.md §3, §4): with flows
// (wind + vortex + curl noise), finite lifetimes and orientation from the flow, a frame's bits do
// not depend on how it was reached — sequentially, alone, after a jump forward or back, on 1 or 2
// threads, with any tile size, or in a split range — and loops repeat exactly: frame P*fps
// equals frame 0 for a steady flow, in a periodic domain, and for a keyframed flow whose time is
// wrapped into the loop (simulator.cpp, State::time_of_step).

#include <tbb/global_control.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;

namespace {

// Two layers: anisotropic Gaussian kernels spun by the vorticity, and cosine kernels aligned
// with the flow, both in wind + Lamb–Oseen vortex + curl noise. 96x96 at 24 fps, 1.5 s and
// 1.0 s lifetimes.
const char* kFlowScene = R"(
[output]
size = [96, 96]
fps = 24
frames = 20000

[[layer]]
seed = 3
density = 12.0
lifetime = 1.5
envelope = "hann"
orientation = "vorticity"
[layer.kernel]
type = "gaussian"
radius = 10.0
sigma = 3.5
aspect = 1.6

[[layer.flow]]
type = "uniform"
velocity = [14.0, -5.0]

[[layer.flow]]
type = "vortex"
center = [40.0, 50.0]
circulation = 3000.0
core = 20.0
model = "lamb-oseen"

[[layer.flow]]
type = "curl"
scale = 40.0
speed = 8.0

[[layer]]
seed = 4
density = 16.0
gain = 0.5
lifetime = 1.0
orientation = "flow"
[layer.kernel]
type = "cosine"
radius = 5.0
aspect = 2.0

[[layer.flow]]
type = "uniform"
velocity = [14.0, -5.0]

[[layer.flow]]
type = "curl"
scale = 40.0
speed = 8.0
)";

scenes::Scene load(const std::string& text) {
    return scenes::load_scene_string(text, "identity.toml");
}

bool same_bits(const render::Frame& a, const render::Frame& b) {
    return a.width == b.width && a.height == b.height && a.data.size() == b.data.size() &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

/// Largest |a - b| over the pixels (for messages when bits differ).
double max_diff(const render::Frame& a, const render::Frame& b) {
    double m = 0.0;
    for (size_t i = 0; i < std::min(a.data.size(), b.data.size()); ++i)
        m = std::max(m, std::abs(double(a.data[i]) - b.data[i]));
    return m;
}

/// A frame that is not trivially constant (guards against comparing two empty frames).
bool has_signal(const render::Frame& f) {
    double s = 0.0;
    for (float v : f.data) s += double(v) * v;
    return s / f.data.size() > 1e-3;
}

/// Frames first..last rendered in order by one Renderer.
std::vector<render::Frame> sequence(const std::string& text, int64_t first, int64_t last,
                                    const render::EvalOptions& eo = {}) {
    scenes::Renderer r(load(text));
    std::vector<render::Frame> out(static_cast<size_t>(last - first + 1));
    for (int64_t f = first; f <= last; ++f) r.render(f, out[static_cast<size_t>(f - first)], eo);
    return out;
}

/// Frame f rendered alone by a fresh Renderer (integrated from birth).
render::Frame alone(const std::string& text, int64_t f) {
    scenes::Renderer r(load(text));
    render::Frame out;
    r.render(f, out);
    return out;
}

}  // namespace

TEST_CASE("motion identity: sequential frames equal frames rendered alone", "[sim][determinism]") {
    const auto seq = sequence(kFlowScene, 0, 23);
    for (int64_t f = 0; f < 24; ++f) {
        INFO("frame " << f);
        const render::Frame a = alone(kFlowScene, f);
        CHECK(has_signal(a));
        CHECK(same_bits(seq[static_cast<size_t>(f)], a));
        if (!same_bits(seq[static_cast<size_t>(f)], a))
            WARN("max |diff| = " << max_diff(seq[f], a));
    }
    // Motion really happens: consecutive frames differ.
    CHECK_FALSE(same_bits(seq[0], seq[1]));
}

TEST_CASE("motion identity: jumps forward and back equal fresh renders", "[sim][determinism]") {
    scenes::Renderer r(load(kFlowScene));
    render::Frame f;
    for (int64_t frame : {5, 17, 40, 12, 0, 300, 299, 301}) {
        INFO("frame " << frame);
        r.render(frame, f);
        CHECK(same_bits(f, alone(kFlowScene, frame)));
    }
}

TEST_CASE("motion identity: 1 thread, 2 threads, any tile size, serial path",
          "[sim][determinism]") {
    std::vector<render::Frame> one, two;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = sequence(kFlowScene, 0, 15);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        two = sequence(kFlowScene, 0, 15);
    }
    render::EvalOptions small_tiles;
    small_tiles.tile_size = 8;
    const auto tiled = sequence(kFlowScene, 0, 15, small_tiles);
    render::EvalOptions serial;
    serial.parallel = false;
    serial.tile_size = 40;
    const auto ser = sequence(kFlowScene, 0, 15, serial);
    for (size_t i = 0; i < one.size(); ++i) {
        INFO("frame " << i);
        CHECK(same_bits(one[i], two[i]));
        CHECK(same_bits(one[i], tiled[i]));
        CHECK(same_bits(one[i], ser[i]));
    }
}

TEST_CASE("motion identity: split frame ranges equal one run", "[sim][determinism]") {
    const auto whole = sequence(kFlowScene, 0, 19);
    const auto a = sequence(kFlowScene, 0, 9);
    const auto b = sequence(kFlowScene, 10, 19);
    for (size_t i = 0; i < 10; ++i) {
        INFO("frame " << i << " and " << i + 10);
        CHECK(same_bits(whole[i], a[i]));
        CHECK(same_bits(whole[i + 10], b[i]));
    }
}

TEST_CASE("motion identity: a far frame alone equals stepping to it", "[sim][determinism]") {
    const auto stepped = sequence(kFlowScene, 9990, 10000);
    const render::Frame far = alone(kFlowScene, 10000);
    CHECK(has_signal(far));
    CHECK(same_bits(stepped.back(), far));
    CHECK(same_bits(stepped.front(), alone(kFlowScene, 9990)));
}

TEST_CASE("motion identity: output.start shifts the timeline by whole frames",
          "[sim][determinism]") {
    // start = 5 s = 120 frames at 24 fps: frame k of the shifted scene is frame k + 120.
    std::string shifted = kFlowScene;
    shifted.replace(shifted.find("frames = 20000"), 14, "frames = 20000\nstart = 5.0");
    const auto a = sequence(shifted, 0, 3);
    const auto b = sequence(kFlowScene, 120, 123);
    for (size_t i = 0; i < a.size(); ++i) {
        INFO("frame " << i);
        CHECK(same_bits(a[i], b[i]));
    }
}

namespace {

/// One layer, 96x96 at 24 fps, lifetime 1.5 s, loop 2 s (48 frames), with the given extra layer
/// keys and flows.
std::string loop_scene(const std::string& layer_keys, const std::string& flows) {
    return "[output]\nsize = [96, 96]\nfps = 24\nframes = 200\n\n[[layer]]\nseed = 9\n"
           "density = 16.0\nlifetime = 1.5\nloop = 2.0\nenvelope = \"hann\"\n"
           "orientation = \"vorticity\"\n" +
           layer_keys +
           "[layer.kernel]\ntype = \"gaussian\"\nradius = 10.0\nsigma = 3.5\naspect = 1.5\n\n" +
           flows;
}

/// Frames k and k + P*fps (and k + 2 P fps) agree bit for bit, sequentially and alone, and the
/// loop is not trivially static.
void check_loop(const std::string& text) {
    constexpr int64_t kPeriod = 48;  // 2 s at 24 fps
    const auto seq = sequence(text, 0, 2 * kPeriod + 2);
    CHECK(has_signal(seq[0]));
    CHECK_FALSE(same_bits(seq[0], seq[kPeriod / 2]));
    for (int64_t k : {0, 1, 2}) {
        INFO("frame " << k << " vs " << k + kPeriod << " and " << k + 2 * kPeriod);
        CHECK(same_bits(seq[k], seq[k + kPeriod]));
        CHECK(same_bits(seq[k], seq[k + 2 * kPeriod]));
        if (!same_bits(seq[k], seq[k + kPeriod]))
            WARN("max |diff| = " << max_diff(seq[k], seq[k + kPeriod]));
    }
    CHECK(same_bits(seq[0], alone(text, kPeriod)));
    CHECK(same_bits(seq[1], alone(text, 3 * kPeriod + 1)));
}

}  // namespace

TEST_CASE("motion identity: a loop with a steady flow repeats exactly", "[sim][determinism]") {
    check_loop(loop_scene("",
                          "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [12.0, 5.0]\n\n"
                          "[[layer.flow]]\ntype = \"vortex\"\ncenter = [48.0, 48.0]\n"
                          "circulation = 2500.0\ncore = 18.0\n"));
}

TEST_CASE("motion identity: a loop in a periodic domain repeats exactly and tiles",
          "[sim][determinism]") {
    // Period = frame size; the wind and the curl noise (scale 32 divides 96) are periodic.
    const std::string text =
        loop_scene("period = [96.0, 96.0]\n",
                   "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [12.0, 5.0]\n\n"
                   "[[layer.flow]]\ntype = \"curl\"\nscale = 32.0\nspeed = 8.0\n");
    check_loop(text);

    // Tiling: the camera moved by exactly one period sees the same field. Positions then differ
    // by 96 in double, so kernel offsets round differently: equal to float rounding of the
    // field, |diff| <= 1e-4 (values are O(1); a seam or a missing copy would be O(0.1)).
    const std::string shifted = text + "\n[camera]\ncenter = [144.0, 48.0]\n";
    for (int64_t f : {0, 30}) {
        INFO("frame " << f);
        const render::Frame a = alone(text, f), b = alone(shifted, f);
        CHECK(max_diff(a, b) < 1e-4);
    }
}

TEST_CASE("motion identity: a loop with a keyframed, non-periodic flow repeats exactly",
          "[sim][determinism]") {
    // vx ramps 0 -> 30 over the loop and would keep rising; the flow time is wrapped into the
    // loop (time_of_step), so looped copies see the same flow and the loop still closes.
    check_loop(
        loop_scene("",
                   "[[layer.flow]]\ntype = \"uniform\"\nvx = { keys = [[0.0, 0.0], [2.0, 30.0], "
                   "[4.0, 60.0]] }\n"
                   "vy = 4.0\n\n"
                   "[[layer.flow]]\ntype = \"vortex\"\ncenter = [48.0, 48.0]\n"
                   "circulation = { keys = [[0.0, 1000.0], [3.0, 4000.0]], ease = \"smooth\" }\n"
                   "core = 18.0\n"));
}
