// SPDX-License-Identifier: Apache-2.0
#pragma once
// Gauss–Legendre quadrature used for kernel statistics (part of impulse::kernels; synth/ uses it).

#include <functional>

namespace impulse::kernels::detail {

/// Integral of f over [a, b] with `panels` composite 16-point Gauss–Legendre panels.
double integrate(const std::function<double(double)>& f, double a, double b, int panels);

/// Nodes (on [-1, 1]) and weights of the 16-point Gauss–Legendre rule.
const double* gl_nodes();
const double* gl_weights();
inline constexpr int kGlPoints = 16;

/// Bessel function J0(x), absolute error < 1e-10: power series for |x| <= 12, Hankel's
/// asymptotic expansion beyond (about 100x faster than std::cyl_bessel_j).
double bessel_j0(double x);

}  // namespace impulse::kernels::detail
