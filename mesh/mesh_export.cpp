// SPDX-License-Identifier: Apache-2.0
// Mesh -> OBJ text (mesh/detail/obj_format.h) or aiScene -> assimp's PLY exporter into memory ->
// atomic file (output/files.h); vertices in the Mesh's order either way.

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>

#include "mesh/mesh.h"
#include "mesh/detail/obj_format.h"
#include "numeric/errors.h"
#include "output/files.h"

namespace impulse::mesh {
namespace {

/// assimp's PLY exporter stores (int)(c * 255), truncating; the colour handed to it is the centre
/// of the 8-bit code nearest c, so the file holds round(255 c).
float ply_colour(float c) {
    const float code = std::round(std::clamp(c, 0.0f, 1.0f) * 255.0f);
    return (code + 0.5f) / 255.0f;
}

unsigned primitive_type(uint32_t face_size) {
    switch (face_size) {
        case 1: return aiPrimitiveType_POINT;
        case 2: return aiPrimitiveType_LINE;
        case 3: return aiPrimitiveType_TRIANGLE;
        default: return aiPrimitiveType_POLYGON;
    }
}

void copy_vertices(const Mesh& in, aiMesh& out) {
    const auto n = static_cast<unsigned>(in.positions.size());
    out.mNumVertices = n;
    out.mVertices = new aiVector3D[n];
    if (!in.normals.empty()) out.mNormals = new aiVector3D[n];
    if (!in.uvs.empty()) out.mTextureCoords[0] = new aiVector3D[n], out.mNumUVComponents[0] = 2;
    if (!in.colors.empty()) out.mColors[0] = new aiColor4D[n];
    for (unsigned v = 0; v < n; ++v) {
        const Vec3& p = in.positions[v];
        out.mVertices[v] = aiVector3D(p.x(), p.y(), p.z());
        if (out.mNormals) out.mNormals[v] = aiVector3D(in.normals[v].x(), in.normals[v].y(), in.normals[v].z());
        if (out.mTextureCoords[0]) out.mTextureCoords[0][v] = aiVector3D(in.uvs[v].x(), in.uvs[v].y(), 0.0f);
        if (!out.mColors[0]) continue;
        const Vec3& c = in.colors[v];
        out.mColors[0][v] = aiColor4D(ply_colour(c.x()), ply_colour(c.y()), ply_colour(c.z()), 1.0f);
    }
}

void copy_faces(const Mesh& in, aiMesh& out) {
    out.mNumFaces = static_cast<unsigned>(in.face_sizes.size());
    out.mFaces = new aiFace[out.mNumFaces];
    size_t at = 0;
    for (unsigned f = 0; f < out.mNumFaces; ++f) {
        aiFace& face = out.mFaces[f];
        face.mNumIndices = in.face_sizes[f];
        face.mIndices = new unsigned[face.mNumIndices];
        std::copy_n(in.indices.begin() + at, face.mNumIndices, face.mIndices);
        at += face.mNumIndices;
        out.mPrimitiveTypes |= primitive_type(face.mNumIndices);
    }
}

std::unique_ptr<aiScene> to_scene(const Mesh& mesh) {
    auto scene = std::make_unique<aiScene>();
    scene->mRootNode = new aiNode("impulse");
    scene->mRootNode->mNumMeshes = 1;
    scene->mRootNode->mMeshes = new unsigned[1]{0};
    scene->mNumMaterials = 1;
    scene->mMaterials = new aiMaterial*[1]{new aiMaterial()};
    scene->mNumMeshes = 1;
    scene->mMeshes = new aiMesh*[1]{new aiMesh()};
    scene->mMeshes[0]->mMaterialIndex = 0;
    copy_vertices(mesh, *scene->mMeshes[0]);
    copy_faces(mesh, *scene->mMeshes[0]);
    return scene;
}

}  // namespace

void write_mesh(const std::string& path, const Mesh& mesh) {
    check_mesh_output(path);
    if (output::lower_extension(path) == ".obj") {  // assimp's OBJ exporter renumbers vertices
        const std::string text = encode_obj(mesh);
        output::write_file_atomic(path, text.data(), text.size());
        return;
    }
    const std::unique_ptr<aiScene> scene = to_scene(mesh);
    Assimp::Exporter exporter;
    // ASCII PLY: assimp 5.2 cannot read back its own binary PLY with colours (0 vertices).
    const aiExportDataBlob* blob = exporter.ExportToBlob(scene.get(), "ply");
    if (!blob) throw IoError(path + ": cannot encode mesh: " + exporter.GetErrorString());
    output::write_file_atomic(path, blob->data, blob->size);
}

std::vector<synth::SolidPoint> solid_points(const std::vector<Vec3>& positions, double t) {
    std::vector<synth::SolidPoint> points(positions.size());
    for (size_t i = 0; i < positions.size(); ++i)
        points[i] = {positions[i].x(), positions[i].y(), positions[i].z(), t};
    return points;
}

std::vector<Vec3> vertex_normals(const Mesh& mesh) {
    std::vector<Eigen::Vector3d> sum(mesh.positions.size(), Eigen::Vector3d::Zero());
    size_t at = 0;
    for (const uint32_t size : mesh.face_sizes) {
        const uint32_t* f = mesh.indices.data() + at;
        at += size;
        for (uint32_t k = 1; k + 1 < size; ++k) {  // fan: twice the triangle's area along n
            const Eigen::Vector3d a = mesh.positions[f[0]].cast<double>();
            const Eigen::Vector3d n = (mesh.positions[f[k]].cast<double>() - a)
                                          .cross(mesh.positions[f[k + 1]].cast<double>() - a);
            for (const uint32_t v : {f[0], f[k], f[k + 1]}) sum[v] += n;
        }
    }
    std::vector<Vec3> normals(sum.size(), Vec3::Zero());
    for (size_t v = 0; v < sum.size(); ++v)
        if (sum[v].norm() > 0) normals[v] = sum[v].normalized().cast<float>();
    return normals;
}

}  // namespace impulse::mesh
