// SPDX-License-Identifier: Apache-2.0
#pragma once
// Atlases and flow maps for game engines (part of impulse::output; docs/export.md): frames or
// slices laid out as rows x columns of cells in one image, and a velocity field in the usual
// two-channel flow-map encoding.

#include <cstdint>
#include <string>
#include <vector>

namespace impulse::output {

/// Cells of `cell_width` x `cell_height` pixels, `rows` x `columns` of them, filled row by row
/// from the top-left (cell i at row i / columns, column i % columns).
struct AtlasLayout {
    int rows = 1, columns = 1;
    int cell_width = 0, cell_height = 0;
    int width() const { return columns * cell_width; }
    int height() const { return rows * cell_height; }
    int64_t cells() const { return int64_t(rows) * columns; }
};

/// The layout of `count` cells: `text` "RxC" (rows x columns) when given, else the squarest
/// grid that holds them (columns = ceil(sqrt(count)), rows = ceil(count / columns)). Throws
/// ValueError "--layout TEXT: ..." for a malformed text, a grid that cannot hold `count`
/// (naming one that can), or an atlas wider or taller than 32768 pixels.
AtlasLayout atlas_layout(const std::string& text, int64_t count, int cell_width, int cell_height);

/// Copies a cell (`channels` interleaved floats per pixel, rows of layout.cell_width) into cell
/// `index` of `atlas` (layout.width() x layout.height() pixels, the same channels), bit for bit.
void place_cell(const AtlasLayout& layout, int index, int channels, const float* cell,
                std::vector<float>& atlas);

/// The flow-map encoding of a velocity (vx, vy): R, G = 0.5 + 0.5 v / vmax (clamped to [0, 1]),
/// B = 0, so (0.5, 0.5) is still; +x to the right, +y down the picture (the frame's rows).
/// `vmax` > 0.
void encode_flow(const std::vector<double>& vx, const std::vector<double>& vy, double vmax,
                 std::vector<float>& rgb);

}  // namespace impulse::output
