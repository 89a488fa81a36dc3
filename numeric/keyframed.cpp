// SPDX-License-Identifier: Apache-2.0
#include "numeric/keyframed.h"

#include <algorithm>
#include <cmath>

namespace impulse::numeric {

std::optional<Ease> ease_from_string(std::string_view name) {
    for (size_t i = 0; i < kEaseNames.size(); ++i)
        if (kEaseNames[i] == name) return static_cast<Ease>(i);
    return std::nullopt;
}

double Keyframed::value(double t) const {
    if (keys.empty()) return 0.0;
    if (keys.size() == 1 || t <= keys.front().first) return keys.front().second;
    if (t >= keys.back().first) return keys.back().second;
    auto it = std::upper_bound(keys.begin(), keys.end(), t,
                               [](double v, const auto& k) { return v < k.first; });
    const auto& b = *it;
    const auto& a = *(it - 1);
    double s = (t - a.first) / (b.first - a.first);
    switch (ease) {
        case Ease::Linear: break;
        case Ease::Smooth: s = s * s * (3.0 - 2.0 * s); break;
        case Ease::Step: s = 0.0; break;
    }
    return a.second + s * (b.second - a.second);
}

namespace {

// int_{t_first}^{t} value(s) ds of keys k with ease e (t may precede t_first).
double from_first_key(const std::vector<std::pair<double, double>>& k, Ease e, double t) {
    if (t <= k.front().first || k.size() == 1) return k.front().second * (t - k.front().first);
    double sum = 0.0;
    for (size_t i = 1; i < k.size(); ++i) {
        const auto& [ta, a] = k[i - 1];
        const auto& [tb, b] = k[i];
        const double dt = tb - ta;
        if (t < tb) {
            // The part of the segment up to s = (t - ta) / dt: int_0^s ease(u) du.
            const double s = (t - ta) / dt;
            const double eased = e == Ease::Linear   ? 0.5 * s * s
                                 : e == Ease::Smooth ? s * s * s - 0.5 * s * s * s * s
                                                     : 0.0;
            return sum + dt * (a * s + (b - a) * eased);
        }
        sum += e == Ease::Step ? a * dt : 0.5 * (a + b) * dt;
    }
    return sum + k.back().second * (t - k.back().first);
}

}  // namespace

double Keyframed::integral(double t) const {
    if (keys.empty()) return 0.0;
    return from_first_key(keys, ease, t) - from_first_key(keys, ease, 0.0);
}

double Keyframed::max_abs() const {
    double m = 0.0;
    for (const auto& k : keys) m = std::max(m, std::abs(k.second));
    return m;  // linear, smoothstep and step interpolation never overshoot the keys
}

double Keyframed::min() const {
    double m = keys.empty() ? 0.0 : keys.front().second;
    for (const auto& k : keys) m = std::min(m, k.second);
    return m;
}

double Keyframed::max() const {
    double m = keys.empty() ? 0.0 : keys.front().second;
    for (const auto& k : keys) m = std::max(m, k.second);
    return m;
}

}  // namespace impulse::numeric
