// SPDX-License-Identifier: Apache-2.0
#pragma once
// Meshes in and out (part of impulse::mesh; docs/mesh.md "Formats"), vertex i of the file being
// vertex i of the Mesh: OBJ by our own reader and writer (mesh/detail/obj_format.h; `v x y z r g b`
// vertex colours, `l` records for line segments), any other format assimp reads (PLY tested) in
// through assimp, ASCII PLY (uchar red green blue alpha per vertex, 2-vertex faces for line
// segments) out through assimp; written atomically.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

#include "synth/solid.h"

namespace impulse::mesh {

using Vec3 = Eigen::Vector3f;
using Vec2 = Eigen::Vector2f;

/// A polygon mesh, polylines or points: one vertex list, faces of any size (1 a point, 2 a line
/// segment, >= 3 a polygon).
struct Mesh {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  ///< empty or one per vertex
    std::vector<Vec2> uvs;      ///< empty or one per vertex (texture channel 0)
    std::vector<Vec3> colors;   ///< empty or one per vertex, display RGB in [0, 1]
    std::vector<uint32_t> indices;     ///< the faces' vertex indices, concatenated
    std::vector<uint32_t> face_sizes;  ///< vertices of each face

    size_t vertex_count() const { return positions.size(); }
    size_t face_count() const { return face_sizes.size(); }
    /// Appends a face; returns nothing, checks nothing.
    void add_face(std::initializer_list<uint32_t> face);
};

/// Reads a mesh, its vertices in the file's number and order (none joined, none dropped): an
/// OBJ by parse_obj (ValueError "PATH:LINE: ..."), any other format with assimp (every mesh of
/// the file flattened into one, node transforms applied; IoError "PATH: cannot read mesh:
/// <assimp's message>" when assimp refuses it). ValueError "PATH: vertex N position (x, y, z):
/// expected finite coordinates" for a NaN or infinite position, ValueError for no vertices.
Mesh read_mesh(const std::string& path);

/// Throws ValueError "PATH: expected an output ending in .obj or .ply" unless the writer knows the
/// extension (case-insensitive); IoError when the directory does not exist. Call before work.
void check_mesh_output(const std::string& path);

/// Writes `mesh` by its extension (.obj: encode_obj; .ply: assimp's exporter), vertices in
/// order, atomically. PLY colours are rounded to 8 bits. Throws ValueError (extension) or IoError.
void write_mesh(const std::string& path, const Mesh& mesh);

/// The positions as points of the noise's domain (t = `t`).
std::vector<synth::SolidPoint> solid_points(const std::vector<Vec3>& positions, double t = 0.0);

/// Area-weighted vertex normals of the polygons (fans), unit length (zero where no polygon).
std::vector<Vec3> vertex_normals(const Mesh& mesh);

}  // namespace impulse::mesh
