// SPDX-License-Identifier: Apache-2.0
#pragma once
// Angles as the float theta of an impulse (internal to impulse::sim).

#include <cmath>
#include <numbers>

namespace impulse::sim::detail {

/// The float theta of an angle in radians. Beyond +-64 rad (a keyframed angle of a long spin, a
/// large jitter, a long-integrated vorticity) the angle is first wrapped into [-pi, pi]: the float
/// keeps its precision and stays finite (1e300 rad would become an infinite theta, whose cosine
/// the renderer cannot place). Angles within the bound keep their bits.
inline float theta_of(double a) {
    return static_cast<float>(std::abs(a) <= 64.0 ? a : std::remainder(a, 2.0 * std::numbers::pi));
}

}  // namespace impulse::sim::detail
