// SPDX-License-Identifier: Apache-2.0
#pragma once
// Catmull-Rom cubic interpolation weights: the C1 interpolant of lattice values used for the
// stream-function flows (sim/detail/lattice.h) and for resampling and differentiating frames in the
// composition of layers (scenes/frame/compose_render.cpp).

namespace impulse::numeric {

/// Weights w and their first and second derivatives d, dd (per unit t) at t in [0, 1) for the
/// nodes -1, 0, 1, 2; w reproduces node 0 exactly at t = 0 (w = 0, 1, 0, 0).
inline void catmull_rom(double t, double w[4], double d[4], double dd[4]) {
    const double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t + 2 * t2 - t3), w[1] = 0.5 * (2 - 5 * t2 + 3 * t3);
    w[2] = 0.5 * (t + 4 * t2 - 3 * t3), w[3] = 0.5 * (-t2 + t3);
    d[0] = 0.5 * (-1 + 4 * t - 3 * t2), d[1] = 0.5 * (-10 * t + 9 * t2);
    d[2] = 0.5 * (1 + 8 * t - 9 * t2), d[3] = 0.5 * (-2 * t + 3 * t2);
    dd[0] = 2 - 3 * t, dd[1] = -5 + 9 * t, dd[2] = 4 - 9 * t, dd[3] = -1 + 3 * t;
}

}  // namespace impulse::numeric
