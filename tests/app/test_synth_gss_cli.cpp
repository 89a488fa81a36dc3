// SPDX-License-Identifier: Apache-2.0
// `impulse synth gss` as a separate process: the forms of the issue, the JSON levels, refining
// an image keeps its pixels, and bad input is one line, a non-zero exit and no file.

#include <algorithm>
#include <catch2/catch.hpp>
#include <fstream>
#include <string>

#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"

namespace {

using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " synth gss " + args);
}

}  // namespace

TEST_CASE("synth gss: 1-D CSV, 2-D EXR and the per-level JSON", "[app][synth]") {
    TempDir dir("gss");
    const Result a = run(dir, "--acf markov --param length=8 --size 65 --dim 1 --seed 3 -o " +
                                  quote(dir / "a.csv") + " --json " + quote(dir / "a.json"));
    REQUIRE(a.status == 0);
    const std::string csv = read_file(dir / "a.csv");
    CHECK(csv.rfind("i,value\n0,", 0) == 0);
    CHECK(std::count(csv.begin(), csv.end(), '\n') == 66);
    const std::string json = read_file(dir / "a.json");
    for (const char* key :
         {"\"levels\"", "\"spacing\"", "\"neighbors\"", "\"coefficients\"", "\"variance\""})
        CHECK_THAT(json, Contains(key));
    const Result b = run(dir,
                         "--acf oscillatory_markov --param length=12 --param omega=0.3 "
                         "--param separable=1 --size 33x17 --dim 2 -o " +
                             quote(dir / "b.exr"));
    REQUIRE(b.status == 0);
    const impulse::render::Frame f = impulse::output::read_image(dir / "b.exr");
    CHECK(f.width == 33);
    CHECK(f.height == 17);
}

TEST_CASE("synth gss --refine keeps the input at every F-th node and prints the estimate",
          "[app][synth]") {
    TempDir dir("gss");
    REQUIRE(
        run(dir, "--acf markov --param length=3 --size 9x9 -o " + quote(dir / "c.exr")).status ==
        0);
    const Result r =
        run(dir, "--refine " + quote(dir / "c.exr") + " --factor 4 -o " + quote(dir / "f.exr"));
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("eq. 15"));
    const impulse::render::Frame c = impulse::output::read_image(dir / "c.exr");
    const impulse::render::Frame f = impulse::output::read_image(dir / "f.exr");
    REQUIRE(f.width == 33);
    REQUIRE(f.height == 33);
    for (int y = 0; y < 9; ++y)
        for (int x = 0; x < 9; ++x) CHECK(f.at(4 * x, 4 * y) == c.at(x, y));
}

TEST_CASE("synth gss: bad input is one line, exit 1, nothing written", "[app][synth]") {
    TempDir dir("gss");
    REQUIRE(run(dir, "--acf markov --size 9x9 -o " + quote(dir / "c.exr")).status == 0);
    const std::string out = " -o " + quote(dir / "o.exr") + " --json " + quote(dir / "o.json");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--acf expression --param 'expr=max(0, 1 - (r/8)^2)' --size 65x65",
         "non-negative definite"},
        {"--acf markov --size 100x100", "2^k + 1"},
        {"--acf markov --size 64x64", "2^k + 1"},
        {"--acf markov --size 65x65 --periodic", "2^k samples"},
        {"--refine " + quote(dir / "c.exr") + " --factor 3", "power of two"},
        {"--acf markov --param lenght=3 --size 65x65", "unknown key"},
        {"--acf nosuch --size 65x65", "unknown model"},
    };
    for (const auto& [args, what] : cases) {
        CAPTURE(args);
        const Result r = run(dir, args + out);
        CHECK(r.status == 1);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err, Contains(what));
    }
    CHECK(dir.files() == std::vector<std::string>{"c.exr"});
}
