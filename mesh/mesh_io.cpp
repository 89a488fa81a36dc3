// SPDX-License-Identifier: Apache-2.0
// Meshes through assimp: the importer with its validation, the exporters to memory, then an
// atomic write (output/files.h).

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>

#include "mesh/mesh.h"
#include "numeric/errors.h"
#include "output/files.h"

namespace impulse::mesh {
namespace {

namespace fs = std::filesystem;

/// The first non-finite position of the file's meshes, as assimp read it (before joining).
void check_finite(const aiScene& scene, const std::string& path) {
    for (unsigned m = 0, base = 0; m < scene.mNumMeshes; base += scene.mMeshes[m]->mNumVertices, ++m) {
        const aiMesh& mesh = *scene.mMeshes[m];
        for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
            const aiVector3D& p = mesh.mVertices[v];
            if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) continue;
            std::ostringstream s;
            s << path << ": vertex " << base + v << " position (" << p.x << ", " << p.y << ", "
              << p.z << "): expected finite coordinates";
            throw ValueError(s.str());
        }
    }
}

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

}  // namespace

void Mesh::add_face(std::initializer_list<uint32_t> face) {
    indices.insert(indices.end(), face.begin(), face.end());
    face_sizes.push_back(static_cast<uint32_t>(face.size()));
}

Mesh read_mesh(const std::string& path) {
    Assimp::Importer importer;
    // Validation catches what the parsers let through (a PLY face index past the vertices).
    const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    if (!scene) throw IoError(path + ": cannot read mesh: " + importer.GetErrorString());
    check_finite(*scene, path);
    // Joined after the check, so a NaN never meets the vertex hash.
    scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices);
    if (!scene) throw IoError(path + ": cannot read mesh: " + importer.GetErrorString());
    Mesh mesh = from_scene(*scene);
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
