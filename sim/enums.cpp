// SPDX-License-Identifier: Apache-2.0
// Names, moments and envelopes of the point process; keyframed parameters.

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim/sim.h"

namespace impulse::sim {
namespace {

template <class E, size_t N>
std::optional<E> from_names(const std::array<std::string_view, N>& names, std::string_view name) {
    for (size_t i = 0; i < N; ++i)
        if (names[i] == name) return static_cast<E>(i);
    return std::nullopt;
}

}  // namespace

std::optional<Amplitude> amplitude_from_string(std::string_view n) {
    return from_names<Amplitude>(kAmplitudeNames, n);
}
std::optional<Envelope> envelope_from_string(std::string_view n) {
    return from_names<Envelope>(kEnvelopeNames, n);
}
std::optional<Ease> ease_from_string(std::string_view n) { return from_names<Ease>(kEaseNames, n); }
std::optional<VortexModel> vortex_model_from_string(std::string_view n) {
    return from_names<VortexModel>(kVortexModelNames, n);
}
std::optional<Integrator> integrator_from_string(std::string_view n) {
    return from_names<Integrator>(kIntegratorNames, n);
}
std::optional<OrientationMode> orientation_mode_from_string(std::string_view n) {
    return from_names<OrientationMode>(kOrientationModeNames, n);
}

double amplitude_second_moment(Amplitude a) {
    switch (a) {
        case Amplitude::Normal: return 1.0;
        case Amplitude::Uniform: return 1.0 / 3.0;
        case Amplitude::Sign: return 1.0;
    }
    return 1.0;
}

double amplitude_fourth_moment(Amplitude a) {
    switch (a) {
        case Amplitude::Normal: return 3.0;
        case Amplitude::Uniform: return 1.0 / 5.0;
        case Amplitude::Sign: return 1.0;
    }
    return 1.0;
}

double envelope_weight(Envelope e, double age, double T) {
    if (!(age >= 0.0) || !(age < T)) return 0.0;
    if (e == Envelope::Box) return 1.0;
    const double s = std::sin(std::numbers::pi * age / T);
    return s * s;
}

double envelope_sq_integral(Envelope e, double T) { return e == Envelope::Box ? T : 0.375 * T; }
double envelope_integral(Envelope e, double T) { return e == Envelope::Box ? T : 0.5 * T; }

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

void Impulses::clear() {
    x.clear();
    y.clear();
    weight.clear();
    theta.clear();
}

}  // namespace impulse::sim
