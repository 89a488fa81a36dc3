// SPDX-License-Identifier: Apache-2.0
#pragma once
// A ray-marched preview of a density grid (part of impulse::volume): so a user sees a cloud
// volume without Blender.

#include <array>
#include <vector>

#include "volume/cloud.h"

namespace impulse::volume {

/// Light, camera and medium of the preview. Directions need not be unit length.
struct MarchOptions {
    int width = 640, height = 360;               ///< pixels
    std::array<double, 3> sun = {-0.4, -0.5, 0.75};  ///< direction towards the light
    std::array<double, 3> sun_color = {3.0, 2.85, 2.6};  ///< radiance, linear
    std::array<double, 3> sky_zenith = {0.30, 0.48, 0.80};   ///< background at the top
    std::array<double, 3> sky_horizon = {0.72, 0.82, 0.93};  ///< background at the horizon
    double extinction = 0.08;   ///< sigma_t per unit density per voxel (Beer–Lambert)
    double albedo = 0.95;       ///< sigma_s / sigma_t
    double anisotropy = 0.3;    ///< Henyey–Greenstein g, in (-1, 1)
    double ambient = 0.35;      ///< sky light scattered in, relative to the sun
    double exposure = 1.0;
    /// Camera: eye and target in voxel units, vertical field of view in degrees. eye == target
    /// (the default): a view from the front (-y), a little below the middle, framing the grid.
    std::array<double, 3> eye = {0, 0, 0}, target = {0, 0, 0};
    double fov_deg = 40.0;
    double step = 1.0;          ///< march step along camera rays, voxels, > 0
};

/// Renders `grid` (z up) into display RGB in [0, 1], 3 floats per pixel, rows top to bottom:
/// Beer–Lambert absorption along each ray, single scattering of the sun (Henyey–Greenstein
/// phase) with its transmittance from a light-transmittance grid marched once per frame
/// (shadow rays at half resolution), plus an ambient sky term, over a sky gradient; sRGB-encoded.
/// Deterministic for any thread count (each pixel is one task's).
std::vector<float> march(const DensityGrid& grid, const MarchOptions& options);

}  // namespace impulse::volume
