// SPDX-License-Identifier: Apache-2.0
// `impulse render --channels` and `impulse analyze` of its files, run as separate processes
// (docs/channels.md): the EXR's channel names read back with OpenImageIO, the value channel equal
// to a plain render's, normal maps in PNG, refusals that write nothing, and analyze following the
// frames' framing (--size recorded in the metadata).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "output/output.h"
#include "tests/support.h"

namespace {

using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " " + args);
}

// Two named-and-unnamed layers with a flow, orthographic at zoom 1.
const char* kScene = R"([output]
size = [64, 48]
frames = 3
[shading]
relief = 2.0
[[layer]]
name = "cells"
seed = 5
density = 8.0
lifetime = 2.0
[layer.kernel]
type = "gaussian"
radius = 12.0
sigma = 4.0
[[layer.flow]]
type = "uniform"
velocity = [15.0, 0.0]
[[layer]]
seed = 6
density = 8.0
[layer.kernel]
type = "cosine"
radius = 5.0
)";

}  // namespace

TEST_CASE("render --channels writes a multi-channel EXR with the documented names",
          "[app][channels]") {
    TempDir dir("channels");
    write_file(dir / "s.toml", kScene);
    const Result r = run(dir, "render " + quote(dir / "s.toml") + " --channels value,dx,dy,normal,motion -q -o " +
                                  quote(dir / "c.exr") + " --frames 1");
    INFO(r.err);
    REQUIRE(r.status == 0);
    const std::vector<std::string> expected = {
        "R", "G", "B", "A", "value", "cells.value", "layer1.value", "dx", "cells.dx", "layer1.dx",
        "dy", "cells.dy", "layer1.dy", "N.X", "N.Y", "N.Z", "forward.u", "forward.v",
        "backward.u", "backward.v"};
    std::vector<std::string> names = impulse::output::channel_names(dir / "c.exr");
    std::sort(names.begin(), names.end());
    std::vector<std::string> want = expected;
    std::sort(want.begin(), want.end());
    CHECK(names == want);
    // The value channel is the plain render's field, bit for bit.
    REQUIRE(run(dir, "render " + quote(dir / "s.toml") + " -q -o " + quote(dir / "plain.exr") + " --frames 1")
                .status == 0);
    const auto plain = impulse::output::read_image(dir / "plain.exr");
    const auto value = impulse::output::read_channel(dir / "c.exr", "value");
    CHECK(plain.data == value.data);
    // Normals of unit length; the wind's 15 units/s is half a pixel a frame at 30 fps.
    const auto nx = impulse::output::read_channel(dir / "c.exr", "N.X");
    const auto ny = impulse::output::read_channel(dir / "c.exr", "N.Y");
    const auto nz = impulse::output::read_channel(dir / "c.exr", "N.Z");
    for (size_t i = 0; i < nx.data.size(); ++i)
        CHECK(std::abs(std::hypot(nx.data[i], ny.data[i], nz.data[i]) - 1.0) <= 1e-6);
    const auto fu = impulse::output::read_channel(dir / "c.exr", "forward.u");
    // Only layer 0 moves: the composite weighs its velocity by its share of the variance.
    CHECK(fu.data[0] > 0.0f);
    CHECK(fu.data[0] < 0.5f);
    // analyze reads the value channel of a multi-channel EXR (not the luminance of R G B).
    const Result a = run(dir, "analyze " + quote(dir / "c.exr") + " --json");
    REQUIRE(a.status == 0);
    const Result b = run(dir, "analyze " + quote(dir / "plain.exr") + " --json");
    auto moments = [](const std::string& json) {
        const size_t i = json.find("\"moments\""), j = json.find("\"histogram\"");
        return i == std::string::npos || j == std::string::npos ? std::string() : json.substr(i, j - i);
    };
    CHECK(!moments(a.out).empty());
    CHECK(moments(a.out) == moments(b.out));
    const Result c = run(dir, "analyze " + quote(dir / "c.exr") + " --channel nope");
    CHECK(c.status == 1);
    CHECK_THAT(c.err, Contains("no channel \"nope\""));
}

TEST_CASE("render --channels normal writes a normal map PNG (N * 0.5 + 0.5)", "[app][channels]") {
    TempDir dir("channels");
    write_file(dir / "s.toml", kScene);
    for (int bits : {8, 16}) {
        const std::string png = dir / ("n" + std::to_string(bits) + ".png");
        const Result r = run(dir, "render " + quote(dir / "s.toml") + " --channels normal -q -o " + quote(png) +
                                      " --frames 0 --set output.bits=" + std::to_string(bits));
        INFO(r.err);
        REQUIRE(r.status == 0);
        const auto info = impulse::output::probe_image(png);
        CHECK(info.channels == 3);
        CHECK(info.bits == bits);
        // Each component is quantised to within half a step: |N| is 1 within sqrt(3) steps of
        // 2 / (2^bits - 1) / 2.
        const auto rr = impulse::output::read_channel(png, "R");
        const auto gg = impulse::output::read_channel(png, "G");
        const auto bb = impulse::output::read_channel(png, "B");
        const double step = 1.0 / ((1 << bits) - 1);
        for (size_t i = 0; i < rr.data.size(); ++i) {
            const double x = 2 * rr.data[i] - 1, y = 2 * gg.data[i] - 1, z = 2 * bb.data[i] - 1;
            CHECK(std::abs(std::hypot(x, y, z) - 1.0) <= std::sqrt(3.0) * step + 1e-6);
            CHECK(z > 0.0);
        }
    }
}

TEST_CASE("channels a format cannot hold are refused: one line, exit 1, nothing written",
          "[app][channels][errors]") {
    TempDir dir("channels");
    write_file(dir / "s.toml", kScene);
    struct Case {
        std::string args, message;
    };
    const std::vector<Case> cases = {
        {"--channels value,dxx --frames 0 -o " + quote(dir / "a.exr"),
         "error: --channels value,dxx: unknown channel \"dxx\" (did you mean \"dx\"?): expected "
         "one of value, dx, dy, normal, motion"},
        {"--channels value,dx,dy,normal --frames 0 -o " + quote(dir / "a.png"),
         "error: --channels value,dx,dy,normal: 16 channels"},
        {"--channels motion -o " + quote(dir / "a.mp4"), "error: --channels motion: "},
        {"--set 'output.channels=[\"motion\"]' -o " + quote(dir / "a.mp4"),
         "error: output.channels: "},
    };
    for (const auto& c : cases) {
        const Result r = run(dir, "render " + quote(dir / "s.toml") + " -q " + c.args);
        INFO(c.args << "\n" << r.err);
        CHECK(r.status == 1);
        CHECK(r.err_lines().size() == 1);
        CHECK_THAT(r.err, Contains(c.message));
        CHECK(dir.files() == std::vector<std::string>{"s.toml"});
    }
}

TEST_CASE("analyze --scene takes its theory at the frames' recorded --size",
          "[app][channels][analyze][slow]") {
    // drift at a quarter of its pixels (the same view, zoom 0.25): before the frames recorded
    // their --size, the theory was taken at 1920x1080 and the spectrum was told it disagrees.
    TempDir dir("framing");
    const std::string frames = dir / "d_####.exr";
    const Result r = run(dir, "render drift --size 480x270 --frames 0-1 -q -o " + quote(frames));
    INFO(r.err);
    REQUIRE(r.status == 0);
    const auto meta = impulse::output::read_metadata(dir / "d_0000.exr");
    CHECK(std::find(meta.begin(), meta.end(), std::make_pair(std::string("size"), std::string("480x270"))) !=
          meta.end());
    const Result a = run(dir, "analyze " + quote(frames) + " --scene drift");
    INFO(a.out << a.err);
    REQUIRE(a.status == 0);
    CHECK_THAT(a.out, Contains("spectrum agrees with theory: yes"));
    CHECK_THAT(a.out, Contains("theory at the frames' --size 480x270"));
    // The theory at the scene's own framing (what analyze did before): it disagrees.
    const Result b = run(dir, "analyze " + quote(frames) + " --scene drift --size 1920x1080");
    CHECK_THAT(b.out, Contains("spectrum agrees with theory: no"));
}
