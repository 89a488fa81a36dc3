// SPDX-License-Identifier: Apache-2.0
// Names, moments and envelopes of the point process.

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
std::optional<VortexModel> vortex_model_from_string(std::string_view n) {
    return from_names<VortexModel>(kVortexModelNames, n);
}
std::optional<Integrator> integrator_from_string(std::string_view n) {
    return from_names<Integrator>(kIntegratorNames, n);
}
std::optional<OrientationMode> orientation_mode_from_string(std::string_view n) {
    return from_names<OrientationMode>(kOrientationModeNames, n);
}

double amplitude_mean(Amplitude a) { return a == Amplitude::Exponential ? 1.0 : 0.0; }

double amplitude_second_moment(Amplitude a) {
    switch (a) {
        case Amplitude::Normal: return 1.0;
        case Amplitude::Uniform: return 1.0 / 3.0;
        case Amplitude::Sign: return 1.0;
        case Amplitude::Exponential: return 2.0;  // E[a^n] = n! for rate 1
    }
    return 1.0;
}

double amplitude_fourth_moment(Amplitude a) {
    switch (a) {
        case Amplitude::Normal: return 3.0;
        case Amplitude::Uniform: return 1.0 / 5.0;
        case Amplitude::Sign: return 1.0;
        case Amplitude::Exponential: return 24.0;
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
double envelope_fourth_integral(Envelope e, double T) {
    return e == Envelope::Box ? T : 35.0 / 128.0 * T;  // int sin^8 over a period: 35/128
}

void Impulses::clear() {
    x.clear();
    y.clear();
    weight.clear();
    theta.clear();
    scale.clear();
}

}  // namespace impulse::sim
