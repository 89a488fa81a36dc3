// SPDX-License-Identifier: Apache-2.0
// Particles forced by vector solid noise (Lewis 1989 Figs. 12-13).

#include <cmath>
#include <numbers>

#include "mesh/mesh.h"
#include "numeric/errors.h"
#include "numeric/rng.h"

namespace impulse::mesh {
namespace {

constexpr uint32_t kStartStream = 0x54524A53u;  // "TRJS": the start points' stream

void check(const TrajectoryParams& p) {
    auto refuse = [](const std::string& what) { throw ValueError(what); };
    if (p.particles < 1 || p.particles > 1000000) refuse("particles = " + std::to_string(p.particles) + ": expected in [1, 1000000]");
    if (p.steps < 1 || p.steps > 100000) refuse("steps = " + std::to_string(p.steps) + ": expected in [1, 100000]");
    if (double(p.particles) * p.steps > 1e8) refuse("particles x steps = " + std::to_string(double(p.particles) * p.steps) + ": expected <= 1e8");
    if (!(p.dt > 0) || !std::isfinite(p.dt)) refuse("dt = " + std::to_string(p.dt) + ": expected a finite number > 0");
    if (!std::isfinite(p.force)) refuse("force: expected a finite number");
    if (!(p.drag >= 0) || !std::isfinite(p.drag)) refuse("drag = " + std::to_string(p.drag) + ": expected a finite number >= 0");
    if (!(p.radius > 0) || !std::isfinite(p.radius)) refuse("radius = " + std::to_string(p.radius) + ": expected a finite number > 0");
    if (p.noise.dims != 3) refuse("dims = " + std::to_string(p.noise.dims) + ": expected 3");
}

}  // namespace

std::vector<Vec3> trajectory_starts(const TrajectoryParams& p) {
    const numeric::CounterRng rng(p.seed, kStartStream);
    std::vector<Vec3> x(p.particles);
    for (int i = 0; i < p.particles; ++i) {
        const auto u = rng.uniforms(i, 0, 0, 0);  // one draw: four uniforms in (0, 1]
        const double r = p.radius * std::cbrt(u[0]);  // uniform in the ball's volume
        const double cos_theta = 2.0 * u[1] - 1.0, phi = 2.0 * std::numbers::pi * u[2];
        const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
        x[i] = Vec3(float(r * s * std::cos(phi)), float(r * s * std::sin(phi)), float(r * cos_theta));
    }
    return x;
}

Mesh trajectories(const TrajectoryParams& p) {
    check(p);
    const synth::SolidNoise noise(p.noise);
    const double f = p.force / std::sqrt(noise.theory().variance);
    std::vector<Eigen::Vector3d> x(p.particles), v(p.particles, Eigen::Vector3d::Zero());
    const std::vector<Vec3> starts = trajectory_starts(p);
    for (int i = 0; i < p.particles; ++i) x[i] = starts[i].cast<double>();
    const size_t stride = size_t(p.steps) + 1;
    Mesh m;
    m.positions.resize(stride * p.particles);
    std::vector<synth::SolidPoint> pts(p.particles);
    std::vector<float> eta[3];
    for (int s = 0;; ++s) {
        for (int i = 0; i < p.particles; ++i) {
            m.positions[i * stride + s] = x[i].cast<float>();
            pts[i] = {x[i].x(), x[i].y(), x[i].z(), 0.0};
        }
        if (s == p.steps) break;
        for (int c = 0; c < 3; ++c) noise.evaluate(pts, eta[c], c);
        for (int i = 0; i < p.particles; ++i) {  // semi-implicit Euler: v first, then x with it
            const Eigen::Vector3d a(eta[0][i], eta[1][i], eta[2][i]);
            v[i] += p.dt * (f * a - p.drag * v[i]);
            x[i] += p.dt * v[i];
        }
    }
    for (int i = 0; i < p.particles; ++i)
        for (int s = 0; s < p.steps; ++s) m.add_face({uint32_t(i * stride + s), uint32_t(i * stride + s + 1)});
    m.colors.resize(m.positions.size());
    const Vec3 first(0.08f, 0.16f, 0.45f), last(0.95f, 0.55f, 0.15f);
    for (size_t k = 0; k < m.colors.size(); ++k) {
        const float along = float(k % stride) / float(p.steps);  // how far along its path
        m.colors[k] = (1 - along) * first + along * last;
    }
    return m;
}

}  // namespace impulse::mesh
