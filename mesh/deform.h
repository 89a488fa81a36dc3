// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stochastic deformation (Lewis 1989 §5.3; docs/mesh.md): every vertex displaced by a vector
// solid noise, "three independent scalar solid noises form the components of the vector field":
//     p' = p + A v(p, t) / sigma,   v = (eta_0, eta_1, eta_2),
// A the amount (mesh units per standard deviation), eta_c component c of one SolidNoise (3-D,
// or 4-D with t for an animation that moves the object through the noise). The displacement
// is a function of the position alone: a vertex moves the same whatever the mesh's order, and
// coincident vertices stay together (no cracks). Seeds give individuals (§5.3's
// "individuality"). Part of impulse::mesh.

#include "mesh/mesh_io.h"
#include "synth/solid.h"

namespace impulse::mesh {

struct DeformParams {
    synth::SolidParams noise;  ///< kernel radius L in mesh units (the feature size); dims 3 or 4
    double amount = 0.1;       ///< A, mesh units per standard deviation, finite
    double t = 0.0;            ///< 4-D: the time coordinate (noise units)
};

/// The displacement A v(p, t) / sigma at every position (bit-identical in any order).
std::vector<Vec3> displacements(const DeformParams& params, const std::vector<Vec3>& positions);
/// The mesh with displaced vertices; normals recomputed when it had normals.
Mesh deform_mesh(const DeformParams& params, const Mesh& mesh);

}  // namespace impulse::mesh
