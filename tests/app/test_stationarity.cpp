// SPDX-License-Identifier: Apache-2.0
// The stationarity verdict of `impulse analyze`, calibrated on seeds (issue 18): a scene without
// flow is called "not stationary" at the stated family rate (1 %), and a source whose rate pulses,
// rendered without sqrt(J) so the variance swings with it, is called "not stationary". A small
// version of the calibration reported in the closing note (24 seeds of 300 frames of 192^2).

#include <catch2/catch.hpp>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "analysis/analyze.h"
#include "scenes/closed_form.h"
#include "scenes/scenes.h"
#include "tests/support.h"

namespace {

using impulse::analysis::Image;

/// 64^2 frames of a cosine layer (radius 4, density 16, lifetime 2 s) at 10 fps; `pulse`: a
/// source at the centre whose rate goes 0 -> 0.4/s -> 0 every 5 s, without sqrt(J).
std::string scene_text(bool pulse, int seed) {
    std::string s = "[output]\nsize = [64, 64]\nframes = 150\nfps = 10\n[[layer]]\nseed = " +
                    std::to_string(seed) + "\ndensity = 16.0\nlifetime = 2.0\n";
    if (pulse) s += "jacobian = false\n";
    s += "[layer.kernel]\ntype = \"cosine\"\nradius = 4.0\n";
    if (pulse)
        s += "[[layer.flow]]\ntype = \"source\"\ncenter = [32.0, 32.0]\nrate = { keys = [[0.0, 0.0], "
             "[2.5, 0.4], [5.0, 0.0], [7.5, 0.4], [10.0, 0.0], [12.5, 0.4], [15.0, 0.0]], ease = "
             "\"smooth\" }\n";
    return s;
}

/// Renders a scene file written from `text` and analyses its frames against it.
std::vector<Image> render_frames(const std::string& path) {
    impulse::scenes::Renderer renderer(impulse::scenes::load_scene(path));
    std::vector<Image> frames;
    for (int f = 0; f < renderer.scene().output.frames; ++f) {
        impulse::render::Frame out;
        renderer.render(f, out);
        frames.push_back(Image{out.width, out.height, std::move(out.data)});
    }
    return frames;
}

/// `frames_out`: when given, receives a copy of the rendered frames.
impulse::analysis::AnalysisResult analyse_result(const impulse::test::TempDir& dir,
                                                 const std::string& name, const std::string& text,
                                                 std::vector<Image>* frames_out = nullptr) {
    const std::string path = dir / (name + ".toml");
    std::ofstream(path) << text;
    std::vector<Image> frames = render_frames(path);
    if (frames_out) *frames_out = frames;
    impulse::analysis::AnalyzeOptions opt;
    opt.input = path;
    opt.scene = path;
    const auto theory = impulse::scenes::closed_form(path, {});
    const auto r = impulse::analysis::analyze_frames(std::move(frames), opt, "sequence", true, 32, 0,
                                                     theory.get());
    REQUIRE(r.stationarity.available);
    REQUIRE(r.stationarity.level_model == "scene theory");
    return r;
}

impulse::analysis::Stationarity analyse(const impulse::test::TempDir& dir, const std::string& name,
                                        const std::string& text) {
    return analyse_result(dir, name, text).stationarity;
}

/// A drift-like blurred animation: the cosine layer of scene_text carried by a wind of
/// (60, 15) px/s (6.2 px a frame) over the pulsing source, seen through a half-open shutter
/// (docs/motion_blur.md): each kernel is averaged over 3.1 px of its path, by 8 copies within
/// 0.004 of its peak (the default 1e-3 takes 16 and twice the time; the variance moves by less
/// than 1 %, a third of the pooled variance's sd). `jacobian`: sqrt(J)
/// on (the rate's pulse keeps the field stationary) or off (the variance swings with it).
std::string blurred_text(bool jacobian, int seed, double shutter = 0.5) {
    std::string s = "[output]\nsize = [64, 64]\nframes = 100\nfps = 10\n[camera]\nshutter = " +
                    std::to_string(shutter) + "\nshutter_error = 0.004\n[[layer]]\nseed = " + std::to_string(seed) +
                    "\ndensity = 16.0\nlifetime = 2.0\njacobian = " + (jacobian ? "true" : "false") +
                    "\n[layer.kernel]\ntype = \"cosine\"\nradius = 4.0\n"
                    "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [60.0, 15.0]\n"
                    "[[layer.flow]]\ntype = \"source\"\ncenter = [32.0, 32.0]\nrate = { keys = "
                    "[[0.0, 0.0], [2.5, 0.4], [5.0, 0.0], [7.5, 0.4], [10.0, 0.0]], ease = \"smooth\" }\n";
    return s;
}

std::string verdict(const impulse::test::TempDir& dir, bool pulse, int seed) {
    const auto st = analyse(dir, (pulse ? "pulse_" : "still_") + std::to_string(seed),
                            scene_text(pulse, seed));
    // Enough impulses and kernel widths in the window for the level tests (about 360 equivalent
    // degrees of freedom per block mean, the minimum 100): the gate must not touch them.
    REQUIRE(st.block_dof >= st.min_block_dof);
    return st.verdict;
}

}  // namespace

TEST_CASE("stationarity verdict: calibrated false alarms, a pulsing source seen",
          "[app][analyze][stats]") {
    impulse::test::TempDir dir;
    // 8 seeds each. No flow: the verdict's family rate is 0.01, so two or more false alarms in
    // 8 have probability 0.0027. The pulse: the per-frame variance swings by about a third
    // (z of the block means 5-10 on these frames); at most one miss is allowed.
    int alarms = 0, seen = 0, inconclusive = 0;
    for (int seed = 1; seed <= 8; ++seed) {
        const std::string still = verdict(dir, false, seed);
        alarms += still == "not stationary";
        inconclusive += still == "inconclusive";
        seen += verdict(dir, true, seed) == "not stationary";
    }
    INFO("no flow: " << alarms << " false alarms, " << inconclusive << " inconclusive; pulse: "
                     << seen << " of 8 seen");
    CHECK(alarms <= 1);
    CHECK(seen >= 7);
}

TEST_CASE("stationarity verdict: too few impulses in the window make the level tests inconclusive",
          "[app][analyze][stats]") {
    // A stationary scene like drift's largest octave in a small crop: Gaussian sigma 40 (R 120)
    // in a 48^2 window, 5 random-sign impulses per truncation disc, 6 s lifetimes, 6 s of frames.
    // A block mean of the frame variance is worth about 0.7 equivalent degrees of freedom, far
    // below the 100 the level tests' z needs (docs/stationarity.md): the verdict must not say
    // "not stationary" on any seed and must say why. Without the gate the level tests reject
    // on 1 of these 5 seeds (seed 5: block-means z 4.38 against the limit 2.71), which the last
    // check asserts so that the gate is seen to matter (about 4 CPU-s).
    impulse::test::TempDir dir;
    int alarms = 0, ungated = 0;
    for (int seed = 1; seed <= 5; ++seed) {
        const std::string text =
            "[output]\nsize = [48, 48]\nframes = 60\nfps = 10\n[[layer]]\nseed = " +
            std::to_string(seed) +
            "\ndensity = 5.0\namplitude = \"sign\"\nlifetime = 6.0\n[layer.kernel]\ntype = "
            "\"gaussian\"\nsigma = 40.0\nradius = 120.0\n";
        const auto st = analyse(dir, "sparse_" + std::to_string(seed), text);
        INFO("seed " << seed << ": block dof " << st.block_dof << ", block z " << st.level.z_blocks
                     << ", trend z " << st.level.z_trend << ", verdict " << st.verdict);
        CHECK(st.block_dof < st.min_block_dof);
        CHECK_FALSE(st.level_note.empty());
        alarms += st.verdict == "not stationary";
        ungated += std::abs(st.level.z_trend) >= st.level_z_limit ||
                   st.level.z_blocks >= st.blocks_z_limit;
    }
    CHECK(alarms == 0);
    CHECK(ungated >= 1);
}

TEST_CASE("stationarity verdict under motion blur: a blurred drifting source is stationary, "
          "jacobian = false is seen",
          "[app][analyze][stats][blur]") {
    // The blurred theory (each kernel averaged along its path over the shutter: variance x 0.85
    // here) is what the frames are judged against. With sqrt(J), three seeds: the verdict's
    // family rate is 0.01, so two false alarms in 3 have probability 3e-4 and at most one is
    // allowed (seed 1 of this scene alarms blurred and unblurred alike, block z 3.5 and 3.9 at
    // 64^2: its realisation, not the blur). Without sqrt(J) the pulse swings the variance by a
    // third: both seeds must be seen. About 7 s: 5 renders of 100 frames (each impulse 8 copies
    // along its path) and their analyses.
    impulse::test::TempDir dir;
    int alarms = 0, seen = 0;
    std::vector<Image> seed1;
    for (int seed = 1; seed <= 3; ++seed) {
        const auto steady = analyse_result(dir, "blur_j_" + std::to_string(seed),
                                           blurred_text(true, seed), seed == 1 ? &seed1 : nullptr);
        const auto& st = steady.stationarity;
        INFO("seed " << seed << " sqrt(J): " << st.verdict << " (block z " << st.level.z_blocks
                     << ", trend z " << st.level.z_trend << ")");
        REQUIRE(st.block_dof >= st.min_block_dof);
        REQUIRE(steady.theory);
        // The theory is the blurred one, and the frames agree with it.
        CHECK(steady.theory->variance_agrees);
        alarms += st.verdict == "not stationary";
        if (seed > 2) continue;
        const auto pulsing = analyse(dir, "blur_nj_" + std::to_string(seed), blurred_text(false, seed));
        INFO("seed " << seed << " without sqrt(J): " << pulsing.verdict << " (block z "
                     << pulsing.level.z_blocks << ")");
        CHECK(pulsing.verdict == "not stationary");
        seen += pulsing.verdict == "not stationary";
    }
    CHECK(alarms <= 1);
    CHECK(seen == 2);

    // Teeth: seed 1's frames judged against the unblurred theory (the scene with shutter = 0)
    // disagree on the variance: blur is in the theory, not absorbed by the tolerance.
    const std::string open = dir / "open.toml";
    std::ofstream(open) << blurred_text(true, 1, 0.0);
    const auto unblurred_theory = impulse::scenes::closed_form(open, {});
    REQUIRE(unblurred_theory);
    impulse::analysis::AnalyzeOptions opt;
    opt.input = open;
    opt.scene = open;
    const auto wrong = impulse::analysis::analyze_frames(std::move(seed1), opt, "sequence", true, 32,
                                                         0, unblurred_theory.get());
    REQUIRE(wrong.theory);
    INFO("against the unblurred theory: variance z " << wrong.theory->z_variance);
    CHECK_FALSE(wrong.theory->variance_agrees);
}
