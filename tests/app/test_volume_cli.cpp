// SPDX-License-Identifier: Apache-2.0
// `impulse render` of a volume scene: an OpenVDB sequence read back with OpenVDB holds the grid
// the library computes (name "density", every voxel's value, zeros inactive), a preview image,
// `impulse scenes` and `impulse info` on volume scenes, and bad input (one line, nothing
// written).

#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "output/volume.h"
#include "scenes/scenes.h"
#include "scenes/volume_scene.h"
#include "tests/support.h"
#include "volume/volume.h"

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;

namespace {

impulse::test::Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " " + args);
}

// The built-in cloudvolume scene, small: a 40 x 24 x 20 grid, 2 octaves.
const std::vector<std::string> kSmall = {"volume.size=[40,24,20]", "volume.octaves=2",
                                         "volume.kernel.radius=8", "output.size=[64,36]"};

std::string sets() {
    std::string s;
    for (const auto& o : kSmall) s += " --set " + quote(o);
    return s;
}

}  // namespace

TEST_CASE("volume render: OpenVDB frames read back with OpenVDB hold the density grid",
          "[cli][volume]") {
    TempDir dir;
    const Result r = run(dir, "render cloudvolume -q -o " + quote(dir / "cloud_####.vdb") +
                                  " --frames 2-3" + sets());
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("2 frames") && Contains("40x24x20 voxels"));
    const auto scene = impulse::scenes::load_scene(impulse::scenes::resolve_scene("cloudvolume"), kSmall);
    REQUIRE(scene.volume);
    impulse::volume::CloudVolume cloud(scene.volume->cloud);
    for (int f = 2; f <= 3; ++f) {
        INFO("frame " << f);
        const impulse::volume::DensityGrid expect = cloud.density(f);
        const impulse::output::VolumeGrid got =
            impulse::output::read_vdb(dir / ("cloud_000" + std::to_string(f) + ".vdb"), "density");
        // read_vdb gives the active voxels' bounding box from index 0: at most the grid.
        REQUIRE(got.size[0] <= 40);
        REQUIRE(got.size[1] <= 24);
        REQUIRE(got.size[2] <= 20);
        size_t nonzero = 0, mismatches = 0;
        for (int k = 0; k < 20; ++k)
            for (int j = 0; j < 24; ++j)
                for (int i = 0; i < 40; ++i) {
                    const float e = expect.values[(size_t(k) * 24 + j) * 40 + i];
                    const bool inside = i < got.size[0] && j < got.size[1] && k < got.size[2];
                    const float g = inside ? got.values[(size_t(k) * got.size[1] + j) * got.size[0] + i] : 0.0f;
                    nonzero += e != 0.0f;
                    mismatches += e != g;  // bit for bit: VDB stores the floats as they are
                }
        CHECK(nonzero > 0);
        CHECK(mismatches == 0);
    }
    // No temporary left behind (atomic writes).
    size_t files = 0;
    for (const auto& e : fs::directory_iterator(dir.path())) files += e.path().extension() == ".vdb";
    CHECK(files == 2);
}

TEST_CASE("volume render: a preview image then the scene list and info", "[cli][volume]") {
    TempDir dir;
    const Result r = run(dir, "render cloudvolume -q -o " + quote(dir / "preview.png") + " --frames 5" + sets());
    REQUIRE(r.status == 0);
    CHECK(fs::exists(dir / "preview.png"));
    const Result list = run(dir, "scenes");
    CHECK_THAT(list.out, Contains("cloudvolume (volume) a cumulus volume"));
    const Result info = run(dir, "info cloudvolume");
    CHECK(info.status == 0);
    CHECK_THAT(info.out, Contains("Campbell") && Contains("octave[3]"));
}

TEST_CASE("volume render: bad input is one line and writes nothing", "[cli][volume]") {
    TempDir dir;
    const Result a = run(dir, "render cloudvolume -q -o " + quote(dir / "cloud.vdb") + " --frames 0-1" + sets());
    CHECK(a.status != 0);
    CHECK_THAT(a.err, Contains("one file but 2 frames"));
    const Result b = run(dir, "render cloudvolume -q -o " + quote(dir / "cloud.obj") + sets());
    CHECK(b.status != 0);
    CHECK_THAT(b.err, Contains("unknown output type for a volume scene"));
    const Result c = run(dir, "render cloudvolume -q -o " + quote(dir / "c.vdb") +
                                  " --set 'volume.size=[0,4,4]'");
    CHECK(c.status != 0);
    CHECK_THAT(c.err, Contains("volume.size") && Contains("[1, 2048]"));
    const Result d = run(dir, "render cloudvolume -q -o " + quote(dir / "c.vdb") +
                                  " --set 'volume.flow.0.tpye=\"curl\"'");
    CHECK(d.status != 0);
    CHECK_THAT(d.err, Contains("tpye"));
    const Result e = run(dir, "render cloudvolume -q -o " + quote(dir / "c.vdb") +
                                  " --set volume.kernel.aspect=0");
    CHECK(e.status != 0);
    CHECK_THAT(e.err, Contains("volume.kernel.aspect = 0: expected") && Contains("(0, 16]"));
    const Result f = run(dir, "render cloudvolume -q -o " + quote(dir / "c.vdb") +
                                  " --set 'volume.orientation=\"vortex\"'");
    CHECK(f.status != 0);
    CHECK_THAT(f.err, Contains("expected one of fixed, random, flow, vorticity"));
    for (const Result* r : {&e, &f}) CHECK(std::count(r->err.begin(), r->err.end(), '\n') <= 1);
    CHECK(dir.files().empty());
}

TEST_CASE("volume render: an oriented, stretched cloud has the same frames rendered in one range "
          "or split", "[cli][volume][orientation]") {
    // docs/volume.md "Orientation": the vorticity axis is integrated on the global time grid,
    // so frames 2-3 rendered on their own (from birth) equal frames 2-3 of the range 0-3.
    TempDir dir;
    const std::string oriented = sets() + " --set 'volume.orientation=\"vorticity\"'" +
                                 " --set volume.kernel.aspect=3";
    REQUIRE(run(dir, "render cloudvolume -q -o " + quote(dir / "one_####.vdb") + " --frames 0-3" + oriented).status == 0);
    REQUIRE(run(dir, "render cloudvolume -q -o " + quote(dir / "split_####.vdb") + " --frames 2-3" + oriented).status == 0);
    for (int f = 2; f <= 3; ++f) {
        INFO("frame " << f);
        const std::string n = "_000" + std::to_string(f) + ".vdb";
        const auto a = impulse::output::read_vdb(dir / ("one" + n), "density");
        const auto b = impulse::output::read_vdb(dir / ("split" + n), "density");
        CHECK(a.size == b.size);
        CHECK(a.values == b.values);
        CHECK(std::any_of(a.values.begin(), a.values.end(), [](float v) { return v > 0.0f; }));
    }
}
