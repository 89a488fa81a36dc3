// SPDX-License-Identifier: Apache-2.0
#pragma once
// The standard normal distribution: density, CDF and quantile, written once for every library
// (marginal shaping, composition theory, ramp stops, analysis thresholds).

namespace impulse::numeric {

/// phi(z) = exp(-z^2 / 2) / sqrt(2 pi).
double normal_pdf(double z);
/// Phi(z) = erfc(-z / sqrt 2) / 2, accurate in the lower tail (normal_cdf(-z) for the upper).
double normal_cdf(double z);
/// Phi^-1(p) for p in (0, 0.5]: Acklam's rational approximation (relative error 1.2e-9) and one
/// Halley step on erfc, which brings it to ~1e-15; p is floored at 1e-300.
double normal_quantile_lower(double p);
/// Phi^-1 of a probability given as p = P(Z <= z) and its complement q = 1 - p (each accurate
/// on its own, so both tails keep their digits): z with Phi(z) = p.
double normal_quantile(double p, double q);
/// Phi^-1(p) for p in (0, 1).
inline double normal_quantile(double p) { return normal_quantile(p, 1.0 - p); }

}  // namespace impulse::numeric
