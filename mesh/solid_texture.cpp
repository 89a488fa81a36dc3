// SPDX-License-Identifier: Apache-2.0
// Solid wood and marble at points (Lewis 1989 §5.1).

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "mesh/mesh.h"
#include "numeric/errors.h"
#include "output/image.h"

namespace impulse::mesh {
namespace {

using Type = output::FieldTransform::Type;

/// u along the marble direction or r from the wood axis, for every point.
std::vector<double> geometry(const SolidTexture& t, const std::vector<synth::SolidPoint>& points) {
    const Eigen::Vector3d a = t.direction.normalized();
    std::vector<double> g(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        const Eigen::Vector3d d = Eigen::Vector3d(points[i].x, points[i].y, points[i].z) - t.origin;
        const double along = d.dot(a);
        g[i] = t.transform.type == Type::Marble ? along : (d - along * a).norm();
    });
    return g;
}

}  // namespace

void validate(const SolidTexture& t) {
    const output::FieldTransform& f = t.transform;
    if (f.type == Type::None) throw ValueError("transform: expected wood or marble");
    if (!(t.direction.norm() > 0) || !t.direction.allFinite())
        throw ValueError("direction: expected a nonzero finite vector");
    if (!(f.turbulence >= 0)) throw ValueError("turbulence = " + std::to_string(f.turbulence) + ": expected >= 0");
    if (f.type == Type::Wood && !(f.ring_width > 0))
        throw ValueError("ring_width = " + std::to_string(f.ring_width) + ": expected > 0");
    if (f.type == Type::Wood && !(f.growth >= 0 && f.growth < 1))
        throw ValueError("growth = " + std::to_string(f.growth) + ": expected in [0, 1)");
    if (f.type == Type::Wood && !(f.sharpness >= 1))
        throw ValueError("sharpness = " + std::to_string(f.sharpness) + ": expected >= 1");
    synth::SolidNoise{t.noise};  // the noise's own checks
}

std::vector<float> solid_texture_values(const SolidTexture& t,
                                        const std::vector<synth::SolidPoint>& points) {
    validate(t);
    const synth::SolidNoise noise(t.noise);
    std::vector<float> eta;
    noise.evaluate(points, eta);
    const double inv_sigma = 1.0 / std::sqrt(noise.theory().variance);
    const std::vector<double> g = geometry(t, points);
    const double r_max = g.empty() ? 0.0 : *std::max_element(g.begin(), g.end());
    const output::PointTransform transform(t.transform, r_max);
    std::vector<float> v(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        v[i] = static_cast<float>(transform(g[i], eta[i] * inv_sigma));
    });
    return v;
}

std::vector<Vec3> solid_texture_colors(const SolidTexture& t, const std::vector<float>& values) {
    output::Shading shading;
    shading.ramp = t.ramp;
    const output::Shader shader(output::transform_range(t.transform), shading);
    // The values as rows of a frame, shaded a band of rows per task.
    constexpr int kRow = 1024;
    numeric::Frame f;
    f.resize(kRow, static_cast<int>((values.size() + kRow - 1) / kRow));
    std::copy(values.begin(), values.end(), f.data.begin());
    std::vector<float> rgb(f.data.size() * 3);
    tbb::parallel_for(0, f.height, [&](int y) { shader.rows(f, y, y + 1, rgb.data() + size_t(y) * kRow * 3); });
    std::vector<Vec3> colors(values.size());
    for (size_t i = 0; i < values.size(); ++i) colors[i] = Vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    return colors;
}

void texture_mesh(const SolidTexture& t, Mesh& mesh) {
    mesh.colors = solid_texture_colors(t, solid_texture_values(t, solid_points(mesh.positions)));
}

std::vector<float> solid_texture_section(const SolidTexture& t, const Section& s) {
    const int u = (s.axis + 1) % 3, v = (s.axis + 2) % 3;  // right-handed: (x, y) for z, ...
    std::vector<synth::SolidPoint> points(size_t(s.width) * s.height);
    for (int j = 0; j < s.height; ++j)
        for (int i = 0; i < s.width; ++i) {
            double p[3];
            p[s.axis] = s.value;
            p[u] = s.lo.x() + (i + 0.5) * (s.hi.x() - s.lo.x()) / s.width;
            p[v] = s.hi.y() - (j + 0.5) * (s.hi.y() - s.lo.y()) / s.height;
            points[size_t(j) * s.width + i] = {p[0], p[1], p[2], 0.0};
        }
    const std::vector<Vec3> c = solid_texture_colors(t, solid_texture_values(t, points));
    std::vector<float> rgb(c.size() * 3);
    for (size_t i = 0; i < c.size(); ++i) std::copy_n(c[i].data(), 3, rgb.data() + 3 * i);
    return rgb;
}

}  // namespace impulse::mesh
