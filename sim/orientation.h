// SPDX-License-Identifier: Apache-2.0
#pragma once
// Orientation fields: a kernel rotation theta(x, t) set by the scene (sim/orientation.cpp). Part of
// impulse::sim (sim/sim.h).

#include <array>
#include <memory>
#include <vector>

#include "numeric/keyframed.h"

namespace impulse::sim {

using numeric::Keyframed;

/// A direction field theta(x, t) in radians, counter-clockwise from +x, that rotates each
/// impulse's kernel; evaluated at the particle's current position at the frame time ("wind-blown
/// clouds or terrain ridges ... emulated by rotating the kernel as a function of position",
/// Lewis 1986 §3.1). Deterministic and thread-safe.
class OrientationField {
public:
    virtual ~OrientationField() = default;
    /// theta at the n points (x[i], y[i]) at time t_s, into theta[i].
    virtual void angles(double t_s, size_t n, const double* x, const double* y,
                        float* theta) const = 0;
};
/// theta = angle(t) everywhere.
std::shared_ptr<OrientationField> make_constant_orientation(Keyframed angle_rad);
/// theta = atan2(y - cy, x - cx): kernels point away from the centre (0 at the centre itself).
std::shared_ptr<OrientationField> make_radial_orientation(Keyframed cx, Keyframed cy);
/// The radial angle + pi/2 (counter-clockwise around the centre), or - pi/2 when `clockwise`.
std::shared_ptr<OrientationField> make_circular_orientation(Keyframed cx, Keyframed cy,
                                                            bool clockwise);
/// Tangent of a polyline (>= 2 points, consecutive points distinct): the direction of the
/// nearest segment; with `smooth` > 0 (texture units) the segment directions are averaged as
/// doubled-angle vectors with weights exp(-(d_i^2 - d_min^2) / (2 smooth^2)), d_i the distance
/// to segment i, so the field turns smoothly at the vertices. `smooth` may vary in time.
std::shared_ptr<OrientationField> make_polyline_orientation(std::vector<std::array<double, 2>> points,
                                                            Keyframed smooth);
/// Tangent of a family of sine curves. In coordinates (u, w) along direction `angle_rad`
/// through `origin` (u = (p - origin) . (cos angle, sin angle)), the curve is
/// w = amplitude sin(2 pi u / wavelength + phase) and every point takes the tangent of the copy
/// through it (shifted across): theta = angle + atan(2 pi amplitude / wavelength
/// cos(2 pi u / wavelength + phase)). wavelength > 0 at every key; amplitude, wavelength, phase
/// and angle may vary in time.
std::shared_ptr<OrientationField> make_sine_orientation(Keyframed amplitude, Keyframed wavelength,
                                                        Keyframed phase, Keyframed angle_rad,
                                                        double origin_x, double origin_y);
/// A sampled field: channels = 1, an angle in radians; channels = 2, a direction (x, y).
/// Interpolated bilinearly as unit vectors (angles) or as vectors (directions), clamped at the
/// edges; grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing.
struct OrientationGrid {
    int width = 0, height = 0, channels = 1;
    std::vector<float> values;  ///< width * height * channels, row-major, interleaved
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or a value that is not finite (naming its pixel).
std::shared_ptr<OrientationField> make_grid_orientation(OrientationGrid grid);

}  // namespace impulse::sim
