// SPDX-License-Identifier: Apache-2.0
#pragma once
// Trajectories of particles forced by a vector solid noise (Lewis 1989 Figs. 12-13;
// docs/mesh.md): each particle starts at rest at a point drawn from the counter RNG keyed by
// (seed, particle) uniformly in a ball, and moves under
//     dv/dt = F v(x) / sigma - c v,   dx/dt = v,
// v = (eta_0, eta_1, eta_2) the vector noise, F the force, c the drag, integrated with fixed
// steps dt (semi-implicit Euler). With a strong drag the particles follow the field's
// streamlines at speed F / c per sd and gather where it converges. The paths are polylines of
// steps + 1 vertices, coloured from dark blue at the start to orange at the end. Every step
// evaluates the noise at all particles in one batch: bit-identical for any thread count.
// Part of impulse::mesh.

#include "mesh/mesh_io.h"
#include "synth/solid.h"

namespace impulse::mesh {

struct TrajectoryParams {
    synth::SolidParams noise;  ///< kernel radius in scene units, 3-D
    int particles = 200;       ///< in [1, 10^6]
    int steps = 400;           ///< in [1, 10^5]; particles x steps <= 10^8
    double dt = 0.01;          ///< time step, > 0
    double force = 10.0;       ///< F, acceleration per sd of the noise, finite
    double drag = 10.0;        ///< c >= 0, per unit time
    double radius = 1.0;       ///< the start ball's radius, > 0
    uint64_t seed = 0;         ///< start points (the noise has its own seed)
};

/// The start points (particle i from the counter RNG of (seed, i)).
std::vector<Vec3> trajectory_starts(const TrajectoryParams& params);
/// Polylines as line segments (faces of 2 vertices), particle i's vertices at
/// i (steps + 1) + s. Throws ValueError naming a field out of range.
Mesh trajectories(const TrajectoryParams& params);

}  // namespace impulse::mesh
