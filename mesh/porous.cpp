// SPDX-License-Identifier: Apache-2.0
// Porous objects: noise times an envelope, meshed by OpenVDB (Lewis 1989 §5.2).

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mesh/mesh.h"
#include "numeric/errors.h"

namespace impulse::mesh {
namespace {

/// The grid's margin: samples outside [-1, 1] on each side, where e = 0.
constexpr int kMargin = 2;

double smoothstep(double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

void check(const PorousParams& p) {
    if (p.size < 8 || p.size > 1024)
        throw ValueError("size = " + std::to_string(p.size) + ": expected samples across the object in [8, 1024]");
    if (!(p.falloff > 0 && p.falloff <= 1))
        throw ValueError("falloff = " + std::to_string(p.falloff) + ": expected in (0, 1]");
    if (p.noise.dims != 3) throw ValueError("dims = " + std::to_string(p.noise.dims) + ": expected 3");
}

/// F = iso as OpenVDB wants it: -F, so the object {F > T} is the "inside" {-F < -T} of a level
/// set and the faces turn outwards.
openvdb::FloatGrid::Ptr negated_grid(const PorousField& f) {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(0.0f);
    auto transform = openvdb::math::Transform::createLinearTransform(f.spacing);
    transform->postTranslate(openvdb::Vec3d(f.origin, f.origin, f.origin));
    grid->setTransform(transform);
    auto acc = grid->getAccessor();
    for (int k = 0; k < f.n; ++k)
        for (int j = 0; j < f.n; ++j)
            for (int i = 0; i < f.n; ++i) {
                const float v = f.values[(size_t(k) * f.n + j) * f.n + i];
                if (v != 0.0f) acc.setValue({i, j, k}, -v);
            }
    return grid;
}

}  // namespace

Envelope parse_envelope(const std::string& name) {
    if (name == "sphere") return Envelope::Sphere;
    if (name == "box") return Envelope::Box;
    throw ValueError("envelope = \"" + name + "\": expected one of sphere, box");
}

double envelope(Envelope shape, double falloff, double x, double y, double z) {
    // d: 1 on the envelope's surface, < 1 inside (Euclidean for the sphere, Chebyshev for the box).
    const double d = shape == Envelope::Sphere
                         ? std::sqrt(x * x + y * y + z * z)
                         : std::max({std::abs(x), std::abs(y), std::abs(z)});
    return smoothstep((1.0 - d) / falloff);
}

PorousField porous_field(const PorousParams& p) {
    check(p);
    const synth::SolidNoise noise(p.noise);
    PorousField f;
    f.spacing = 2.0 / (p.size - 1);
    f.n = p.size + 2 * kMargin;
    f.origin = -1.0 - kMargin * f.spacing;
    f.values = noise.grid(f.n, f.n, f.n, {f.origin, f.origin, f.origin, 0.0}, f.spacing);
    const double inv_sigma = 1.0 / std::sqrt(noise.theory().variance);
    for (int k = 0; k < f.n; ++k)
        for (int j = 0; j < f.n; ++j)
            for (int i = 0; i < f.n; ++i) {
                float& v = f.values[(size_t(k) * f.n + j) * f.n + i];
                const double e = envelope(p.envelope, p.falloff, f.origin + i * f.spacing,
                                          f.origin + j * f.spacing, f.origin + k * f.spacing);
                v = static_cast<float>(e * v * inv_sigma);  // L89 §5.2: noise times the density
            }
    const auto [lo, hi] = std::minmax_element(f.values.begin(), f.values.end());
    f.min = *lo, f.max = *hi;
    return f;
}

Mesh porous_mesh(const PorousField& f, double iso) {
    if (!(iso > f.min && iso < f.max) || iso == 0.0) {
        std::ostringstream s;
        s << "iso = " << iso << ": " << (iso == 0.0 ? "F is 0 all round the object; " : "outside ")
          << "the field's range [" << f.min << ", " << f.max << "] on this grid (expected a nonzero value inside it)";
        throw ValueError(s.str());
    }
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*negated_grid(f), points, triangles, quads, -iso, 0.0);
    Mesh m;
    m.positions.reserve(points.size());
    for (const auto& p : points) m.positions.emplace_back(p.x(), p.y(), p.z());
    for (const auto& q : quads) m.add_face({q[0], q[1], q[2], q[3]});
    for (const auto& t : triangles) m.add_face({t[0], t[1], t[2]});
    return m;
}

}  // namespace impulse::mesh
