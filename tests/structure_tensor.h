// SPDX-License-Identifier: Apache-2.0
#pragma once
// The local orientation of a rendered texture, measured with a structure tensor: shared by the
// orientation-field tests (tests/sim) and the layer-orientation tests (tests/scenes).

#include <cmath>
#include <numbers>
#include <vector>

#include "render/render.h"

namespace impulse::test {

/// Angle difference modulo pi (orientations), in degrees, in [0, 90].
inline double orientation_error_deg(double a, double b) {
    const double d = std::remainder(a - b, std::numbers::pi);
    return std::abs(d) * 180.0 / std::numbers::pi;
}

/// Local orientation of the streaks of `f` in windows of `win` pixels: the structure tensor
/// (gradients by central differences; the tensor summed over the window) has its dominant
/// gradient direction phi = atan2(2 Jxy, Jxx - Jyy) / 2 across the streaks; the streaks (the
/// kernels' long axis) run at phi + pi/2.
struct OrientationEstimate {
    double cx, cy, angle;
    double coherence;  ///< (l1 - l2) / (l1 + l2)
};
inline std::vector<OrientationEstimate> structure_tensor(const render::Frame& f, int win) {
    std::vector<OrientationEstimate> out;
    for (int y0 = 1; y0 + win <= f.height - 1; y0 += win)
        for (int x0 = 1; x0 + win <= f.width - 1; x0 += win) {
            double jxx = 0, jxy = 0, jyy = 0;
            for (int y = y0; y < y0 + win; ++y)
                for (int x = x0; x < x0 + win; ++x) {
                    const double gx = 0.5 * (f.at(x + 1, y) - f.at(x - 1, y));
                    const double gy = 0.5 * (f.at(x, y + 1) - f.at(x, y - 1));
                    jxx += gx * gx, jxy += gx * gy, jyy += gy * gy;
                }
            const double phi = 0.5 * std::atan2(2.0 * jxy, jxx - jyy);
            const double l = std::hypot(jxx - jyy, 2.0 * jxy);
            out.push_back({x0 + 0.5 * win, y0 + 0.5 * win, phi + 0.5 * std::numbers::pi,
                           l / (jxx + jyy)});
        }
    return out;
}

}  // namespace impulse::test
