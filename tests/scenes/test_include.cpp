// SPDX-License-Identifier: Apache-2.0
// `include`: included files are the base, the including file's keys override them (sections
// merge key by key, everything else is replaced whole), paths resolve from the file they are
// written in, errors name that file, cycles and missing files are refused, --set comes last.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <future>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/support.h"
#include "numeric/errors.h"

using namespace impulse;
namespace S = impulse::scenes;
namespace fs = std::filesystem;
using Catch::Contains;
using Catch::StartsWith;

namespace {

std::string error_of(const std::string& path, const std::vector<std::string>& sets = {}) {
    try {
        S::load_scene(path, sets);
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

}  // namespace

TEST_CASE("included tables are the base and the including file overrides them",
          "[scenes][include]") {
    test::TempDir dir("include");
    test::write_file(dir / "base.toml", R"(
[output]
size = [64, 48]
fps = 12
frames = 5
[camera]
zoom = 2.0
[shading]
relief = 2.0
ambient = 0.5
[[layer]]
density = 4.0
gain = { keys = [[0.0, 1.0], [2.0, 3.0]], ease = "smooth" }
[[layer]]
density = 9.0
)");
    test::write_file(dir / "scene.toml", R"(
include = "base.toml"
[output]
frames = 7
[shading]
ambient = 0.1
[[layer]]
density = 6.0
gain = { keys = [[0.0, 2.0], [1.0, 1.0]] }
)");
    const S::Scene s = S::load_scene(dir / "scene.toml");
    // [output] and [shading] merge key by key.
    CHECK(s.output.width == 64);
    CHECK(s.output.fps == 12);
    CHECK(s.output.frames == 7);
    CHECK(s.camera.zoom.value(0) == 2.0);
    CHECK(s.shading.relief == 2.0);
    CHECK(s.shading.ambient == 0.1);
    // [[layer]] is replaced whole: one layer, the including file's.
    REQUIRE(s.layers.size() == 1);
    CHECK(s.layers[0].density.value(0) == 6.0);
    // An inline table (here keyframes) is a value: replaced whole, so no "smooth" from the base.
    CHECK(s.layers[0].gain.ease == numeric::Ease::Linear);
    CHECK(s.layers[0].gain.value(0.5) == 1.5);

    // --set applies after the includes, over both files.
    const S::Scene set = S::load_scene(dir / "scene.toml", {"output.fps=24", "output.size=[32,16]"});
    CHECK(set.output.fps == 24);
    CHECK(set.output.width == 32);
    CHECK(set.output.frames == 7);
    CHECK_THAT(error_of(dir / "scene.toml", {"include=\"base.toml\""}),
               StartsWith("--set include=\"base.toml\": include = \"base.toml\": includes are "
                          "resolved before --set applies"));

    // The hash covers the included text: editing the base changes it.
    const std::string hash = s.hash;
    test::write_file(dir / "base.toml", test::read_file(dir / "base.toml") + "\n# edited\n");
    CHECK(S::load_scene(dir / "scene.toml").hash != hash);
}

TEST_CASE("lists of includes and nested includes apply in order", "[scenes][include]") {
    test::TempDir dir("include");
    fs::create_directories(dir.path() / "lib" / "deeper");
    test::write_file(dir / "lib/deeper/common.toml", "[output]\nfps = 10\nframes = 3\nsize = [20, 10]\n");
    test::write_file(dir / "lib/a.toml", "include = \"deeper/common.toml\"\n[output]\nfps = 20\n[[layer]]\ndensity = 2.0\n");
    test::write_file(dir / "lib/b.toml", "[output]\nfps = 30\nframes = 4\n");
    test::write_file(dir / "scene.toml", "include = [\"lib/a.toml\", \"lib/b.toml\"]\n");
    const S::Scene s = S::load_scene(dir / "scene.toml");
    CHECK(s.output.fps == 30);     // b overrides a
    CHECK(s.output.frames == 4);   // b overrides common (through a)
    CHECK(s.output.width == 20);   // common, included by a, relative to a's directory
    REQUIRE(s.layers.size() == 1);  // from a
    CHECK(s.layers[0].density.value(0) == 2.0);
    // The same file included twice (not a cycle) is fine.
    test::write_file(dir / "twice.toml", "include = [\"lib/b.toml\", \"lib/b.toml\", \"lib/a.toml\"]\n");
    CHECK(S::load_scene(dir / "twice.toml").output.fps == 20);
}

TEST_CASE("paths in an included file resolve from that file's directory", "[scenes][include]") {
    test::TempDir dir("include");
    fs::create_directories(dir.path() / "sub");
    // A 2-channel image only sub/ holds, named by the included file.
    render::Frame img;
    img.resize(4, 4);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = 0.1f * float(i);
    output::write_image(dir / "sub/values.exr", img, {0.0, 1.0}, {});
    test::write_file(dir / "sub/layer.toml",
                     "[[layer]]\nmarginal = { type = \"empirical\", image = \"values.exr\" }\n");
    test::write_file(dir / "scene.toml", "include = \"sub/layer.toml\"\n");
    const S::Scene s = S::load_scene(dir / "scene.toml");
    REQUIRE(s.layers[0].marginal);
    CHECK(s.layers[0].marginal->target().mean() == Approx(0.75));
    // The same key written in the including file resolves from its own directory: not found.
    test::write_file(dir / "direct.toml",
                     "include = \"sub/layer.toml\"\n[[layer]]\nmarginal = { type = \"empirical\", image = \"values.exr\" }\n");
    CHECK_THAT(error_of(dir / "direct.toml"),
               StartsWith(dir / "direct.toml:3:") && Contains("image = \"values.exr\": cannot read"));
}

TEST_CASE("errors in included files name them, and cycles and missing files are refused",
          "[scenes][include]") {
    test::TempDir dir("include");
    fs::create_directories(dir.path() / "sub");
    test::write_file(dir / "sub/bad.toml", "[[layer]]\ngain = { keys = [[1.0, 1.0], [0.5, 2.0]] }\n");
    test::write_file(dir / "scene.toml", "include = \"sub/bad.toml\"\n");
    CHECK(error_of(dir / "scene.toml") ==
          dir / "sub/bad.toml:2:30: layer[0].gain.keys = [0.5, 2]: keyframes out of order: time 0.5 "
                "follows 1 (times must increase)");
    test::write_file(dir / "sub/syntax.toml", "[[layer]\n");
    test::write_file(dir / "syntax.toml", "include = \"sub/syntax.toml\"\n");
    CHECK_THAT(error_of(dir / "syntax.toml"), StartsWith(dir / "sub/syntax.toml:1:"));

    // a -> b -> a, and a file including itself.
    test::write_file(dir / "a.toml", "include = \"sub/b.toml\"\n[[layer]]\n");
    test::write_file(dir / "sub/b.toml", "include = [\"../a.toml\"]\n");
    CHECK(error_of(dir / "a.toml") ==
          dir / "sub/b.toml:1:12: include = \"../a.toml\": include cycle: " + dir / "a.toml -> " +
              dir / "sub/b.toml -> " + dir / "a.toml");
    test::write_file(dir / "self.toml", "include = \"self.toml\"\n[[layer]]\n");
    CHECK_THAT(error_of(dir / "self.toml"), Contains("self.toml\": include cycle: "));

    test::write_file(dir / "sub/ok.toml", "[output]\nfps = 10\n");
    test::write_file(dir / "missing.toml", "include = [\"sub/ok.toml\", \"nowhere.toml\"]\n[[layer]]\n");
    CHECK(error_of(dir / "missing.toml") ==
          dir / "missing.toml:1:27: include = \"nowhere.toml\": cannot open: No such file or "
                "directory (relative to this file's directory)");
}

TEST_CASE("include takes only regular files under 1 MiB: a FIFO, a device, a directory and a "
          "large file are refused with the including line", "[scenes][include][errors]") {
    test::TempDir dir("include-kinds");
    const std::string fifo = dir / "pipe.toml";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    test::write_file(dir / "big.toml", "# " + std::string(1 << 20, 'x') + "\n");
    fs::create_directories(dir.path() / "folder");
    struct Case {
        std::string include, expected;
    };
    for (const Case& c : {Case{"pipe.toml", "a FIFO: expected a regular file"},
                          Case{"/dev/zero", "a character device: expected a regular file"},
                          Case{"folder", "a directory: expected a regular file"},
                          Case{"big.toml", "1048579 bytes: a scene file is at most 1 MiB"}}) {
        INFO(c.include);
        test::write_file(dir / "scene.toml", "# a scene\ninclude = \"" + c.include + "\"\n[[layer]]\n");
        // A FIFO with no writer blocks its reader: the load runs aside, and is unblocked by
        // opening the FIFO's write end if it has not returned within 20 s.
        auto load = std::async(std::launch::async, [&] { return error_of(dir / "scene.toml"); });
        if (load.wait_for(std::chrono::seconds(20)) != std::future_status::ready) {
            FAIL_CHECK("the load blocked on " << c.include);
            const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
            if (fd >= 0) ::close(fd);
        }
        CHECK(load.get() == dir / "scene.toml" + ":2:11: include = \"" + c.include +
                                "\": cannot open: " + c.expected);
    }
    // The scene file itself too.
    CHECK(error_of(dir / "folder") == dir / "folder" + ": cannot open scene file: a directory: expected a regular file");
}
