// SPDX-License-Identifier: Apache-2.0
#pragma once
// The grid every source renders into: an orthographic view (pixel centres in texture space)
// and a single-channel float frame. Shared by the renderers, the synthesizers, output and
// analysis.

#include <cstddef>
#include <vector>

#include "numeric/box.h"

namespace impulse::numeric {

/// Orthographic view: pixel (i, j) (row j from the top) has its centre at texture point
/// (x0 + (i + 0.5) * scale, y0 + (j + 0.5) * scale).
struct View {
    int width = 0;
    int height = 0;
    double x0 = 0.0, y0 = 0.0;
    double scale = 1.0;  ///< texture units per pixel, > 0
    /// Texture-space box covered by the pixels.
    Box box() const { return {x0, y0, x0 + width * scale, y0 + height * scale}; }
};

/// A single-channel float frame, row-major, top row first.
struct Frame {
    int width = 0, height = 0;
    std::vector<float> data;
    void resize(int w, int h) { width = w, height = h, data.assign(size_t(w) * h, 0.0f); }
    float at(int x, int y) const { return data[size_t(y) * width + x]; }
};

}  // namespace impulse::numeric
