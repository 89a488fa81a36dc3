// SPDX-License-Identifier: Apache-2.0
#pragma once
// Keyframed scalars: every time-varying number of a scene (densities, gains, kernel parameters,
// flows, cameras, shading) is one of these.

#include <array>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

namespace impulse::numeric {

enum class Ease { Linear, Smooth, Step };
inline constexpr std::array<std::string_view, 3> kEaseNames = {"linear", "smooth", "step"};
std::optional<Ease> ease_from_string(std::string_view name);

/// A scalar that may vary in time: constant, or keys (t_s, value) with strictly increasing
/// times, held constant before the first and after the last key. `smooth` eases with
/// smoothstep between keys; `step` holds each key's value until the next.
struct Keyframed {
    std::vector<std::pair<double, double>> keys;  ///< (time in seconds, value)
    Ease ease = Ease::Linear;

    Keyframed() = default;
    Keyframed(double constant) : keys{{0.0, constant}} {}  // NOLINT: implicit by design
    double value(double t_s) const;
    double max_abs() const;  ///< max |value| over all time
    /// Smallest and largest value over all time: the extreme keys (linear, smoothstep and step
    /// interpolation never leave the range of the two keys around t).
    double min() const;
    double max() const;
    bool is_constant() const { return keys.size() <= 1; }
    /// int_0^t value(s) ds (negative for t < 0), in closed form: a linear or smoothstep segment
    /// of keys a, b over dt integrates to (a + b) dt / 2 (int_0^1 3s^2 - 2s^3 ds = 1/2), a step
    /// segment to a dt; before the first and after the last key the held value times the time.
    double integral(double t_s) const;
};

}  // namespace impulse::numeric
