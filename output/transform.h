// SPDX-License-Identifier: Apache-2.0
#pragma once
// Field transforms: procedural transforms of the homogeneous noise field into structured
// textures, marble and wood (Lewis 1989 §5.1 "a procedural transform of a homogeneous
// texture"), applied to the float field before shading. Part of impulse::output; included by
// output/output.h.

#include <cstdint>
#include <vector>

#include "numeric/frame.h"

namespace impulse::output {

using numeric::Frame;
using numeric::View;
struct ValueMapping;

/// What the transform does to the field f at texture point p. z = (f - mean) / sd is the field
/// in standard deviations (the closed-form mean and sd of the scene), so `turbulence` means the
/// same at any density, gain or kernel.
///  * marble (Perlin 1985, Lewis 1989 §5.1): v = sin(2 pi frequency u + phase + turbulence z),
///    u = p . (cos angle, sin angle): stripes across `angle`, their phase perturbed by the
///    noise; v in [-1, 1].
///  * wood (Lewis 1989 §5.1, wood = xtab[sqrt(x^2 + y^2) + eta]): v = xtab(frac(D(r) +
///    turbulence z)), r = |p - center| the distance from the trunk's axis, D(r) the ring count
///    at r: r / ring_width, or with `growth` > 0 a random monotonic function of r ("radial
///    regions of densely or sparsely separated rings"): ring k is ring_width (1 + growth
///    (2 u_k - 1)) wide, u_k uniform from (seed, k). xtab is the ring's cross-section,
///    xtab(s) = 1 - s^a (1 - s) / m with a = sharpness and m = a^a / (a + 1)^(a + 1) its
///    maximum: light early wood darkening slowly to the latewood at s = a / (a + 1), then
///    back to light within the ring's last 1 / (a + 1); v in [0, 1].
struct FieldTransform {
    enum class Type { None, Marble, Wood };
    Type type = Type::None;
    double turbulence = 1.0;  ///< marble: radians per sd of the field; wood: rings per sd; >= 0
    // marble
    double angle_rad = 0.0;         ///< direction along which the stripes' phase advances
    double frequency = 1.0 / 64.0;  ///< cycles per texture unit along `angle_rad`, >= 0
    double phase = 0.0;             ///< radians
    // wood
    double center_x = 0.0, center_y = 0.0;  ///< the trunk's axis (texture units)
    double ring_width = 16.0;  ///< mean ring width, texture units, > 0
    double growth = 0.0;       ///< ring width irregularity in [0, 1); 0: periodic rings
    double sharpness = 6.0;    ///< xtab exponent a >= 1: larger, a thinner latewood band
    uint64_t seed = 1;         ///< ring widths when growth > 0
};

/// The range of the transformed values ([-1, 1] marble, [0, 1] wood), for the display mapping.
/// Type None: {0, 0} (no transform; the caller keeps its own mapping).
ValueMapping transform_range(const FieldTransform& transform);

/// xtab(s) of the wood transform for s in [0, 1) (exposed for tests).
double wood_profile(double s, double sharpness);

/// The transform at one point for callers with their own geometry (solid textures on 3-D meshes,
/// mesh/solid_texture.h): marble(u, z) = sin(2 pi frequency u + phase + turbulence z) with u the
/// coordinate along the stripes' direction; wood(r, z) = xtab(frac(D(r) + turbulence z)) with r
/// the distance from the trunk's axis (the 2-D geometry fields of FieldTransform are unused).
/// `r_max` bounds the distances wood is asked about (the ring table with growth > 0 reaches it;
/// farther distances use the last ring's width). apply_transform goes through the same code, so
/// a pixel and a point with the same (u or r, z) get the same bits. Immutable, thread-safe.
class PointTransform {
public:
    /// Throws ValueError as apply_transform (rings over 1e7 out to r_max).
    PointTransform(const FieldTransform& transform, double r_max);
    /// Marble: u along the stripes' direction; wood: r >= 0 from the axis. z in sd.
    double operator()(double u_or_r, double z) const {
        return m_t.type == FieldTransform::Type::Marble ? marble(u_or_r, z) : wood(u_or_r, z);
    }
    double marble(double u, double z) const;
    double wood(double r, double z) const;
    /// xtab(frac(D(r) + shift)), the shift in rings (wood(r, z) = wood_shifted(r, turbulence z)).
    double wood_shifted(double r, double shift) const;
    /// D(r): rings crossed from the axis out to r (r / ring_width when growth = 0).
    double rings(double r) const;

private:
    FieldTransform m_t;
    std::vector<double> m_radii;  ///< ring boundaries when growth > 0
    double m_inv_width = 1.0, m_inv_peak = 1.0;
};

/// Replaces every pixel's value f of `field` by the transform at the pixel's centre in texture
/// space under the orthographic `view` (same size as the field), with z = (f - mean) / sd,
/// sd > 0. Pure per-pixel work, deterministic for any thread count. Throws ValueError when wood
/// rings with growth > 0 would number over 1e7 out to the view's far corner.
void apply_transform(const FieldTransform& transform, const View& view, double mean, double sd,
                     Frame& field);

}  // namespace impulse::output
