// SPDX-License-Identifier: Apache-2.0
#include "numeric/box.h"

#include <algorithm>

namespace impulse::numeric {

Box Region::bounds() const {
    Box r{1e300, 1e300, -1e300, -1e300};
    for (const Box& b : boxes) {
        if (b.empty()) continue;
        r.x0 = std::min(r.x0, b.x0), r.y0 = std::min(r.y0, b.y0);
        r.x1 = std::max(r.x1, b.x1), r.y1 = std::max(r.y1, b.y1);
    }
    return r.empty() ? Box{0, 0, -1, -1} : r;
}

double Region::area() const {
    double a = 0.0;
    for (const Box& b : boxes)
        if (!b.empty()) a += b.area();
    return a;
}

bool Region::empty() const {
    return std::all_of(boxes.begin(), boxes.end(), [](const Box& b) { return b.empty(); });
}

Region Region::expanded(double margin) const {
    Region r;
    r.boxes.reserve(boxes.size());
    for (const Box& b : boxes)
        if (!b.empty()) r.boxes.push_back(b.expanded(margin));
    return r;
}

}  // namespace impulse::numeric
