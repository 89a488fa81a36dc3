// SPDX-License-Identifier: Apache-2.0
// Birth regions: shapes as signed distances, soft edges, sampled masks (Lewis 1986 §3.1:
// points "restricted to an area of the plane ... with conceptually simple algorithms", where
// restricting a noise field "requires scan converting the boundary of the region").

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "sim/sim.h"
#include "numeric/errors.h"

namespace impulse::sim {
namespace {

double hypot2(double x, double y) { return std::sqrt(x * x + y * y); }

/// Distance from (px, py) to the segment (ax, ay)-(bx, by).
double segment_distance(double px, double py, double ax, double ay, double bx, double by) {
    const double ex = bx - ax, ey = by - ay;
    const double len2 = ex * ex + ey * ey;
    const double t = len2 > 0 ? std::clamp(((px - ax) * ex + (py - ay) * ey) / len2, 0.0, 1.0) : 0.0;
    return hypot2(px - ax - t * ex, py - ay - t * ey);
}

/// Box of a turned rectangle of half-sizes (hx, hy).
Box turned_bounds(double cx, double cy, double hx, double hy, double angle) {
    const double c = std::abs(std::cos(angle)), s = std::abs(std::sin(angle));
    const double ex = c * hx + s * hy, ey = s * hx + c * hy;
    return {cx - ex, cy - ey, cx + ex, cy + ey};
}

class Circle final : public Shape {
public:
    Circle(double cx, double cy, double r) : m_cx(cx), m_cy(cy), m_r(r) {}
    double distance(double x, double y) const override { return hypot2(x - m_cx, y - m_cy) - m_r; }
    Box bounds() const override { return {m_cx - m_r, m_cy - m_r, m_cx + m_r, m_cy + m_r}; }

private:
    double m_cx, m_cy, m_r;
};

class RoundedBox final : public Shape {
public:
    RoundedBox(double cx, double cy, double hx, double hy, double angle, double corner)
        : m_cx(cx), m_cy(cy), m_hx(hx), m_hy(hy), m_cos(std::cos(angle)), m_sin(std::sin(angle)),
          m_corner(corner), m_bounds(turned_bounds(cx, cy, hx, hy, angle)) {}
    double distance(double x, double y) const override {
        // In the box's own frame, folded into the first quadrant; the inner rectangle shrunk by
        // the corner radius, then the distance to it minus the radius (a rounded rectangle is
        // the set of points within `corner` of the inner one).
        const double dx = x - m_cx, dy = y - m_cy;
        const double u = std::abs(m_cos * dx + m_sin * dy), v = std::abs(-m_sin * dx + m_cos * dy);
        const double qx = u - (m_hx - m_corner), qy = v - (m_hy - m_corner);
        return hypot2(std::max(qx, 0.0), std::max(qy, 0.0)) + std::min(std::max(qx, qy), 0.0) -
               m_corner;
    }
    Box bounds() const override { return m_bounds; }

private:
    double m_cx, m_cy, m_hx, m_hy, m_cos, m_sin, m_corner;
    Box m_bounds;
};

class Ellipse final : public Shape {
public:
    Ellipse(double cx, double cy, double a, double b, double angle)
        : m_cx(cx), m_cy(cy), m_a(a), m_b(b), m_cos(std::cos(angle)), m_sin(std::sin(angle)) {
        // The box of a turned ellipse: half-extents sqrt(a^2 cos^2 + b^2 sin^2) and the swap.
        const double ex = hypot2(a * m_cos, b * m_sin), ey = hypot2(a * m_sin, b * m_cos);
        m_bounds = {cx - ex, cy - ey, cx + ex, cy + ey};
    }
    double distance(double x, double y) const override {
        const double dx = x - m_cx, dy = y - m_cy;
        double u = std::abs(m_cos * dx + m_sin * dy), v = std::abs(-m_sin * dx + m_cos * dy);
        double e0 = m_a, e1 = m_b;
        if (e0 < e1) std::swap(e0, e1), std::swap(u, v);
        const double d = first_quadrant_distance(e0, e1, u, v);
        const double k = (u / e0) * (u / e0) + (v / e1) * (v / e1);
        return k < 1.0 ? -d : d;
    }
    Box bounds() const override { return m_bounds; }

private:
    /// Distance from (y0, y1) >= 0 to the ellipse of semi-axes e0 >= e1 > 0 (D. Eberly,
    /// "Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid", 2013: the
    /// closest point's parameter is the root of a monotone function, found by bisection).
    static double first_quadrant_distance(double e0, double e1, double y0, double y1) {
        if (y1 > 0) {
            if (y0 > 0) {
                const double z0 = y0 / e0, z1 = y1 / e1;
                double g = z0 * z0 + z1 * z1 - 1.0;
                if (g == 0) return 0.0;
                const double r0 = (e0 / e1) * (e0 / e1);
                const double n0 = r0 * z0;
                double s0 = z1 - 1.0, s1 = g < 0 ? 0.0 : hypot2(n0, z1) - 1.0, s = 0.0;
                for (int i = 0; i < 200; ++i) {
                    s = 0.5 * (s0 + s1);
                    if (s == s0 || s == s1) break;
                    const double q0 = n0 / (s + r0), q1 = z1 / (s + 1.0);
                    g = q0 * q0 + q1 * q1 - 1.0;
                    if (g > 0)
                        s0 = s;
                    else if (g < 0)
                        s1 = s;
                    else
                        break;
                }
                const double x0 = r0 * y0 / (s + r0), x1 = y1 / (s + 1.0);
                return hypot2(x0 - y0, x1 - y1);
            }
            return std::abs(y1 - e1);
        }
        const double numer0 = e0 * y0, denom0 = e0 * e0 - e1 * e1;
        if (numer0 < denom0) {
            const double xde0 = numer0 / denom0;
            const double x0 = e0 * xde0, x1 = e1 * std::sqrt(std::max(0.0, 1.0 - xde0 * xde0));
            return hypot2(x0 - y0, x1);
        }
        return std::abs(y0 - e0);
    }

    double m_cx, m_cy, m_a, m_b, m_cos, m_sin;
    Box m_bounds;
};

class Capsule final : public Shape {
public:
    Capsule(double ax, double ay, double bx, double by, double r)
        : m_ax(ax), m_ay(ay), m_bx(bx), m_by(by), m_r(r) {}
    double distance(double x, double y) const override {
        return segment_distance(x, y, m_ax, m_ay, m_bx, m_by) - m_r;
    }
    Box bounds() const override {
        return {std::min(m_ax, m_bx) - m_r, std::min(m_ay, m_by) - m_r,
                std::max(m_ax, m_bx) + m_r, std::max(m_ay, m_by) + m_r};
    }

private:
    double m_ax, m_ay, m_bx, m_by, m_r;
};

class Polygon final : public Shape {
public:
    Polygon(std::vector<std::array<double, 2>> p, FillRule rule) : m_p(std::move(p)), m_rule(rule) {
        m_bounds = {m_p[0][0], m_p[0][1], m_p[0][0], m_p[0][1]};
        for (const auto& q : m_p) {
            m_bounds.x0 = std::min(m_bounds.x0, q[0]), m_bounds.x1 = std::max(m_bounds.x1, q[0]);
            m_bounds.y0 = std::min(m_bounds.y0, q[1]), m_bounds.y1 = std::max(m_bounds.y1, q[1]);
        }
    }
    double distance(double x, double y) const override {
        // Nearest edge for |d|; the crossing count (even-odd) and winding number (nonzero) of
        // the edges against a ray towards +x for the sign (half-open in y, so a vertex on the
        // ray is counted once).
        double d = std::numeric_limits<double>::infinity();
        int crossings = 0, winding = 0;
        const size_t n = m_p.size();
        for (size_t i = 0, j = n - 1; i < n; j = i++) {
            const auto& a = m_p[j];
            const auto& b = m_p[i];
            d = std::min(d, segment_distance(x, y, a[0], a[1], b[0], b[1]));
            const bool up = a[1] <= y && b[1] > y, down = b[1] <= y && a[1] > y;
            if (!up && !down) continue;
            // Side of (x, y) against the edge a -> b: > 0 left of it.
            const double side = (b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1]);
            if (up && side > 0) ++crossings, ++winding;
            if (down && side < 0) ++crossings, --winding;
        }
        const bool inside = m_rule == FillRule::EvenOdd ? (crossings & 1) != 0 : winding != 0;
        return inside ? -d : d;
    }
    Box bounds() const override { return m_bounds; }

private:
    std::vector<std::array<double, 2>> m_p;
    FillRule m_rule;
    Box m_bounds;
};

class Combined final : public Shape {
public:
    Combined(ShapeOp op, std::vector<std::shared_ptr<const Shape>> parts)
        : m_op(op), m_parts(std::move(parts)) {
        m_bounds = m_parts[0]->bounds();
        for (size_t i = 1; i < m_parts.size() && op != ShapeOp::Subtract; ++i) {
            const Box b = m_parts[i]->bounds();
            if (op == ShapeOp::Union)
                m_bounds = {std::min(m_bounds.x0, b.x0), std::min(m_bounds.y0, b.y0),
                            std::max(m_bounds.x1, b.x1), std::max(m_bounds.y1, b.y1)};
            else  // an empty intersection keeps an inverted box: nothing passes the cull test
                m_bounds = {std::max(m_bounds.x0, b.x0), std::max(m_bounds.y0, b.y0),
                            std::min(m_bounds.x1, b.x1), std::min(m_bounds.y1, b.y1)};
        }
    }
    double distance(double x, double y) const override {
        double d = m_parts[0]->distance(x, y);
        for (size_t i = 1; i < m_parts.size(); ++i) {
            const double e = m_parts[i]->distance(x, y);
            switch (m_op) {
                case ShapeOp::Union: d = std::min(d, e); break;
                case ShapeOp::Intersection: d = std::max(d, e); break;
                case ShapeOp::Subtract: d = std::max(d, -e); break;
            }
        }
        return d;
    }
    Box bounds() const override { return m_bounds; }

private:
    ShapeOp m_op;
    std::vector<std::shared_ptr<const Shape>> m_parts;
    Box m_bounds;
};

class ShapeRegion final : public BirthRegion {
public:
    ShapeRegion(std::shared_ptr<const Shape> s, double feather, bool invert)
        : m_shape(std::move(s)), m_feather(feather), m_invert(invert) {}
    double acceptance(double x, double y) const override {
        const double d = m_shape->distance(x, y);
        double p;
        if (m_feather > 0) {
            const double t = std::clamp((d + 0.5 * m_feather) / m_feather, 0.0, 1.0);
            p = 1.0 - t * t * (3.0 - 2.0 * t);
        } else {
            p = d <= 0.0 ? 1.0 : 0.0;
        }
        return m_invert ? 1.0 - p : p;
    }
    std::optional<Box> support() const override {
        // Outside bounds() expanded by feather/2 the distance to the inside exceeds feather/2
        // (the combinations' min/max keep this: see Shape), so p = 0 there.
        if (m_invert) return std::nullopt;
        return m_shape->bounds().expanded(0.5 * m_feather);
    }

private:
    std::shared_ptr<const Shape> m_shape;
    double m_feather;
    bool m_invert;
};

class MaskRegion final : public BirthRegion {
public:
    MaskRegion(MaskGrid g, bool invert) : m_g(std::move(g)), m_invert(invert) {
        // Support: the box of the non-zero pixels plus one pixel (the bilinear reach), when the
        // border is all zero; a non-zero border pixel is held out to infinity (no support).
        const int w = m_g.width, h = m_g.height;
        int i0 = w, i1 = -1, j0 = h, j1 = -1;
        for (int j = 0; j < h; ++j)
            for (int i = 0; i < w; ++i)
                if (m_g.values[size_t(j) * w + i] > 0.0f)
                    i0 = std::min(i0, i), i1 = std::max(i1, i), j0 = std::min(j0, j),
                    j1 = std::max(j1, j);
        if (m_invert) return;
        if (i1 < 0) {  // all zero: nothing is born
            m_support = Box{m_g.origin_x, m_g.origin_y, m_g.origin_x, m_g.origin_y};
            return;
        }
        if (i0 == 0 || j0 == 0 || i1 == w - 1 || j1 == h - 1) return;
        const double s = m_g.spacing;
        m_support = Box{m_g.origin_x + (i0 - 0.5) * s, m_g.origin_y + (j0 - 0.5) * s,
                        m_g.origin_x + (i1 + 1.5) * s, m_g.origin_y + (j1 + 1.5) * s};
    }
    double acceptance(double x, double y) const override {
        const int w = m_g.width, h = m_g.height;
        const double fx = std::clamp((x - m_g.origin_x) / m_g.spacing - 0.5, 0.0, w - 1.0);
        const double fy = std::clamp((y - m_g.origin_y) / m_g.spacing - 0.5, 0.0, h - 1.0);
        const int i0 = std::min(static_cast<int>(fx), w - 1), j0 = std::min(static_cast<int>(fy), h - 1);
        const int i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
        const double ax = fx - i0, ay = fy - j0;
        const auto& v = m_g.values;
        const double a = v[size_t(j0) * w + i0], b = v[size_t(j0) * w + i1];
        const double c = v[size_t(j1) * w + i0], d = v[size_t(j1) * w + i1];
        const double p = std::clamp((1.0 - ay) * (a + ax * (b - a)) + ay * (c + ax * (d - c)), 0.0, 1.0);
        return m_invert ? 1.0 - p : p;
    }
    std::optional<Box> support() const override { return m_support; }

private:
    MaskGrid m_g;
    bool m_invert;
    std::optional<Box> m_support;
};

class Unsupported final : public BirthRegion {
public:
    explicit Unsupported(std::shared_ptr<const BirthRegion> r) : m_region(std::move(r)) {}
    double acceptance(double x, double y) const override { return m_region->acceptance(x, y); }
    std::optional<Box> support() const override { return std::nullopt; }

private:
    std::shared_ptr<const BirthRegion> m_region;
};

bool finite(std::initializer_list<double> v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

[[noreturn]] void invalid(const std::string& what) { throw ValueError(what); }

}  // namespace

std::shared_ptr<const Shape> make_circle_shape(double cx, double cy, double radius) {
    if (!finite({cx, cy, radius}) || !(radius > 0)) invalid("circle: expected a finite centre and radius > 0");
    return std::make_shared<Circle>(cx, cy, radius);
}

std::shared_ptr<const Shape> make_box_shape(double cx, double cy, double hx, double hy,
                                            double angle_rad, double corner) {
    if (!finite({cx, cy, hx, hy, angle_rad, corner}) || !(hx > 0) || !(hy > 0))
        invalid("box: expected a finite centre and half-sizes > 0");
    if (!(corner >= 0) || corner > std::min(hx, hy))
        invalid("box: expected a corner radius in [0, half the smaller side]");
    return std::make_shared<RoundedBox>(cx, cy, hx, hy, angle_rad, corner);
}

std::shared_ptr<const Shape> make_ellipse_shape(double cx, double cy, double a, double b,
                                                double angle_rad) {
    if (!finite({cx, cy, a, b, angle_rad}) || !(a > 0) || !(b > 0))
        invalid("ellipse: expected a finite centre and semi-axes > 0");
    return std::make_shared<Ellipse>(cx, cy, a, b, angle_rad);
}

std::shared_ptr<const Shape> make_capsule_shape(double ax, double ay, double bx, double by,
                                                double radius) {
    if (!finite({ax, ay, bx, by, radius}) || !(radius > 0))
        invalid("capsule: expected finite end points and radius > 0");
    return std::make_shared<Capsule>(ax, ay, bx, by, radius);
}

std::shared_ptr<const Shape> make_polygon_shape(std::vector<std::array<double, 2>> points,
                                                FillRule rule) {
    if (points.size() < 3) invalid("polygon: expected at least 3 points");
    for (const auto& p : points)
        if (!finite({p[0], p[1]})) invalid("polygon: expected finite points");
    // Degenerate when every point lies on one line (no area whatever the fill rule): the
    // largest distance from the line through p0 and the point farthest from it, relative to
    // that length.
    const auto& p0 = points[0];
    size_t far = 0;
    double far2 = 0.0;
    for (size_t i = 1; i < points.size(); ++i) {
        const double d2 = std::pow(points[i][0] - p0[0], 2) + std::pow(points[i][1] - p0[1], 2);
        if (d2 > far2) far2 = d2, far = i;
    }
    double off = 0.0;
    if (far2 > 0) {
        const double ex = points[far][0] - p0[0], ey = points[far][1] - p0[1];
        for (const auto& p : points)
            off = std::max(off, std::abs(ex * (p[1] - p0[1]) - ey * (p[0] - p0[0])) / std::sqrt(far2));
    }
    if (!(off > 1e-9 * std::sqrt(far2)))
        invalid("polygon: its points lie on one line (no area)");
    return std::make_shared<Polygon>(std::move(points), rule);
}

std::shared_ptr<const Shape> make_combined_shape(ShapeOp op,
                                                 std::vector<std::shared_ptr<const Shape>> parts) {
    if (parts.empty()) invalid("combined shape: expected at least one part");
    for (const auto& p : parts)
        if (!p) invalid("combined shape: a part is null");
    return std::make_shared<Combined>(op, std::move(parts));
}

std::shared_ptr<const BirthRegion> make_shape_region(std::shared_ptr<const Shape> shape,
                                                     double feather, bool invert) {
    if (!shape) invalid("region: no shape");
    if (!std::isfinite(feather) || feather < 0) invalid("region: expected a feather >= 0");
    return std::make_shared<ShapeRegion>(std::move(shape), feather, invert);
}

std::shared_ptr<const BirthRegion> make_mask_region(MaskGrid grid, bool invert) {
    if (grid.width < 1 || grid.height < 1 ||
        grid.values.size() != size_t(grid.width) * grid.height || !(grid.spacing > 0) ||
        !finite({grid.origin_x, grid.origin_y, grid.spacing}))
        invalid("mask: expected width, height >= 1, width * height values and spacing > 0");
    for (size_t i = 0; i < grid.values.size(); ++i) {
        const float v = grid.values[i];
        if (!(v >= 0.0f && v <= 1.0f)) {
            std::ostringstream s;
            s << "mask: expected values in [0, 1], found " << v << " at pixel ("
              << i % grid.width << ", " << i / grid.width << ")";
            invalid(s.str());
        }
    }
    return std::make_shared<MaskRegion>(std::move(grid), invert);
}

std::shared_ptr<const BirthRegion> without_support(std::shared_ptr<const BirthRegion> region) {
    if (!region) invalid("region: null");
    return std::make_shared<Unsupported>(std::move(region));
}

}  // namespace impulse::sim
