// SPDX-License-Identifier: Apache-2.0
// impulse-mesh: `impulse mesh ...` and `impulse trajectories ...` (app/mesh.h, docs/mesh.md). A
// companion of the `impulse` tool, which runs it for those two commands: they need assimp and
// OpenVDB, and linking those into `impulse` would load them with every command (issue 19:
// start-up). Same options, messages and exit status as any impulse command.

#include <CLI/CLI.hpp>
#include <iostream>

#include "app/mesh.h"
#include "numeric/errors.h"

int main(int argc, char** argv) {
    CLI::App app{"impulse: solid-noise applications on meshes (Lewis 1989 §5)", "impulse"};
    app.require_subcommand(1);
    impulse::app::MeshOptions mo, to;
    CLI::App* mesh = impulse::app::add_mesh(app, mo);
    CLI::App* trajectories = impulse::app::add_trajectories(app, to);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;  // 2 for a bad command line, as `impulse`
    }
    try {
        if (*mesh) return impulse::app::run_mesh(*mesh, mo);
        if (*trajectories) return impulse::app::run_trajectories(to);
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
