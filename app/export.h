// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse export flipbook|flowmap|volume`: what game engines take (docs/export.md) — a looping
// sequence as one atlas of frames, a layer's velocity field as a flow map, periodic solid noise
// as a slice atlas and a raw float volume; each with a JSON sidecar.

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace impulse::app {

/// Options of `impulse export ...`, as given ("": the default).
struct ExportOptions {
    std::string scene, output, frames, layout, size, seed;
    std::vector<std::string> sets;
    bool loop = false, tileable = false;  ///< flipbook: check and record a loop / a tile
    std::string layer, frame, vmax, bits;  ///< flowmap
    std::string volume_size, radius, density, kernel;  ///< volume
    int threads = 0;
};

/// Adds `export` and its three subcommands to `app`, filling `options`; returns `export`.
CLI::App* add_export(CLI::App& app, ExportOptions& options);

/// Runs the subcommand `export_command` received. Every check comes before any file is
/// written; a refused request is one line (ValueError, IoError, SceneError) and nothing written.
int run_export(const CLI::App& export_command, const ExportOptions& options);

}  // namespace impulse::app
