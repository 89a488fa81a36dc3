// SPDX-License-Identifier: Apache-2.0
#pragma once
// Texture-space boxes and regions (unions of boxes): views, birth regions and budgets.

#include <vector>

namespace impulse::numeric {

/// Axis-aligned box in texture space.
struct Box {
    double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    Box expanded(double m) const { return {x0 - m, y0 - m, x1 + m, y1 + m}; }
    double area() const { return (x1 - x0) * (y1 - y0); }
    /// True when x1 < x0 or y1 < y0 (or a bound is NaN).
    bool empty() const { return !(x1 >= x0 && y1 >= y0); }
};

/// A texture-space region: the union of boxes (empty boxes, x1 < x0 or y1 < y0, are ignored).
/// The part of the plane a perspective camera sees is a wedge whose bounding box is about twice
/// its area; a union of row boxes follows it.
struct Region {
    std::vector<Box> boxes;
    Region() = default;
    Region(const Box& box) : boxes{box} {}  // NOLINT: a box is a region
    /// Bounding box of the non-empty boxes ({0, 0, -1, -1} when there are none).
    Box bounds() const;
    /// Sum of the non-empty boxes' areas (at least the union's: a budget estimate).
    double area() const;
    bool empty() const;
    Region expanded(double margin) const;
};

}  // namespace impulse::numeric
