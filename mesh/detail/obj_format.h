// SPDX-License-Identifier: Apache-2.0
#pragma once
// Wavefront OBJ read and written vertex for vertex (part of impulse::mesh, docs/mesh.md
// "Formats"): vertex i of the Mesh is the file's i-th `v` line, so attributes computed per
// vertex line up with the artist's mesh. assimp's OBJ importer makes a vertex of every face
// corner and its exporter renumbers vertices by first use, so neither keeps that order.

#include <string>

#include "mesh/mesh_io.h"

namespace impulse::mesh {

/// Parses OBJ text (`v` with optional `r g b`, `vt`, `vn`, `f`, `l`, `p`; other records
/// ignored). Normals, texture coordinates and colours are kept when every vertex has exactly
/// one. `path` names the file in errors: ValueError "PATH:LINE: ...: expected ...".
Mesh parse_obj(const std::string& text, const std::string& path);

/// The OBJ text of `mesh`: `v` lines in vertex order (9 significant digits, colours as
/// `v x y z r g b`), `vt`, `vn` one per vertex, faces as `f`, 2-vertex faces as `l`, points as `p`.
std::string encode_obj(const Mesh& mesh);

}  // namespace impulse::mesh
