// SPDX-License-Identifier: Apache-2.0
// `impulse synth solid` (issue 17 item 4) as a separate process: bad input is one line on
// stderr, a non-zero exit and no file; a grid is an EXR stack of D layers or an OpenVDB grid,
// and point queries give the grid's values at the same points.

#include <catch2/catch.hpp>
#include <sstream>
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

}  // namespace

TEST_CASE("synth solid refuses bad input with one line and writes nothing", "[cli][errors][synth]") {
    TempDir dir;
    write_file(dir / "bad.csv", "1,2,3\n4.5,x,7\n");
    const std::string out = " -o " + quote(dir / "v.exr");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--method sparse --size 0x4x4" + out, "--size 0x4x4: expected WxHxD"},
        {"--method sparse --size 4x4" + out, "--size 4x4: expected WxHxD"},
        {"--method sparse --radius -1 --size 4x4x4" + out, "--radius -1: expected a number in (0, 1e6]"},
        {"--method sparse --radius 0 --size 4x4x4" + out, "--radius 0"},
        {"--method sparse --density 0 --size 4x4x4" + out, "density = 0"},
        {"--method sparse --size 100000x100000x1000" + out, "needs an estimated"},
        {"--method simplex --size 4x4x4" + out, "expected one of sparse, perlin, value, wiener"},
        {"--method wiener --covariance gaussian --length 1 --size 4x4x4" + out,
         "C(1, 0, 0) = 0.367879 C(0)"},
        {"--method sparse --points " + quote(dir / "bad.csv") + " -o " + quote(dir / "v.csv"),
         "bad.csv:2: \"4.5,x,7\": expected x,y,z"},
        {"--method sparse --size 4x4x4 -o " + quote(dir / "v.png"), "expected .exr or .vdb"},
    };
    for (const auto& [args, message] : cases) {
        const Result r = run(dir, "synth solid " + args);
        INFO(args);
        CHECK(r.status != 0);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains(message));
    }
    CHECK(dir.files().size() == 1);  // bad.csv only
}

TEST_CASE("synth solid writes grids and point values that agree", "[cli][synth]") {
    TempDir dir;
    REQUIRE(run(dir, "synth solid --method sparse --radius 3 --size 6x5x4 --seed 2 -o " + quote(dir / "v.exr")).status == 0);
    REQUIRE(run(dir, "synth solid --method perlin --size 6x5x4 -o " + quote(dir / "v.vdb")).status == 0);
    const Result info = shell(dir, "oiiotool --info -v " + quote(dir / "v.exr"));
    CHECK_THAT(info.out, Contains("6 x    5, 4 channel, float"));
    CHECK_THAT(info.out, Contains("z0000.Y, z0001.Y, z0002.Y, z0003.Y"));
    CHECK(read_file(dir / "v.vdb").find("density") != std::string::npos);
    // Points at (1, 2, 3) and (5, 4, 0) against the grid's samples there.
    write_file(dir / "p.csv", "1,2,3\n# comment\n5,4,0\n");
    REQUIRE(run(dir, "synth solid --method sparse --radius 3 --seed 2 --points " + quote(dir / "p.csv") +
                     " -o " + quote(dir / "v.csv")).status == 0);
    const std::string csv = read_file(dir / "v.csv");
    std::istringstream in(csv);
    std::string l1, l2;
    std::getline(in, l1);
    std::getline(in, l2);
    CHECK_THAT(l1, Contains("1,2,3,"));
    CHECK_THAT(l2, Contains("5,4,0,"));
    // Layer z0003 as its own image: pixel (1, 2) is the point (1, 2, 3).
    REQUIRE(shell(dir, "oiiotool " + quote(dir / "v.exr") + " --ch z0003.Y -o " + quote(dir / "s.exr")).status == 0);
    const impulse::numeric::Frame f = impulse::output::read_image(dir / "s.exr");
    const double v1 = std::stod(l1.substr(l1.rfind(',') + 1));
    CHECK(f.at(1, 2) == Approx(v1).margin(1e-6));
    CHECK(v1 != 0.0);
}
