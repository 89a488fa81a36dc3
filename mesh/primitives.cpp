// SPDX-License-Identifier: Apache-2.0
// An icosphere: the icosahedron's triangles split, midpoints shared and pushed onto the sphere.

#include <cmath>
#include <map>
#include <utility>

#include "mesh/mesh.h"
#include "numeric/errors.h"

namespace impulse::mesh {

Mesh icosphere(int levels) {
    if (levels < 0 || levels > 9) throw ValueError("levels = " + std::to_string(levels) + ": expected in [0, 9]");
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    Mesh m;
    for (const auto& p : {Vec3(-1, t, 0), Vec3(1, t, 0), Vec3(-1, -t, 0), Vec3(1, -t, 0),
                          Vec3(0, -1, t), Vec3(0, 1, t), Vec3(0, -1, -t), Vec3(0, 1, -t),
                          Vec3(t, 0, -1), Vec3(t, 0, 1), Vec3(-t, 0, -1), Vec3(-t, 0, 1)})
        m.positions.push_back(p.normalized());
    std::vector<uint32_t> tri = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
                                 11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8,
                                 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::minmax(a, b);
            if (const auto it = mid.find(key); it != mid.end()) return it->second;
            m.positions.push_back((m.positions[a] + m.positions[b]).normalized());
            return mid[key] = uint32_t(m.positions.size() - 1);
        };
        std::vector<uint32_t> next;
        for (size_t f = 0; f < tri.size(); f += 3) {
            const uint32_t a = tri[f], b = tri[f + 1], c = tri[f + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        tri = std::move(next);
    }
    m.indices = tri;
    m.face_sizes.assign(tri.size() / 3, 3);
    return m;
}

}  // namespace impulse::mesh
