// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to `impulse export` (app/export.cpp, app/export_volume.cpp): the JSON sidecar and the
// volume subcommand.

#include <charconv>
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
}

namespace impulse::scenes {
struct Scene;
}

namespace impulse::app {

struct ExportOptions;

/// The shortest text that reads back as `v` (a JSON number for finite v).
inline std::string fmt(double v) {
    char buffer[32];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
    return std::string(buffer, r.ptr);
}

/// `s` as a JSON string (quotes, backslashes and control characters escaped).
std::string json_string(const std::string& s);

/// A JSON object written in the order its members are added; values are JSON text.
class JsonObject {
public:
    void add(const std::string& key, const std::string& json_value) { m_members.emplace_back(key, json_value); }
    /// The object, one member a line, with a final newline.
    std::string text() const;

private:
    std::vector<std::pair<std::string, std::string>> m_members;
};

/// The scene's file, hash and seed as sidecar members.
void add_scene_fields(JsonObject& j, const scenes::Scene& sc);
/// OUT.json for OUT.exr or OUT.png.
std::string sidecar_path(const std::string& image);
/// Writes `text` to `path` atomically (output::write_file_atomic).
void write_text(const std::string& path, const std::string& text);

/// Adds `export volume` to `export_command`.
void add_volume_export(CLI::App& export_command, ExportOptions& options);
/// Runs `export volume`.
int run_volume_export(const ExportOptions& options);

}  // namespace impulse::app
