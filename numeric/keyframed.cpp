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
