// SPDX-License-Identifier: Apache-2.0
// Every ```toml block of docs/scenes.md is a complete scene that loads (relative paths from the
// repository root), so the documentation cannot drift from the loader. A block fenced
// ```toml fragment is part of a scene (a table that needs files the repository does not hold,
// such as a simulation's cache) and is not loaded.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "scenes/scenes.h"
#include "numeric/errors.h"

TEST_CASE("every toml block of docs/scenes.md loads as a scene", "[scenes][docs]") {
    namespace fs = std::filesystem;
    const fs::path root(IMPULSE_SOURCE_DIR);
    std::ifstream in(root / "docs" / "scenes.md");
    REQUIRE(in);
    std::vector<std::pair<int, std::string>> blocks;  // (first line, text)
    std::string line, block;
    int number = 0, start = 0;
    bool inside = false;
    while (std::getline(in, line)) {
        ++number;
        if (!inside && line == "```toml") {
            inside = true, start = number + 1, block.clear();
        } else if (inside && line == "```") {
            inside = false;
            blocks.emplace_back(start, block);
        } else if (inside) {
            block += line + "\n";
        }
    }
    REQUIRE(blocks.size() >= 20);
    for (const auto& [first, text] : blocks) {
        INFO("docs/scenes.md line " << first << ":\n" << text);
        std::string error;
        try {
            impulse::scenes::load_scene_string(text, (root / "docs-example.toml").string());
        } catch (const impulse::Error& e) {
            error = e.what();
        }
        CHECK(error.empty());
        if (!error.empty()) FAIL_CHECK(error);
    }
}
