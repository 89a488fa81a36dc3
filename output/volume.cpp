// SPDX-License-Identifier: Apache-2.0
// Volumes out: multi-layer EXR stacks (OpenImageIO) and OpenVDB float grids, written atomically
// (part of libimpulse_io.so, output/io_module.h; volume.h documents the calls).

#include "output/detail/io_impl.h"

#include <OpenImageIO/imageio.h>
#include <openvdb/openvdb.h>

#include <cstdio>
#include <filesystem>
#include <mutex>

#include "numeric/errors.h"
#include "output/files.h"

namespace impulse::output::io {
namespace {

namespace fs = std::filesystem;

void check_grid(const std::string& path, const VolumeGrid& g) {
    const auto& n = g.size;
    if (n[0] <= 0 || n[1] <= 0 || n[2] <= 0 ||
        g.values.size() != size_t(n[0]) * size_t(n[1]) * size_t(n[2]))
        throw ValueError(path + ": volume of " + std::to_string(g.values.size()) +
                         " samples does not match its size");
}

void initialize_vdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

void write_exr_stack(const std::string& path, const VolumeGrid& grid,
                     const std::string& description) {
    check_grid(path, grid);
    const int W = grid.size[0], H = grid.size[1], D = grid.size[2];
    OIIO::ImageSpec spec(W, H, D, OIIO::TypeDesc::FLOAT);
    spec.depth = 1;
    spec.channelnames.clear();
    for (int k = 0; k < D; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "z%04d.Y", k);
        spec.channelnames.push_back(name);
    }
    spec.attribute("compression", "zip");
    spec.attribute("ImageDescription", description);
    spec.attribute("DateTime", "1970:01:01 00:00:00");  // a pure function of the options
    // Interleave: pixel (i, j) holds the D layers' values.
    std::vector<float> px(size_t(W) * H * D);
    for (int k = 0; k < D; ++k)
        for (size_t p = 0; p < size_t(W) * H; ++p) px[p * D + k] = grid.values[size_t(k) * W * H + p];
    const std::string tmp = partial_path(path);
    auto out = OIIO::ImageOutput::create(tmp);
    const bool ok = out && out->open(tmp, spec) && out->write_image(OIIO::TypeDesc::FLOAT, px.data());
    std::string err = out ? out->geterror() : OIIO::geterror();
    if (out && !out->close() && err.empty()) err = out->geterror();
    if (!ok || !err.empty()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot write: " + (err.empty() ? std::string("unknown error") : err));
    }
    commit_partial(tmp, path);
}

void write_vdb(const std::string& path, const VolumeGrid& g, const std::string& description,
               const VdbOptions& options) {
    check_grid(path, g);
    initialize_vdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(options.name);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->insertMeta("description", openvdb::StringMetadata(description));
    if (options.voxel_size != 1.0)
        grid->setTransform(openvdb::math::Transform::createLinearTransform(options.voxel_size));
    auto acc = grid->getAccessor();
    const auto& n = g.size;
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const float v = g.values[(size_t(k) * n[1] + j) * n[0] + i];
                if (!options.sparse || v != 0.0f) acc.setValue({i, j, k}, v);
            }
    const std::string tmp = partial_path(path);
    try {
        openvdb::io::File file(tmp);
        file.write({grid});
        file.close();
    } catch (const std::exception& e) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot write: " + e.what());
    }
    commit_partial(tmp, path);
}

VolumeGrid read_vdb(const std::string& path, const std::string& name) {
    initialize_vdb();
    openvdb::GridBase::Ptr base;
    try {
        openvdb::io::File file(path);
        file.open();
        base = file.readGrid(name);
        file.close();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read grid \"" + name + "\": " + e.what());
    }
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid) throw IoError(path + ": grid \"" + name + "\" is not a float grid");
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    VolumeGrid out;
    if (box.empty()) return out;
    const openvdb::Coord hi = box.max();
    out.size = {hi.x() + 1, hi.y() + 1, hi.z() + 1};
    out.values.assign(size_t(out.size[0]) * out.size[1] * out.size[2], 0.0f);
    auto acc = grid->getConstAccessor();
    for (int k = 0; k < out.size[2]; ++k)
        for (int j = 0; j < out.size[1]; ++j)
            for (int i = 0; i < out.size[0]; ++i)
                out.values[(size_t(k) * out.size[1] + j) * out.size[0] + i] = acc.getValue({i, j, k});
    return out;
}

std::vector<VdbGridHeader> list_vdb_grids(const std::string& path) {
    initialize_vdb();
    std::vector<VdbGridHeader> out;
    try {
        openvdb::io::File file(path);
        file.open(false);  // headers only: no delayed loading of the voxels
        const openvdb::GridPtrVecPtr grids = file.readAllGridMetadata();  // held: the loop reads it
        for (const auto& g : *grids) out.push_back({g->getName(), g->valueType()});
        file.close();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read: " + e.what());
    }
    return out;
}

namespace {

/// The dense samples of `grid` (vec3s or vec3d) over `box` (empty: its active bounding box)
/// into `out`.
template <typename GridT>
void copy_vectors(const GridT& grid, openvdb::CoordBBox box, VdbVectorGrid& out) {
    if (box.empty()) box = grid.evalActiveVoxelBoundingBox();
    if (box.empty()) return;
    const openvdb::Coord lo = box.min(), dim = box.dim();
    out.origin = {lo.x(), lo.y(), lo.z()};
    out.size = {dim.x(), dim.y(), dim.z()};
    out.values.resize(size_t(3) * out.size[0] * out.size[1] * out.size[2]);
    auto acc = grid.getConstAccessor();
    size_t n = 0;
    for (int k = 0; k < out.size[2]; ++k)
        for (int j = 0; j < out.size[1]; ++j)
            for (int i = 0; i < out.size[0]; ++i) {
                const auto v = acc.getValue(lo.offsetBy(i, j, k));
                for (int c = 0; c < 3; ++c) out.values[n++] = static_cast<float>(v[c]);
            }
}

}  // namespace

VdbIndexBox read_vdb_active_box(const std::string& path, const std::string& name) {
    initialize_vdb();
    openvdb::CoordBBox b;
    try {
        openvdb::io::File file(path);
        file.open(false);
        const auto head = file.readGridMetadata(name);
        const auto lo = head->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MIN);
        const auto hi = head->getMetadata<openvdb::Vec3IMetadata>(openvdb::GridBase::META_FILE_BBOX_MAX);
        if (lo && hi) b = {openvdb::Coord(lo->value()), openvdb::Coord(hi->value())};
        else b = file.readGrid(name)->evalActiveVoxelBoundingBox();
        file.close();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read grid \"" + name + "\": " + e.what());
    }
    if (b.empty()) return {{0, 0, 0}, {-1, -1, -1}};
    return {{b.min().x(), b.min().y(), b.min().z()}, {b.max().x(), b.max().y(), b.max().z()}};
}

VdbVectorGrid read_vdb_vectors(const std::string& path, const std::string& name,
                               const VdbIndexBox* box) {
    initialize_vdb();
    openvdb::GridBase::Ptr base;
    openvdb::CoordBBox clip;
    try {
        openvdb::io::File file(path);
        file.open(false);
        if (box) {
            // the grid's transform first (metadata only), then the nodes that meet the box
            clip = {{box->min[0], box->min[1], box->min[2]}, {box->max[0], box->max[1], box->max[2]}};
            const auto head = file.readGridMetadata(name);
            const openvdb::BBoxd index(clip.min().asVec3d() - openvdb::Vec3d(0.5),
                                       clip.max().asVec3d() + openvdb::Vec3d(0.5));
            const openvdb::BBoxd world = head->transform().indexToWorld(index);
            base = file.readGrid(name, world);
        } else {
            base = file.readGrid(name);
        }
        file.close();
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read grid \"" + name + "\": " + e.what());
    }
    VdbVectorGrid out;
    if (auto g = openvdb::gridPtrCast<openvdb::Vec3SGrid>(base)) copy_vectors(*g, clip, out);
    else if (auto d = openvdb::gridPtrCast<openvdb::Vec3DGrid>(base)) copy_vectors(*d, clip, out);
    else
        throw IoError(path + ": grid \"" + name + "\" holds " + base->valueType() +
                      " values: expected a vector grid (vec3s or vec3d)");
    out.staggered = base->getGridClass() == openvdb::GRID_STAGGERED;
    const auto map = base->transform().baseMap();
    out.affine = map->isLinear();
    if (out.affine) {
        // OpenVDB multiplies row vectors: world = index * M, the translation in M's last row.
        const openvdb::Mat4d m = map->getAffineMap()->getMat4();
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) out.linear[size_t(3 * r + c)] = m(c, r);
            out.translation[size_t(r)] = m(3, r);
        }
    }
    return out;
}

}  // namespace impulse::output::io
