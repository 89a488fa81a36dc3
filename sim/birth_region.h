// SPDX-License-Identifier: Apache-2.0
#pragma once
// Birth regions: shapes and masks that thin births by position (sim/region.cpp). Part of
// impulse::sim (sim/sim.h).

#include <array>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "numeric/box.h"

namespace impulse::sim {

using numeric::Box;

/// A planar shape as a signed distance d(x, y): negative inside, positive outside, zero on the
/// boundary. Exact (|d| is the Euclidean distance to the boundary) for the primitives; the
/// combinations take min / max of their parts, which is exact outside a union and a lower bound
/// of the distance otherwise (exact at the boundary itself). Deterministic and thread-safe.
class Shape {
public:
    virtual ~Shape() = default;
    virtual double distance(double x, double y) const = 0;
    /// The axis-aligned box holding the inside (d <= 0).
    virtual Box bounds() const = 0;
};
/// Disc of `radius` > 0 round (cx, cy).
std::shared_ptr<const Shape> make_circle_shape(double cx, double cy, double radius);
/// Rectangle of half-sizes (hx, hy) > 0 centred on (cx, cy), turned by `angle_rad`
/// counter-clockwise, with corners rounded to `corner` in [0, min(hx, hy)] (0: sharp).
std::shared_ptr<const Shape> make_box_shape(double cx, double cy, double hx, double hy,
                                            double angle_rad, double corner);
/// Ellipse of semi-axes (a, b) > 0 centred on (cx, cy), the a axis turned by `angle_rad`. The
/// distance is the exact one (closest point found by bisection, Eberly 2013).
std::shared_ptr<const Shape> make_ellipse_shape(double cx, double cy, double a, double b,
                                                double angle_rad);
/// Capsule: the points within `radius` > 0 of the segment (ax, ay)-(bx, by) (a disc if a = b).
std::shared_ptr<const Shape> make_capsule_shape(double ax, double ay, double bx, double by,
                                                double radius);
/// Which points a self-intersecting polygon holds: even-odd (a point is inside when a ray from
/// it crosses the boundary an odd number of times) or nonzero (when the boundary winds round it
/// a nonzero number of times: overlapping loops are filled). Equal for simple polygons.
enum class FillRule { EvenOdd, NonZero };
inline constexpr std::array<std::string_view, 2> kFillRuleNames = {"evenodd", "nonzero"};
/// Closed polygon through `points` (>= 3, not all on one line; the last joins the first).
/// Throws ValueError for a degenerate polygon.
std::shared_ptr<const Shape> make_polygon_shape(std::vector<std::array<double, 2>> points,
                                                FillRule rule);
/// Union (min), intersection (max) or the first part minus all the others (max(d0, -d1, ...)).
enum class ShapeOp { Union, Intersection, Subtract };
inline constexpr std::array<std::string_view, 3> kShapeOpNames = {"union", "intersection",
                                                                  "subtract"};
std::shared_ptr<const Shape> make_combined_shape(ShapeOp op,
                                                 std::vector<std::shared_ptr<const Shape>> parts);

/// Where a layer's impulses may be born (Lewis 1986 §3.1: points "restricted to an area of the
/// plane"): an acceptance probability p(x, y) in [0, 1] at the birth position. The simulator
/// thins births with it (a birth is kept iff a uniform drawn from its identity is <= p), so the
/// kept impulses are a Poisson process of intensity lambda p(x) and, where p varies slowly on
/// the kernel's scale, the field's local variance is p(x) times the layer's. Deterministic and
/// thread-safe.
class BirthRegion {
public:
    virtual ~BirthRegion() = default;
    /// p(x, y) in [0, 1].
    virtual double acceptance(double x, double y) const = 0;
    /// A box outside which p = 0, or nullopt when p may be positive anywhere (an inverted
    /// region); the simulator does not generate seeding cells outside it.
    virtual std::optional<Box> support() const = 0;
};
/// A shape with a soft edge: p = 1 - smoothstep((d + feather/2) / feather), so p falls from 1
/// at d = -feather/2 to 0 at d = feather/2 (1/2 on the boundary); feather = 0 is a hard edge
/// (p = 1 for d <= 0). `invert`: 1 - p (births outside the shape).
std::shared_ptr<const BirthRegion> make_shape_region(std::shared_ptr<const Shape> shape,
                                                     double feather, bool invert);
/// A sampled mask: grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing
/// (as OrientationGrid); p is the bilinear interpolation of the values, which must lie in
/// [0, 1], held at the edges (clamped coordinates). `invert`: 1 - p.
struct MaskGrid {
    int width = 0, height = 0;
    std::vector<float> values;  ///< width * height, row-major, in [0, 1]
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or values outside [0, 1].
std::shared_ptr<const BirthRegion> make_mask_region(MaskGrid grid, bool invert);
/// The same acceptance as `region` without a support: the simulator then generates every
/// seeding cell and thins each birth — the reference path for the culling (same impulses, bit
/// for bit; tests and benchmarks compare the two).
std::shared_ptr<const BirthRegion> without_support(std::shared_ptr<const BirthRegion> region);

}  // namespace impulse::sim
