// SPDX-License-Identifier: Apache-2.0
#pragma once
// Solid texturing (Lewis 1989 §5.1; docs/mesh.md): wood and marble evaluated at points of 3-D
// space, so a mesh coloured at its vertices looks carved from a block: the pattern runs on across
// faces and edges. Part of impulse::mesh.
//   wood:   v = xtab[D(r) + k eta(p) / sigma], r the distance of p from the trunk's axis, D the
//           ring count (rings of irregular width with growth > 0), xtab the ring's profile;
//   marble: v = sin(2 pi f u + phase + k eta(p) / sigma), u = (p - origin) . direction;
// eta the solid noise, sigma its closed-form standard deviation (so k is per sd). The profiles
// are output::PointTransform's, the same as the 2-D wood and marble scenes.

#include <Eigen/Core>
#include <vector>

#include "mesh/mesh_io.h"
#include "output/shading.h"
#include "output/transform.h"
#include "synth/solid.h"

namespace impulse::mesh {

struct SolidTexture {
    synth::SolidParams noise;           ///< eta: kernel radius in the mesh's units, 3-D
    /// Marble or Wood and their profile numbers (turbulence, frequency, phase, ring_width,
    /// growth, sharpness, seed); centre_x/_y and angle are replaced by origin and direction.
    output::FieldTransform transform;
    Eigen::Vector3d origin{0, 0, 0};     ///< wood: a point of the axis; marble: phase origin
    Eigen::Vector3d direction{0, 0, 1};  ///< wood: the axis; marble: across the stripes (unit)
    std::vector<output::ColorStop> ramp; ///< colour of (v - lo) / (hi - lo); empty: grey
};

/// Throws ValueError naming the field: type None, a zero direction, turbulence < 0, wood's
/// ring_width <= 0, growth outside [0, 1), sharpness < 1; the noise's own checks.
void validate(const SolidTexture& texture);

/// v at every point (wood in [0, 1], marble in [-1, 1]); bit-identical for any order of the
/// points or thread count (each value a function of its point only).
std::vector<float> solid_texture_values(const SolidTexture& texture,
                                        const std::vector<synth::SolidPoint>& points);
/// The ramp's colour of each value (output::Shader over transform_range).
std::vector<Vec3> solid_texture_colors(const SolidTexture& texture, const std::vector<float>& values);
/// Colours every vertex of `mesh` (mesh.colors).
void texture_mesh(const SolidTexture& texture, Mesh& mesh);

/// A planar section for a quick look: the plane x[axis] = value (axis 0, 1, 2), rows and
/// columns along the other two axes in increasing order (rows from the top: the second axis
/// decreasing), covering [lo, hi] of those axes, `width` x `height` pixels. RGB floats.
struct Section {
    int axis = 2;
    double value = 0.0;
    Eigen::Vector2d lo{-1, -1}, hi{1, 1};
    int width = 512, height = 512;
};
std::vector<float> solid_texture_section(const SolidTexture& texture, const Section& section);

}  // namespace impulse::mesh
