// SPDX-License-Identifier: Apache-2.0
// `impulse preview`'s pieces without a browser: the keys it exposes, the TOML lines it shows,
// the files it watches.

#include <catch2/catch.hpp>

#include "app/detail/preview.h"
#include "numeric/errors.h"
#include "tests/support.h"

using namespace impulse::app::preview;
using Catch::Matchers::Contains;
using impulse::test::TempDir;
using impulse::test::write_file;

namespace {

Exposed key(const std::string& k, double v, bool integer = false) {
    Exposed e;
    e.key = k, e.value = v, e.integer = integer;
    return e;
}

const char* const kBase = R"(
[output]
size = [64, 48]
fps = 24
[[layer]]
density = 12.0
[layer.kernel]
type = "gaussian"
radius = 8.0
)";

}  // namespace

TEST_CASE("toml_line names the table the line goes in", "[preview]") {
    CHECK(toml_line(key("layer.0.kernel.radius", 8.5)) ==
          "radius = 8.5  # in [layer.kernel] of [[layer]] 0");
    CHECK(toml_line(key("layer.1.density", 12)) == "density = 12.0  # in [[layer]] 1");
    CHECK(toml_line(key("layer.0.flow.1.speed", 3)) ==
          "speed = 3.0  # in [[layer.flow]] 1 of [[layer]] 0");
    CHECK(toml_line(key("output.fps", 24, true)) == "fps = 24  # in [output]");
    CHECK(toml_line(key("seed", 7, true)) == "seed = 7");
    CHECK(toml_number(1e-7, false) == "1e-07");
}

TEST_CASE("exposed keys are read from the scene, then from its includes", "[preview]") {
    TempDir dir("preview");
    write_file(dir / "base.toml", kBase);
    write_file(dir / "scene.toml", "include = \"base.toml\"\n[output]\nfps = 30\n");
    const std::vector<Exposed> e =
        exposed_keys(dir / "scene.toml", {"output.fps", "layer.0.kernel.radius=2:32"});
    REQUIRE(e.size() == 2);
    CHECK(e[0].value == 30.0);  // the scene's own value, not base.toml's 24
    CHECK((e[0].integer && e[0].lo == 0.0 && e[0].hi == 60.0 && e[0].step == 1.0));
    CHECK((e[1].value == 8.0 && !e[1].integer && e[1].lo == 2.0 && e[1].hi == 32.0));

    CHECK_THROWS_WITH(exposed_keys(dir / "scene.toml", {"layer.0.kernel.type"}),
                      Contains("layer.0.kernel.type: not a number in the scene file"));
    CHECK_THROWS_WITH(exposed_keys(dir / "scene.toml", {"layer.0.gain"}),
                      Contains("layer.0.gain: not set in the scene file"));
    CHECK_THROWS_WITH(exposed_keys(dir / "scene.toml", {"output.fps=9:3"}),
                      Contains("expected KEY or KEY=LO:HI with numbers LO < HI"));
}

TEST_CASE("the watched files are the scene and its includes", "[preview]") {
    TempDir dir("preview");
    write_file(dir / "base.toml", kBase);
    write_file(dir / "scene.toml", "include = [\"base.toml\"]\n");
    const std::vector<FileStamp> before = scene_files(dir / "scene.toml");
    REQUIRE(before.size() == 2);
    CHECK((before[0].exists && before[1].exists));
    CHECK(before[1].path == dir / "base.toml");
    std::filesystem::remove(dir / "base.toml");
    const std::vector<FileStamp> after = scene_files(dir / "scene.toml");
    REQUIRE(after.size() == 2);
    CHECK(!after[1].exists);
    CHECK(after != before);
}
