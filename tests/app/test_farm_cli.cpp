// SPDX-License-Identifier: Apache-2.0
// `impulse encode` and `impulse farm` without a cluster: the video encode assembles from an EXR
// sequence is the video render makes directly (the display mapping travels in the frames'
// metadata); the sbatch array script's tasks, run one by one by hand, write the frames one run
// writes; gaps, mixed scenes and bad farm options are refused with one line and nothing written.
// The same on a real Slurm: tests/cluster/test_slurm.sh.

#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "output/output.h"
#include "tests/support.h"

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;

/// `command` run by the shell in `dir`.
Result in_dir(const TempDir& dir, const std::string& command) {
    return shell(dir, "cd " + quote(dir.path().string()) + " && " + command);
}

/// `impulse ARGS` in `dir`, after `prefix` (variable assignments).
Result run(const TempDir& dir, const std::string& args, const std::string& prefix = "") {
    return in_dir(dir, prefix + quote(IMPULSE_BINARY) + " " + args);
}

/// A small animated scene with a colour ramp (so a grey encoding would differ), 12 frames.
std::string write_scene(const TempDir& dir, int seed = 21) {
    const std::string path = dir / "scene.toml";
    write_file(path,
               "[output]\nsize = [48, 32]\nfps = 24\nframes = 12\npreset = \"ultrafast\"\n\n"
               "[[layer]]\nseed = " +
                   std::to_string(seed) +
                   "\ndensity = 12.0\nlifetime = 1.0\nenvelope = \"hann\"\n"
                   "[layer.kernel]\ntype = \"cosine\"\nradius = 5.0\n"
                   "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [16.0, 5.0]\n\n"
                   "[shading]\nramp = [[0.0, \"#102040\"], [0.6, [0.9, 0.5, 0.2, 0.8]], "
                   "[1.0, \"#fff0c0\"]]\n");
    return path;
}

bool no_partials(const fs::path& dir) {
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.path().filename().string().find("partial") != std::string::npos) return false;
    return true;
}

}  // namespace

TEST_CASE("encode: display mapping round trip through text is bit-exact", "[cli][encode]") {
    impulse::output::Display d;
    d.mapping = {-3.0507887777798586, 1.0 / 3.0};
    d.shading.ramp = {{0.0, 0.1f, 0.2f, 0.3f, 1.0f}, {0.7, 1.0f / 3.0f, 0.5f, 0.25f, 0.8f}};
    d.shading.relief = 0.125;
    const std::string text = impulse::output::format_display(d);
    const impulse::output::Display e = impulse::output::parse_display(text, "f.exr");
    CHECK(impulse::output::format_display(e) == text);
    CHECK(e.mapping.hi == d.mapping.hi);
    REQUIRE(e.shading.ramp.size() == 2);
    CHECK(e.shading.ramp[1].r == d.shading.ramp[1].r);
    CHECK_THROWS_WITH(impulse::output::parse_display("lo=1 hi=x", "f.exr"),
                      Contains("f.exr: impulse:display field 2 \"hi=x\""));
}

TEST_CASE("encode makes from EXR frames the video render makes directly", "[cli][encode]") {
    TempDir dir("encode");
    const std::string scene = write_scene(dir);
    fs::create_directories(dir.path() / "fr");
    REQUIRE(run(dir, "render scene.toml -o fr/f_####.exr -q").status == 0);
    REQUIRE(run(dir, "render scene.toml -o direct.mp4 -q").status == 0);
    const Result r = run(dir, "encode 'fr/f_####.exr' -o encoded.mp4");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("12 frames 0-11, 48x32, 24 fps"));
    // Same pixels, shading, rate, codec settings and container metadata: the same bytes.
    CHECK(read_file(dir / "encoded.mp4") == read_file(dir / "direct.mp4"));
    CHECK(impulse::output::probe_video(dir / "encoded.mp4").frame_count == 12);
    // An explicit codec and range.
    REQUIRE(run(dir, "encode 'fr/f_####.exr' -o part.mkv --frames 2-5 --fps 12").status == 0);
    const auto info = impulse::output::probe_video(dir / "part.mkv");
    CHECK(info.frame_count == 4);
    CHECK(info.codec_name == "ffv1");
    CHECK(info.fps == Approx(12.0));
}

TEST_CASE("encode refuses gaps, mixed scenes and renamed frames, naming them, writing nothing",
          "[cli][encode]") {
    TempDir dir("encode-bad");
    write_scene(dir);
    for (const char* d : {"fr", "kept", "seed9"}) fs::create_directories(dir.path() / d);
    REQUIRE(run(dir, "render scene.toml -o fr/f_####.exr -q").status == 0);
    const auto refused = [&](const std::string& args, std::vector<std::string> what) {
        const Result r = run(dir, "encode " + args);
        INFO(args << "\n" << r.err);
        CHECK(r.status == 1);
        CHECK(r.err_lines().size() == 1);
        for (const auto& w : what) CHECK_THAT(r.err, Contains(w));
        CHECK_FALSE(fs::exists(dir / "out.mp4"));
        CHECK(no_partials(dir.path()));
    };
    refused("'fr/f_####.exr' -o out.mp4 --frames 0-13", {"frames 12-13 missing from 0-13"});
    refused("fr/f.exr -o out.mp4", {"expected an EXR sequence pattern"});
    refused("'fr/f_####.exr' -o out.png", {"expected a video"});
    const auto move = [&](const std::string& from, const std::string& to, const std::string& name) {
        fs::rename(dir.path() / from / name, dir.path() / to / name);
    };
    for (const char* f : {"f_0003.exr", "f_0007.exr", "f_0008.exr"}) move("fr", "kept", f);
    refused("'fr/f_####.exr' -o out.mp4", {"frames 3, 7-8 missing from 0-11 (e.g. fr/f_0003.exr)"});
    // Frames 3, 7 and 8 of another seed: another scene hash, both named with their frames.
    REQUIRE(run(dir, "render scene.toml --seed 9 -o seed9/f_####.exr --frames 3-8 -q").status == 0);
    for (const char* f : {"f_0003.exr", "f_0007.exr", "f_0008.exr"}) move("seed9", "fr", f);
    refused("'fr/f_####.exr' -o out.mp4",
            {"frames of 2 scenes (impulse:scene_hash)", "frames 0-2, 4-6, 9-11", "frames 3, 7-8"});
    // The right frames back, and one copied under another number.
    for (const char* f : {"f_0003.exr", "f_0007.exr", "f_0008.exr"}) move("kept", "fr", f);
    fs::copy_file(dir.path() / "fr/f_0004.exr", dir.path() / "fr/f_0005.exr",
                  fs::copy_options::overwrite_existing);
    refused("'fr/f_####.exr' -o out.mp4", {"fr/f_0005.exr: impulse:frame is 4, expected 5"});
}

TEST_CASE("farm: the array script's tasks, run by hand, write the frames of one run",
          "[cli][farm]") {
    TempDir dir("farm");
    const std::string scene = write_scene(dir);
    fs::create_directories(dir.path() / "farm");
    fs::create_directories(dir.path() / "local");
    const Result r = run(dir, "farm " + quote(scene) +
                                  " -o 'farm/f_####.exr' --chunk 5 --partition short --time 10 "
                                  "--set layer.0.density=10");
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("3 array tasks of up to 5 frames"));
    const std::string script = read_file(dir / "farm/scene.sbatch");
    CHECK_THAT(script, Contains("#SBATCH --array=0-2\n"));
    CHECK_THAT(script, Contains("#SBATCH --partition=short\n"));
    CHECK_THAT(script, Contains("#SBATCH --time=10\n"));
    CHECK_THAT(script, Contains("--resume"));
    CHECK_THAT(read_file(dir / "farm/scene.encode.sbatch"), Contains(" encode "));
    // Slurm's part done by hand: each task with its SLURM_ARRAY_TASK_ID (the #SBATCH lines are
    // comments to bash), then the encode job.
    for (int task = 0; task < 3; ++task)
        REQUIRE(
            in_dir(dir, "SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " bash farm/scene.sbatch")
                .status == 0);
    REQUIRE(in_dir(dir, "bash farm/scene.encode.sbatch").status == 0);
    REQUIRE(
        run(dir, "render " + quote(scene) + " -o 'local/f_####.exr' --set layer.0.density=10 -q")
            .status == 0);
    for (int f = 0; f < 12; ++f) {
        const std::string name =
            "/f_00" + std::string(f < 10 ? "0" : "") + std::to_string(f) + ".exr";
        INFO(name);
        REQUIRE(fs::exists(dir / ("farm" + name)));
        CHECK(read_file(dir / ("farm" + name)) == read_file(dir / ("local" + name)));
    }
    REQUIRE(run(dir, "encode 'local/f_####.exr' -o local/scene.mp4 -q").status == 0);
    CHECK(read_file(dir / "farm/scene.mp4") == read_file(dir / "local/scene.mp4"));
    // A task run again (a resubmitted one) keeps the frames it finds whole.
    const Result again = in_dir(dir, "SLURM_ARRAY_TASK_ID=1 bash farm/scene.sbatch");
    CHECK(again.status == 0);
    CHECK_THAT(again.out, Contains("0 frames, 5 already present"));
}

TEST_CASE("farm refuses bad input with one line and writes nothing", "[cli][farm]") {
    TempDir dir("farm-bad");
    write_scene(dir);
    fs::create_directories(dir.path() / "fr");
    const auto refused = [&](const std::string& args, const std::string& what) {
        const Result r = run(dir, "farm scene.toml " + args);
        INFO(args << "\n" << r.err);
        CHECK(r.status == 1);
        CHECK(r.err_lines().size() == 1);
        CHECK_THAT(r.err, Contains(what));
        CHECK(fs::is_empty(dir.path() / "fr"));
    };
    refused("-o 'fr/f_####.exr' --chunk 0", "--chunk 0: expected a positive number");
    refused("-o 'fr/f_####.exr' --chunk -4", "--chunk -4: expected a positive number");
    refused("-o 'fr/f_####.exr' --chunk ten", "--chunk ten: expected a positive number");
    refused("-o fr/f.exr --chunk 4", "-o fr/f.exr: expected an image-sequence pattern");
    refused("-o 'fr/f_####.exr' --chunk 4 --time 1h", "--time 1h: expected minutes");
    refused("-o 'fr/f_####.exr' --chunk 4 --frames 5-40", "--frames 5-40: outside [0, 12)");
    refused("-o 'fr/f_####.exr' --chunk 4 --video fr/v.gif", "--video fr/v.gif: expected a video");
    // No Slurm here: how to install it, or the GNU parallel line that renders the same chunks.
    fs::create_directories(dir.path() / "empty");
    const Result r = run(dir, "farm scene.toml -o 'fr/f_####.exr' --chunk 4 --submit",
                         "PATH=" + quote((dir.path() / "empty").string()) + " ");
    CHECK(r.status == 1);
    CHECK(r.err_lines().size() == 1);
    CHECK_THAT(r.err, Contains("sbatch not found on PATH: install Slurm's client (Debian: apt-get "
                               "install slurm-client)"));
    CHECK_THAT(r.err, Contains("--frames {} ::: 0-3 4-7 8-11"));
    CHECK(fs::is_empty(dir.path() / "fr"));
}
