// SPDX-License-Identifier: Apache-2.0
// Regions as unions of boxes: which seeding cells they meet, and point membership.

#include <algorithm>
#include <cmath>

#include "sim/sim.h"
#include "sim/layout.h"

namespace impulse::sim {
namespace detail {

CellCover cell_cover(const Region& region, const Layout& L) {
    CellCover c;
    const Box all = region.bounds();
    if (all.empty()) return c;
    c.cy0 = static_cast<int64_t>(std::floor(all.y0 / L.cell_y));
    c.cy1 = static_cast<int64_t>(std::floor(all.y1 / L.cell_y));
    c.rows.resize(static_cast<size_t>(c.cy1 - c.cy0 + 1));
    for (const Box& b : region.boxes) {
        if (b.empty()) continue;
        const int64_t cx0 = static_cast<int64_t>(std::floor(b.x0 / L.cell_x));
        const int64_t cx1 = static_cast<int64_t>(std::floor(b.x1 / L.cell_x));
        const int64_t cy0 = static_cast<int64_t>(std::floor(b.y0 / L.cell_y));
        const int64_t cy1 = static_cast<int64_t>(std::floor(b.y1 / L.cell_y));
        for (int64_t cy = cy0; cy <= cy1; ++cy) c.rows[size_t(cy - c.cy0)].emplace_back(cx0, cx1);
    }
    for (auto& row : c.rows) {
        if (row.size() < 2) continue;
        std::sort(row.begin(), row.end());
        size_t out = 0;
        for (size_t i = 1; i < row.size(); ++i) {
            if (row[i].first <= row[out].second + 1)
                row[out].second = std::max(row[out].second, row[i].second);
            else
                row[++out] = row[i];
        }
        row.resize(out + 1);
    }
    return c;
}

BoxIndex::BoxIndex(const Region& region) {
    for (const Box& b : region.boxes)
        if (!b.empty()) m_boxes.push_back(b);
    if (m_boxes.empty()) {
        m_bands.resize(1);
        return;
    }
    const Box all = region.bounds();
    m_y0 = all.y0, m_y1 = all.y1;
    // About one band per box: a point is tested against the few boxes overlapping its band.
    const size_t n = std::clamp<size_t>(m_boxes.size(), 1, 4096);
    const double h = (m_y1 - m_y0) / static_cast<double>(n);
    m_inv_band = h > 0.0 ? 1.0 / h : 0.0;
    m_bands.resize(n);
    for (uint32_t i = 0; i < m_boxes.size(); ++i) {
        const Box& b = m_boxes[i];
        const size_t a = std::min(n - 1, static_cast<size_t>((b.y0 - m_y0) * m_inv_band));
        const size_t z = std::min(n - 1, static_cast<size_t>((b.y1 - m_y0) * m_inv_band));
        for (size_t k = a; k <= z; ++k) m_bands[k].push_back(i);
    }
}

}  // namespace detail
}  // namespace impulse::sim
