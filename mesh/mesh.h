// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::mesh — the solid-noise applications of Lewis 1989 §5 on real geometry
// (docs/mesh.md): meshes in and out through assimp (OBJ, PLY with per-vertex colour), solid wood
// and marble carved from a block (§5.1), porous iso-surface objects through OpenVDB's mesher
// (§5.2), stochastic deformation (§5.3), trajectories of particles forced by vector noise
// (Figs. 12-13), and a small orthographic preview renderer. Depends on synth (the noise) and
// output (shading ramps, transforms, atomic writes, PNG).

#include "mesh/deform.h"         // p + A v(p), 3-D or 4-D (animated) vector noise
#include "mesh/mesh_io.h"        // Mesh, read_mesh, write_mesh
#include "mesh/porous.h"         // iso-surfaces of noise times an envelope
#include "mesh/primitives.h"     // an icosphere to start from
#include "mesh/preview.h"        // orthographic software render to RGB
#include "mesh/solid_texture.h"  // wood and marble at vertices and on sections
#include "mesh/trajectories.h"   // particles forced by vector solid noise
