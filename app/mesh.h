// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse mesh texture|porous|deform|sphere|view` and `impulse trajectories`: the solid-noise
// applications of Lewis 1989 §5 on meshes (mesh/mesh.h, docs/mesh.md).

#include <string>

namespace CLI {
class App;
}

namespace impulse::app {

/// The options of the mesh commands, as given (checked when run).
struct MeshOptions {
    std::string input, output;
    // the noise
    std::string scale, density = "16", seed = "0";
    // texture
    std::string transform, section, axis = "z", center, direction = "1,0,0", turbulence;
    std::string ring_width, growth, sharpness, frequency, pixels = "512";
    // porous
    std::string iso, envelope = "sphere", falloff = "0.3", size = "128";
    // deform
    std::string amount, frames, speed;
    // sphere
    std::string levels = "5";
    // view
    std::string azimuth = "35", elevation = "25";
    // trajectories
    std::string particles = "200", steps = "400", dt = "0.01", force = "10", drag = "10", radius = "1";
};

/// Adds `mesh` (texture, porous, deform, sphere, view) to `app`; returns it.
CLI::App* add_mesh(CLI::App& app, MeshOptions& options);
/// Adds `trajectories` to `app`; returns it.
CLI::App* add_trajectories(CLI::App& app, MeshOptions& options);
/// Runs the mesh subcommand that was given; throws ValueError or IoError (one line), nothing
/// written then.
int run_mesh(const CLI::App& mesh, const MeshOptions& options);
int run_trajectories(const MeshOptions& options);

}  // namespace impulse::app
