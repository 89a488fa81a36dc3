// SPDX-License-Identifier: Apache-2.0
// Motion blur's closed form (docs/motion_blur.md "Theory"): each impulse's kernel replaced by
// its mean along its path over the shutter, the path straight at the flow's velocity.

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "scenes/scenes.h"

namespace impulse::scenes {
namespace {

/// sin(x) / x.
double sinc(double x) { return std::abs(x) < 1e-8 ? 1.0 : std::sin(x) / x; }

/// 16-point Gauss-Legendre nodes and weights on [0, 1].
struct Legendre16 {
    std::array<double, 16> x{}, w{};
    Legendre16() {
        static constexpr double n[8] = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274,
                                        0.6178762444026438, 0.7554044083550030, 0.8656312023878318,
                                        0.9445750230732326, 0.9894009349916499};
        static constexpr double v[8] = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025,
                                        0.1495959888165767, 0.1246289712555339, 0.0951585116824928,
                                        0.0622535239386479, 0.0271524594117541};
        for (int i = 0; i < 8; ++i) {
            x[2 * i] = 0.5 * (1 - n[i]), x[2 * i + 1] = 0.5 * (1 + n[i]);
            w[2 * i] = w[2 * i + 1] = 0.5 * v[i];
        }
    }
};

}  // namespace

double MotionBlur::spectrum_factor(double kx, double ky) const {
    if (paths.empty()) return 1.0;
    double s = 0.0;
    for (size_t p = 0; p < paths.size(); ++p) {
        const double c = sinc(std::numbers::pi * (kx * paths[p][0] + ky * paths[p][1]));
        s += weight[p] * c * c;
    }
    return s;
}

double MotionBlur::radial_factor(double rho) const {
    if (paths.empty()) return 1.0;
    constexpr int kAngles = 64;  // sinc^2 of rho |b| cos(a): 64 angles over half a turn
    double s = 0.0;
    for (int i = 0; i < kAngles; ++i) {
        const double a = std::numbers::pi * (i + 0.5) / kAngles;
        s += spectrum_factor(rho * std::cos(a), rho * std::sin(a));
    }
    return s / kAngles;
}

double MotionBlur::variance_factor(const kernels::Kernel& k) const {
    if (paths.empty()) return 1.0;
    // Var_b / Var = mean_p 2 int_0^1 (1 - s) C(s b_p) ds / C(0), C the kernel's autocorrelation
    // (the mean of h over a segment b has the autocorrelation of h convolved with the
    // segment's, a triangle): Gauss-Legendre in s.
    static const Legendre16 q;
    const double c0 = k.integral_sq();
    double sum = 0.0;
    for (size_t p = 0; p < paths.size(); ++p)
        for (int i = 0; i < 16; ++i)
            sum += weight[p] * 2.0 * q.w[i] * (1.0 - q.x[i]) *
                   k.autocorrelation(q.x[i] * paths[p][0], q.x[i] * paths[p][1]) / c0;
    return sum;
}

MotionBlur layer_motion_blur(const Scene& scene, size_t layer, double t_s) {
    MotionBlur m;
    const LayerConfig& l = scene.layers[layer];
    const double shutter_s = scene.camera.shutter / scene.output.fps;
    if (shutter_s <= 0.0 || l.source || !l.flow || l.process.lifetime_s <= 0) return m;
    // The flow at the middle of the shutter on an 8 x 8 lattice over the frame's view (a
    // uniform flow: one path; a curl flow: its spread of directions).
    const render::View v = scene.camera.view(scene.output.width, scene.output.height, t_s);
    const double t = l.layer_time(t_s + (scene.camera.shutter_open + 0.5 * scene.camera.shutter) /
                                            scene.output.fps);
    constexpr int kSide = 8;
    std::vector<double> x, y;
    for (int j = 0; j < kSide; ++j)
        for (int i = 0; i < kSide; ++i) {
            x.push_back(v.x0 + (i + 0.5) * v.width * v.scale / kSide);
            y.push_back(v.y0 + (j + 0.5) * v.height * v.scale / kSide);
        }
    std::vector<double> vx(x.size(), 0.0), vy(x.size(), 0.0);
    l.flow->add(t, x.size(), x.data(), y.data(), vx.data(), vy.data(), nullptr, nullptr);
    std::map<std::array<double, 2>, double> share;  // distinct paths (a uniform flow: one)
    for (size_t p = 0; p < x.size(); ++p)
        share[{vx[p] * shutter_s, vy[p] * shutter_s}] += 1.0 / double(x.size());
    for (const auto& [b, w] : share) m.paths.push_back(b), m.weight.push_back(w);
    return m;
}

double motion_blur_variance_factor(const Scene& scene, size_t layer, double t_s) {
    const MotionBlur m = layer_motion_blur(scene, layer, t_s);
    if (m.paths.empty()) return 1.0;
    const LayerConfig& l = scene.layers[layer];
    const double t = l.layer_time(t_s);
    return m.variance_factor(kernels::Kernel(l.kernel_keys.empty() ? l.kernel : l.kernel_at(t)));
}

}  // namespace impulse::scenes
