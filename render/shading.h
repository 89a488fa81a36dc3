// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shading: from a float field to display RGB — colour ramps, height-field lighting (Lewis's
// figures shade noise "as an obliquely illuminated height field"), and alpha over a sky
// gradient. Part of impulse::render; included by render/render.h.

#include <vector>

namespace impulse::render {

struct Frame;
struct ValueMapping;

/// One stop of a colour ramp: at display value t (0..1 after the value mapping) the colour
/// (r, g, b) and opacity a, all in [0, 1]; linear interpolation between stops.
struct ColorStop {
    double t = 0.0;
    float r = 0, g = 0, b = 0, a = 1;
};

struct Shading {
    /// Empty: grey (r = g = b = display value, opaque).
    std::vector<ColorStop> ramp;
    /// Height-field lighting: the field is a height map scaled by `relief` (height units per
    /// field unit per pixel); 0 disables. Lambert with `ambient`, light from azimuth/elevation.
    double relief = 0.0;
    double light_azimuth_deg = 135.0;   ///< direction the light comes from, in the image plane
    double light_elevation_deg = 35.0;  ///< above the plane
    double ambient = 0.25;
    /// Background behind transparent parts (ramp alpha < 1): a vertical gradient.
    float top[3] = {0.25f, 0.45f, 0.85f};
    float bottom[3] = {0.70f, 0.82f, 0.95f};
};

/// Display RGB (3 floats per pixel in [0, 1]) of `field` under `mapping` and `shading`.
/// Deterministic; per-pixel work only (parallel over rows).
void shade(const Frame& field, const ValueMapping& mapping, const Shading& shading,
           std::vector<float>& rgb);

}  // namespace impulse::render
