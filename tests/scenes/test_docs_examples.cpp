// SPDX-License-Identifier: Apache-2.0
// The schema document and the loader agree: every ```toml example in docs/scenes.md loads.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "scenes/scenes.h"
#include "util/errors.h"

using namespace impulse;

namespace {

struct Example {
    int line = 0;  ///< line of the opening fence in docs/scenes.md
    std::string text;
};

std::vector<Example> toml_examples(const std::string& path) {
    std::ifstream in(path);
    REQUIRE(in);
    std::vector<Example> out;
    std::string line;
    int n = 0;
    Example* open = nullptr;
    while (std::getline(in, line)) {
        ++n;
        if (!open && line.rfind("```toml", 0) == 0) {
            out.push_back({n, {}});
            open = &out.back();
        } else if (open && line.rfind("```", 0) == 0) {
            open = nullptr;
        } else if (open) {
            open->text += line + "\n";
        }
    }
    REQUIRE(open == nullptr);  // every fence closed
    return out;
}

}  // namespace

TEST_CASE("every TOML example in docs/scenes.md loads as a scene", "[scenes][docs]") {
    const std::string root = IMPULSE_SOURCE_DIR;
    const auto examples = toml_examples(root + "/docs/scenes.md");
    // The document has an example per section; a handful would mean the extraction broke.
    REQUIRE(examples.size() >= 15);
    for (const auto& e : examples) {
        // The convention stated at the top of docs/scenes.md: an example without a [[layer]]
        // stands for a scene with one layer (its sub-tables, [layer.kernel] or [[layer.flow]],
        // if it shows them; a default layer otherwise).
        std::string text = e.text;
        if (text.find("[[layer]]") == std::string::npos)
            text = text.find("[layer.") != std::string::npos ? "[[layer]]\n" + text : text + "\n[[layer]]\n";
        // Relative paths in examples resolve as in a scene file in scenes/.
        const std::string name = root + "/scenes/docs-example-" + std::to_string(e.line) + ".toml";
        INFO("docs/scenes.md line " << e.line << ":\n" << e.text);
        try {
            const scenes::Scene s = scenes::load_scene_string(text, name);
            CHECK(!s.hash.empty());
        } catch (const std::exception& ex) {
            FAIL_CHECK(ex.what());
        }
    }
}
