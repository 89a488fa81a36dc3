// SPDX-License-Identifier: Apache-2.0
#pragma once
// Amplitude laws and temporal envelopes of the impulses (Campbell's theorem needs their moments).
// Part of impulse::sim (sim/sim.h).

#include <array>
#include <optional>
#include <string_view>

#include "numeric/box.h"

namespace impulse::sim {

using numeric::Box;

/// The amplitude law of the impulses. Normal, uniform on [-1, 1] and sign (+-1) are zero-mean;
/// exponential (rate 1, a = -ln u) is positive, for fields that are a non-negative quantity
/// (dye, heat): the field's mean is then lambda E[a] int h, not 0 (Campbell's theorem).
enum class Amplitude { Normal, Uniform, Sign, Exponential };
inline constexpr std::array<std::string_view, 4> kAmplitudeNames = {"normal", "uniform", "sign",
                                                                    "exponential"};
std::optional<Amplitude> amplitude_from_string(std::string_view name);
/// E[a]: 0 for normal, uniform and sign; 1 for exponential.
double amplitude_mean(Amplitude a);
/// E[a^2]: normal 1, uniform on [-1, 1] 1/3, sign 1, exponential 2.
double amplitude_second_moment(Amplitude a);
/// E[a^4]: normal 3, uniform 1/5, sign 1, exponential 24.
double amplitude_fourth_moment(Amplitude a);

/// Temporal envelope w(age) of a particle living T seconds: the time half of a space-time kernel.
enum class Envelope { Hann, Box };
inline constexpr std::array<std::string_view, 2> kEnvelopeNames = {"hann", "box"};
std::optional<Envelope> envelope_from_string(std::string_view name);
/// w(age): hann sin^2(pi age / T), box 1, both 0 outside [0, T).
double envelope_weight(Envelope e, double age_s, double lifetime_s);
/// int_0^T w^2 dt: hann 3T/8, box T.
double envelope_sq_integral(Envelope e, double lifetime_s);
/// int_0^T w dt: hann T/2, box T.
double envelope_integral(Envelope e, double lifetime_s);
/// int_0^T w^4 dt: hann 35T/128, box T (the impulse population's fourth cumulant).
double envelope_fourth_integral(Envelope e, double lifetime_s);

}  // namespace impulse::sim
