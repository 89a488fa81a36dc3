// SPDX-License-Identifier: Apache-2.0
// `impulse synth fbm` and `impulse analyze --structure` run as separate processes (issue 16):
// bad input is one line on stderr, a non-zero exit and no file; good input writes the height
// field (float EXR with B(0, 0) = 0, 16-bit PNG) and the analysis reports its H(s).

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"

namespace {

using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args) {
    return shell(dir, quote(IMPULSE_BINARY) + " " + args);
}

}  // namespace

TEST_CASE("synth fbm refuses bad input with one line and writes nothing", "[cli][errors][synth]") {
    TempDir dir;
    const std::string out = " -o " + quote(dir / "f.exr");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"--method exact --hurst 1 --size 64", "hurst = 1: expected H in (0, 1)"},
        {"--method exact --hurst 0 --size 64", "expected H in (0, 1)"},
        {"--method exact --hurst x --size 64", "--hurst x: expected a number"},
        {"--method exact --hurst 0.5 --size 100", "size = 100: expected a power of two"},
        {"--method exact --hurst 0.5 --size 16384", "from 2 to 8192"},
        {"--method midpoint --hurst 0.5 --size 64", "expected one of fourier, incremental, exact"},
        {"--method exact --hurst 0.8 --size 8192 --memory-budget 2", "needs about"},
        {"--method exact --hurst 0.5 --size 64 --seamless", "only the fourier method tiles"},
        {"--method exact --hurst 0.5 --size 64 --seed -3", "--seed -3"},
    };
    for (const auto& [args, message] : cases) {
        const Result r = run(dir, "synth fbm " + args + out);
        INFO(args);
        CHECK(r.status != 0);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains(message));
    }
    const Result j = run(dir, "synth fbm --method exact --hurst 0.5 --size 64 -o " +
                                  quote(dir / "f.jpg"));
    CHECK(j.status != 0);
    CHECK(dir.files().empty());
}

TEST_CASE("synth fbm writes the field and analyze --structure measures it", "[cli][synth]") {
    TempDir dir;
    const Result r = run(dir, "synth fbm --method incremental --hurst 0.3 --size 128 --seed 5 -o " +
                                  quote(dir / "f.exr"));
    REQUIRE(r.status == 0);
    const impulse::render::Frame f = impulse::output::read_image(dir / "f.exr");
    CHECK(f.width == 128);
    CHECK(f.height == 128);
    CHECK(f.at(0, 0) == 0.0f);  // B(0, 0) = 0 (Kaplan & Kuo eq. 1)
    REQUIRE(run(dir, "synth fbm --method fourier --seamless --hurst 0.3 --size 128 -o " +
                         quote(dir / "h.png"))
                .status == 0);
    CHECK(impulse::output::probe_image(dir / "h.png").bits == 16);

    const Result a = run(dir, "analyze " + quote(dir / "f.exr") + " --structure --json");
    REQUIRE(a.status == 0);
    CHECK_THAT(a.out, Contains("\"structure\":{\"lags\":[1,2,4,8,16,32],\"f\":[1"));
    const std::string key = "\"hurst\":[{\"s\":0,\"H\":";
    const size_t at = a.out.find(key);
    REQUIRE(at != std::string::npos);
    // One 128^2 realization: H(0)'s sampling sd is about 0.006 (64 realizations of 512^2 give a
    // band of 0.0002, tests/synth); 0.03 is five of it.
    CHECK(std::abs(std::stod(a.out.substr(at + key.size())) - 0.3) < 0.03);
}

TEST_CASE("analyze --variance-map writes the per-pixel variance over frames", "[cli][synth]") {
    TempDir dir;
    for (int s = 0; s < 8; ++s)
        REQUIRE(run(dir, "synth fbm --method exact --hurst 0.5 --size 64 --seed " +
                             std::to_string(s) + " -o " +
                             quote(dir / ("f_000" + std::to_string(s) + ".exr")))
                    .status == 0);
    const Result a = run(dir, "analyze " + quote(dir / "f_####.exr") + " --variance-map " +
                                  quote(dir / "v.exr"));
    REQUIRE(a.status == 0);
    const impulse::render::Frame v = impulse::output::read_image(dir / "v.exr");
    CHECK(v.at(0, 0) == 0.0f);  // B(0, 0) = 0 in every realization
    // VAR B(m) = |m|^{2H} = |m| for H = 1/2: the far corner (89.1) against (1, 1) (1.41); with 8
    // realizations each estimate is within a factor of ~3 (chi-square with 7 degrees of freedom).
    CHECK(v.at(63, 63) > 10.0f * v.at(1, 1));
    const Result one = run(dir, "analyze " + quote(dir / "f_0000.exr") + " --variance-map " +
                                    quote(dir / "w.exr"));
    CHECK(one.status != 0);
    CHECK_THAT(one.err, Contains("at least 2 frames"));
}
