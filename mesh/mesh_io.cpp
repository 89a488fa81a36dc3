// SPDX-License-Identifier: Apache-2.0
// Meshes in: OBJ vertex for vertex (mesh/detail/obj_format.h), any other format through assimp
// with its validation; vertex i is the file's vertex i (docs/mesh.md "Formats").

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "mesh/mesh.h"
#include "mesh/detail/obj_format.h"
#include "numeric/errors.h"
#include "output/files.h"

namespace impulse::mesh {
namespace {

namespace fs = std::filesystem;

/// Appends one assimp mesh to `out` (vertex attributes present in every mesh are kept).
void append(const aiMesh& m, bool normals, bool uvs, bool colors, Mesh& out) {
    const auto base = static_cast<uint32_t>(out.positions.size());
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
        out.positions.emplace_back(m.mVertices[v].x, m.mVertices[v].y, m.mVertices[v].z);
        if (normals) out.normals.emplace_back(m.mNormals[v].x, m.mNormals[v].y, m.mNormals[v].z);
        if (uvs) out.uvs.emplace_back(m.mTextureCoords[0][v].x, m.mTextureCoords[0][v].y);
        if (colors) out.colors.emplace_back(m.mColors[0][v].r, m.mColors[0][v].g, m.mColors[0][v].b);
    }
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const aiFace& face = m.mFaces[f];
        for (unsigned k = 0; k < face.mNumIndices; ++k) out.indices.push_back(base + face.mIndices[k]);
        out.face_sizes.push_back(face.mNumIndices);
    }
}

Mesh from_scene(const aiScene& scene) {
    bool normals = scene.mNumMeshes > 0, uvs = normals, colors = normals;
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
        normals = normals && scene.mMeshes[m]->HasNormals();
        uvs = uvs && scene.mMeshes[m]->HasTextureCoords(0);
        colors = colors && scene.mMeshes[m]->HasVertexColors(0);
    }
    Mesh out;
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) append(*scene.mMeshes[m], normals, uvs, colors, out);
    return out;
}

/// The first non-finite position, numbered as in the file.
void check_finite(const Mesh& mesh, const std::string& path) {
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3& p = mesh.positions[v];
        if (p.allFinite()) continue;
        std::ostringstream s;
        s << path << ": vertex " << v << " position (" << p.x() << ", " << p.y() << ", " << p.z()
          << "): expected finite coordinates";
        throw ValueError(s.str());
    }
}

std::string read_text(const std::string& path) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) throw IoError(path + ": cannot read mesh: a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": cannot read mesh: " + std::strerror(errno));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw IoError(path + ": cannot read mesh: " + std::strerror(errno));
    return text.str();
}

/// Any format but OBJ through assimp, its vertices as the file lists them (no joining: that
/// would merge a seam's vertices and drop those no face uses, docs/mesh.md "Formats").
Mesh read_with_assimp(const std::string& path) {
    Assimp::Importer importer;
    // Validation catches what the parsers let through (a PLY face index past the vertices).
    const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_PreTransformVertices);
    if (!scene) throw IoError(path + ": cannot read mesh: " + importer.GetErrorString());
    return from_scene(*scene);
}

}  // namespace

void Mesh::add_face(std::initializer_list<uint32_t> face) {
    indices.insert(indices.end(), face.begin(), face.end());
    face_sizes.push_back(static_cast<uint32_t>(face.size()));
}

Mesh read_mesh(const std::string& path) {
    const bool obj = output::lower_extension(path) == ".obj";
    Mesh mesh = obj ? parse_obj(read_text(path), path) : read_with_assimp(path);
    check_finite(mesh, path);
    if (mesh.positions.empty()) throw ValueError(path + ": the file holds no vertices");
    return mesh;
}

void check_mesh_output(const std::string& path) {
    const std::string e = output::lower_extension(path);
    if (e != ".obj" && e != ".ply")
        throw ValueError(path + ": expected an output ending in .obj or .ply (the mesh writer's formats)");
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw IoError(path + ": cannot write: directory " + dir.string() + " does not exist");
}

}  // namespace impulse::mesh
