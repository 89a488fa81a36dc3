// SPDX-License-Identifier: Apache-2.0
#pragma once
// Volumes out (part of impulse::output): a dense float grid as a multi-layer OpenEXR stack or an
// OpenVDB float grid, written atomically (a temporary file beside the target, renamed into
// place: an interrupted run never leaves half a volume, design.md §4).

#include <array>
#include <string>
#include <vector>

namespace impulse::output {

/// A dense W x H x D float grid, sample (i, j, k) at values[(k * H + j) * W + i] (x fastest).
struct VolumeGrid {
    std::array<int, 3> size{};  ///< W, H, D (each > 0)
    std::vector<float> values;  ///< W * H * D samples
};

/// How write_vdb stores a grid.
struct VdbOptions {
    std::string name = "density";  ///< grid name (Blender and Houdini look for "density")
    double voxel_size = 1.0;       ///< world units per voxel (the grid's uniform scale), > 0
    /// false: every sample becomes an active voxel (synth solid: values of both signs); true:
    /// samples equal to the background 0 stay inactive, so a cloud is stored sparsely.
    bool sparse = false;
};

/// Writes the grid as one OpenEXR image of W x H pixels with D float channels named z0000.Y,
/// z0001.Y ... (layer k = slice z = k), zip-compressed, `description` as ImageDescription and a
/// fixed DateTime so the bytes are a pure function of the values. Throws IoError with OIIO's
/// message.
void write_exr_stack(const std::string& path, const VolumeGrid& grid,
                     const std::string& description);
/// Writes the grid as an OpenVDB file holding one fog-volume float grid (background 0, index
/// (i, j, k) = sample (i, j, k)), `description` in its "description" metadata. Throws IoError
/// with OpenVDB's message.
void write_vdb(const std::string& path, const VolumeGrid& grid, const std::string& description,
               const VdbOptions& options = {});
/// Reads the float grid `name` of an OpenVDB file into a dense grid over its active voxels'
/// bounding box starting at index (0, 0, 0) (inactive voxels read as the background). For
/// tests and tools. Throws IoError naming the file.
VolumeGrid read_vdb(const std::string& path, const std::string& name = "density");

/// A grid's header in an OpenVDB file: its name and value type as OpenVDB names it ("vec3s",
/// "float", ...).
struct VdbGridHeader {
    std::string name, type;
};
/// The grids of an OpenVDB file in file order, from the headers alone. Throws IoError naming
/// the file.
std::vector<VdbGridHeader> list_vdb_grids(const std::string& path);

/// A vector grid of an OpenVDB file, dense over its active voxels' bounding box (inactive voxels
/// read as the background).
struct VdbVectorGrid {
    std::array<int, 3> size{};    ///< W, H, D (0 when the grid has no active voxel)
    std::array<int, 3> origin{};  ///< the index of sample (0, 0, 0)
    /// 3 floats a sample (x, y, z components), sample (i, j, k) at 3 ((k H + j) W + i).
    std::vector<float> values;
    /// Index to world: world_r = sum_c linear[3 r + c] index_c + translation[r].
    std::array<double, 9> linear{};
    std::array<double, 3> translation{};
    bool affine = true;      ///< false: the grid's transform is not affine (a frustum)
    bool staggered = false;  ///< the grid's class is "staggered" (components on the faces)
};
/// An index-space box of voxels, both corners included.
struct VdbIndexBox {
    std::array<int, 3> min{}, max{};
};
/// The index box of the active voxels of grid `name` (empty: none; min > max), from the
/// file's statistics metadata (file_bbox_min, file_bbox_max: OpenVDB writes them) when
/// present, else by reading the grid. Throws IoError naming the file and the grid.
VdbIndexBox read_vdb_active_box(const std::string& path, const std::string& name);
/// Reads the vector grid `name` (vec3s or vec3d), dense over its active voxels' bounding box,
/// or over `box` when given (only the file's nodes that meet it are read: a slab of a large
/// grid). Throws IoError naming the file and the grid, also when the grid is not a vector grid.
VdbVectorGrid read_vdb_vectors(const std::string& path, const std::string& name,
                               const VdbIndexBox* box = nullptr);

}  // namespace impulse::output
