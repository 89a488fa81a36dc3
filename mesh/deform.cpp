// SPDX-License-Identifier: Apache-2.0
// Stochastic deformation by vector solid noise (Lewis 1989 §5.3).

#include <cmath>

#include "mesh/mesh.h"
#include "numeric/errors.h"

namespace impulse::mesh {

std::vector<Vec3> displacements(const DeformParams& p, const std::vector<Vec3>& positions) {
    if (!std::isfinite(p.amount)) throw ValueError("amount: expected a finite number");
    const synth::SolidNoise noise(p.noise);
    const double scale = p.amount / std::sqrt(noise.theory().variance);
    const std::vector<synth::SolidPoint> points = solid_points(positions, p.t);
    std::vector<Vec3> d(positions.size());
    std::vector<float> eta;
    for (int c = 0; c < 3; ++c) {  // L89 §5.3: three independent scalar noises
        noise.evaluate(points, eta, c);
        for (size_t i = 0; i < d.size(); ++i) d[i][c] = static_cast<float>(scale * eta[i]);
    }
    return d;
}

Mesh deform_mesh(const DeformParams& p, const Mesh& mesh) {
    const std::vector<Vec3> d = displacements(p, mesh.positions);
    Mesh out = mesh;
    for (size_t i = 0; i < d.size(); ++i) out.positions[i] += d[i];
    if (!out.normals.empty()) out.normals = vertex_normals(out);
    return out;
}

}  // namespace impulse::mesh
