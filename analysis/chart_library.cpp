// SPDX-License-Identifier: Apache-2.0
// The chart library `impulse analyze --report` inlines: the Vega modules of Debian's libjs-vega
// (design.md §6, "The report's plots drawn by Vega"). Debian ships Vega as one UMD file per
// module and no bundle; each file, run as a plain script, would replace the global `vega` of the
// one before it, so the page runs them under a small AMD `define` that keeps each module's
// exports by name and hands a module those it asks for.

#include "analysis/report.h"

#include <array>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <utility>

#include "numeric/errors.h"

#ifndef IMPULSE_VEGA_DIR
#define IMPULSE_VEGA_DIR "/usr/share/javascript/vega"
#endif

namespace impulse::analysis {
namespace {

/// The modules the report's specs need (parser, view, scales, SVG scenegraph, the formula
/// and encoding transforms), each after those it asks for: (the name its `define` asks for,
/// the file in the folder). Debian names the file of `vega-selections` vega-selection.min.js.
constexpr std::array<std::pair<const char*, const char*>, 19> kVegaModules{{
    {"vega-util", "vega-util.min.js"},
    {"vega-time", "vega-time.min.js"},
    {"vega-format", "vega-format.min.js"},
    {"vega-loader", "vega-loader.min.js"},
    {"vega-dataflow", "vega-dataflow.min.js"},
    {"vega-canvas", "vega-canvas.min.js"},
    {"vega-scale", "vega-scale.min.js"},
    {"vega-scenegraph", "vega-scenegraph.min.js"},
    {"vega-expression", "vega-expression.min.js"},
    {"vega-event-selector", "vega-event-selector.min.js"},
    {"vega-selections", "vega-selection.min.js"},
    {"vega-statistics", "vega-statistics.min.js"},
    {"vega-functions", "vega-functions.min.js"},
    {"vega-runtime", "vega-runtime.min.js"},
    {"vega-view", "vega-view.min.js"},
    {"vega-parser", "vega-parser.min.js"},
    {"vega-encode", "vega-encode.min.js"},
    {"vega-transforms", "vega-transforms.min.js"},
    {"vega-view-transforms", "vega-view-transforms.min.js"},
}};

/// Before the modules: `define` records a module's exports under the name set before its file.
constexpr const char* kDefine =
    "window.impulseVega = {};\n"
    "window.impulseModule = '';\n"
    "window.define = function (deps, factory) {\n"
    "  const exports = {};\n"
    "  factory.apply(null, deps.map((d) => (d === 'exports' ? exports : impulseVega[d])));\n"
    "  impulseVega[impulseModule] = exports;\n"
    "};\n"
    "define.amd = true;\n";

/// After them: no `define` left behind for other scripts to mistake for a loader.
constexpr const char* kUndefine = ";\ndelete window.define;\ndelete window.impulseModule;\n";

/// A module's text, or "" when it cannot be read.
std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return "";
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// `</script` would end the page's <script> element early; `<\/script` means the same in a JS
/// string or regular expression, the only places it can stand in a module (none of Debian's
/// 5.22.1 files holds one; this keeps a later version safe).
std::string script_safe(std::string js) {
    const auto lower = [](char c) { return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c; };
    for (size_t at = js.find("</"); at != std::string::npos; at = js.find("</", at + 2)) {
        std::string tag = js.substr(at + 2, 6);
        for (char& c : tag) c = lower(c);
        if (tag == "script") js.replace(at, 2, "<\\/");
    }
    return js;
}

}  // namespace

std::string chart_library_dir() {
    const char* env = std::getenv("IMPULSE_VEGA_DIR");
    return env && *env ? std::string(env) : std::string(IMPULSE_VEGA_DIR);
}

std::string load_chart_library() {
    const std::string dir = chart_library_dir();
    std::string js = kDefine;
    for (const auto& [name, file] : kVegaModules) {
        const std::string path = dir + "/" + file;
        const std::string text = read_text(path);
        if (text.empty())
            throw IoError(path + ": " + (std::ifstream(path) ? "empty" : "cannot be read") +
                          ": the report's charts need Vega from Debian's libjs-vega (apt install "
                          "libjs-vega), or IMPULSE_VEGA_DIR naming a folder of its vega-*.min.js");
        js += "impulseModule = '" + std::string(name) + "';\n" + script_safe(text) + "\n";
    }
    return js + kUndefine;
}

}  // namespace impulse::analysis
