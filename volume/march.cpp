// SPDX-License-Identifier: Apache-2.0
// Ray-marched preview: Beer–Lambert absorption and single scattering of a directional light
// (Max 1995, "Optical models for direct volume rendering", §4), shadows from a light-
// transmittance grid.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "numeric/errors.h"
#include "volume/march.h"

namespace impulse::volume {
namespace {

using V3 = std::array<double, 3>;
V3 operator+(V3 a, V3 b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V3 operator-(V3 a, V3 b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 operator*(double s, V3 a) { return {s * a[0], s * a[1], s * a[2]}; }
double dot(V3 a, V3 b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 cross(V3 a, V3 b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
V3 normalized(V3 a) { return (1.0 / std::sqrt(dot(a, a))) * a; }

/// A grid sampled trilinearly at a point in voxel units (centres at i + 1/2), 0 outside.
struct Sampler {
    const float* v;
    std::array<int, 3> n;
    double scale;  ///< voxel units per sample of this grid (2 for the half-resolution light)
    double operator()(const V3& p) const {
        double u[3];
        int i[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            u[a] = p[a] / scale - 0.5;
            i[a] = int(std::floor(u[a]));
            f[a] = u[a] - i[a];
        }
        double s = 0.0;
        for (int c = 0; c < 8; ++c) {
            const int x = i[0] + (c & 1), y = i[1] + ((c >> 1) & 1), z = i[2] + (c >> 2);
            if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) continue;
            const double w = ((c & 1) ? f[0] : 1 - f[0]) * (((c >> 1) & 1) ? f[1] : 1 - f[1]) *
                             ((c >> 2) ? f[2] : 1 - f[2]);
            s += w * v[(size_t(z) * n[1] + y) * n[0] + x];
        }
        return s;
    }
};

/// Where the ray o + t d meets the box [0, n]: [t0, t1] (t0 > t1: misses).
std::pair<double, double> box_hit(const V3& o, const V3& d, const std::array<int, 3>& n) {
    double t0 = 0.0, t1 = 1e30;
    for (int a = 0; a < 3; ++a) {
        const double inv = 1.0 / d[a];
        double ta = (0.0 - o[a]) * inv, tb = (n[a] - o[a]) * inv;
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    }
    return {t0, t1};
}

/// exp(-optical depth) towards the sun from every voxel of a half-resolution grid (the shadow
/// rays, marched once per frame instead of once per camera sample).
std::vector<float> light_grid(const DensityGrid& g, const MarchOptions& o, std::array<int, 3>& ln) {
    const Sampler density{g.values.data(), g.size, 1.0};
    for (int a = 0; a < 3; ++a) ln[a] = std::max(1, g.size[a] / 2);
    std::vector<float> L(size_t(ln[0]) * ln[1] * ln[2]);
    const V3 sun = normalized(o.sun);
    constexpr double kStep = 2.0;
    tbb::parallel_for(0, ln[2], [&](int k) {
        for (int j = 0; j < ln[1]; ++j)
            for (int i = 0; i < ln[0]; ++i) {
                const V3 p0 = {2.0 * (i + 0.5), 2.0 * (j + 0.5), 2.0 * (k + 0.5)};
                const double t1 = box_hit(p0, sun, g.size).second;
                double tau = 0.0;
                for (double t = 0.5 * kStep; t < t1; t += kStep) tau += density(p0 + t * sun);
                L[(size_t(k) * ln[1] + j) * ln[0] + i] = float(std::exp(-o.extinction * kStep * tau));
            }
    });
    return L;
}

V3 sky(const MarchOptions& o, const V3& d) {
    const double t = std::clamp(d[2] * 2.0, 0.0, 1.0);
    return (1.0 - t) * V3{o.sky_horizon} + t * V3{o.sky_zenith};
}

/// Linear radiance to display radiance: the identity below kKnee, then an exponential shoulder
/// of slope 1 at the knee that tends to 1 (docs/volume.md "Preview"): sunlit tops roll off
/// towards white instead of clipping to a flat plate (a clamp put 9.8 % of cloudvolume's frame
/// 0 at the top code value). The top 8-bit code takes linear radiance above 1.56.
double shoulder(double x) {
    constexpr double kKnee = 0.8;
    return x <= kKnee ? x : kKnee + (1.0 - kKnee) * (1.0 - std::exp(-(x - kKnee) / (1.0 - kKnee)));
}

double srgb(double x) {
    x = std::clamp(shoulder(x), 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
}

/// Henyey–Greenstein phase times 4 pi (1 for isotropic scattering).
double phase(double g, double cos_theta) {
    return (1.0 - g * g) / std::pow(1.0 + g * g - 2.0 * g * cos_theta, 1.5);
}

struct Camera {
    V3 eye, f, r, u;
    double tan_half;
};

Camera camera(const DensityGrid& g, const MarchOptions& o) {
    const auto& n = g.size;
    Camera c;
    V3 eye = o.eye, target = o.target;
    const double aspect = double(o.width) / o.height;
    c.tan_half = std::tan(o.fov_deg * std::numbers::pi / 360.0);
    if (eye == target) {  // frame the box from the front, a little below its middle
        target = {n[0] / 2.0, n[1] / 2.0, n[2] * 0.5};
        const double fit = std::max(n[0] / aspect, double(n[2])) * 0.4 / c.tan_half;
        eye = {n[0] / 2.0, n[1] / 2.0 - n[1] / 2.0 - fit, n[2] * 0.3};
    }
    c.eye = eye;
    c.f = normalized(target - eye);
    c.r = normalized(cross(c.f, {0, 0, 1}));
    c.u = cross(c.r, c.f);
    return c;
}

}  // namespace

std::vector<float> march(const DensityGrid& g, const MarchOptions& o) {
    if (o.width < 1 || o.height < 1 || !(o.step > 0)) throw ValueError("march: bad image size or step");
    std::array<int, 3> ln{};
    const std::vector<float> L = light_grid(g, o, ln);
    const Sampler density{g.values.data(), g.size, 1.0}, light{L.data(), ln, 2.0};
    const Camera cam = camera(g, o);
    const V3 sun = normalized(o.sun);
    const double aspect = double(o.width) / o.height;
    std::vector<float> rgb(size_t(o.width) * o.height * 3);
    tbb::parallel_for(0, o.height, [&](int py) {
        for (int px = 0; px < o.width; ++px) {
            const double sx = (2.0 * (px + 0.5) / o.width - 1.0) * cam.tan_half * aspect;
            const double sy = (1.0 - 2.0 * (py + 0.5) / o.height) * cam.tan_half;
            const V3 d = normalized(cam.f + sx * cam.r + sy * cam.u);
            const double ph = phase(o.anisotropy, dot(sun, d));
            V3 acc = {0, 0, 0};
            double T = 1.0;
            auto [t0, t1] = box_hit(cam.eye, d, g.size);
            for (double t = t0 + 0.5 * o.step; t < t1 && T > 1e-3; t += o.step) {
                const V3 p = cam.eye + t * d;
                const double rho = density(p);
                if (rho <= 0.0) continue;
                // Beer–Lambert over the step; what is removed is scattered light: the sun's
                // (attenuated towards the light, HG phase) plus an ambient sky term that
                // darkens towards the base (an empirical stand-in for multiple scattering).
                const double a = 1.0 - std::exp(-o.extinction * rho * o.step);
                const double sun_in = light(p) * ph;
                const double amb = o.ambient * (0.35 + 0.65 * p[2] / g.size[2]);
                for (int c = 0; c < 3; ++c)
                    acc[c] += T * a * o.albedo * (o.sun_color[c] * sun_in + amb * o.sky_zenith[c] * 2.0);
                T *= 1.0 - a;
            }
            const V3 bg = sky(o, d);
            for (int c = 0; c < 3; ++c)
                rgb[(size_t(py) * o.width + px) * 3 + c] = float(srgb(o.exposure * (acc[c] + T * bg[c])));
        }
    });
    return rgb;
}

}  // namespace impulse::volume
