// SPDX-License-Identifier: Apache-2.0
// The malformed-scene corpus: every file in tests/scenes/errors/ starts with
// "# expect: <message>" and loading it must fail with exactly that one line (after the
// directory part of the path). Adding a case is adding a file.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace fs = std::filesystem;

TEST_CASE("every malformed scene in the corpus fails with its expected message", "[scenes][errors]") {
    const fs::path dir = fs::path(IMPULSE_SOURCE_DIR) / "tests" / "scenes" / "errors";
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    REQUIRE(files.size() >= 30);
    for (const auto& f : files) {
        std::ifstream in(f);
        std::string first;
        std::getline(in, first);
        const std::string prefix = "# expect: ";
        REQUIRE(first.rfind(prefix, 0) == 0);
        const std::string expected = (dir / first.substr(prefix.size())).string();
        INFO(f.filename().string());
        std::string got = "(no error)";
        try {
            impulse::scenes::load_scene(f.string());
        } catch (const impulse::Error& e) {
            got = e.what();
        }
        CHECK(got == expected);
        CHECK(got.find('\n') == std::string::npos);  // one line
    }
}
