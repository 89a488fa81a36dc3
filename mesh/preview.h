// SPDX-License-Identifier: Apache-2.0
#pragma once
// A look at a mesh without Blender (part of impulse::mesh): an orthographic software render,
// z up, seen from an azimuth and elevation, polygons lit by one directional light (Lambert,
// two-sided) in their vertex colours (light grey without), line segments drawn in their colours
// (dark blue without), 2x2 supersampled. For the gallery and quick checks, not for production.

#include <vector>

#include "mesh/mesh_io.h"

namespace impulse::mesh {

struct PreviewView {
    int width = 512, height = 512;  ///< pixels, in [16, 8192]
    double azimuth_deg = 35.0;      ///< camera direction round z, from +x towards +y
    double elevation_deg = 25.0;    ///< above the xy plane
    float background[3] = {0.93f, 0.93f, 0.91f};
};

/// RGB floats in [0, 1], rows from the top. The mesh fills the picture (5 % margin).
std::vector<float> render_preview(const Mesh& mesh, const PreviewView& view);

}  // namespace impulse::mesh
