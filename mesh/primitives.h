// SPDX-License-Identifier: Apache-2.0
#pragma once
// A test and example shape (part of impulse::mesh), so nobody needs a mesh file to start.

#include "mesh/mesh_io.h"

namespace impulse::mesh {

/// The unit icosphere: an icosahedron whose triangles are split in four `levels` times
/// (levels in [0, 9]; 10 4^levels + 2 vertices, 20 4^levels triangles), shared vertices.
Mesh icosphere(int levels);

}  // namespace impulse::mesh
