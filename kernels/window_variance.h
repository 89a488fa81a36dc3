// SPDX-License-Identifier: Apache-2.0
#pragma once
// The impulse population's share of the scatter of a frame's sample variance, exact for any
// kernel against the analysed window (part of impulse::kernels; included by kernels/kernels.h).
//
// A frame of N pixels x_i measures V = (1/N) sum_i (f(x_i) - fbar)^2. For shot noise
// f(x) = sum_j m_j h(x - p_j) (Poisson points p_j of intensity lambda, marks m_j = a_j w_j) V is
// a quadratic form in the random measure M = sum_j m_j delta_{p_j}:
//     V = int int Q(u, v) dM(u) dM(v),
//     Q(u, v) = (1/N) sum_i (h(x_i - u) - hbar(u)) (h(x_i - v) - hbar(v)),
//     hbar(u) = (1/N) sum_i h(x_i - u).
// The cumulant measures of M are kappa_n = lambda E[m^n] on the diagonal (Campbell's theorem).
// Var V sums the connected partitions of the four factors: those holding a kappa_1 vanish
// (int Q(u, v) dv = 0: the frame mean takes away a constant), the two pairings give the
// Gaussian part 2 (lambda E[m^2])^2 int int Q^2, and the one block of four gives
//     Var_population V = lambda E[m^4] int A(u)^2 du,   A(u) = Q(u, u)
//                      = (1/N) sum_i h(x_i - u)^2 - hbar(u)^2.
// For kernels small against the window A = int h^2 / N over the window's area N and zero
// outside, so this is lambda E[m^4] (int h^2)^2 / N; wider kernels put most of an impulse into
// hbar, which the frame mean removes, and the term is far smaller.

namespace impulse::kernels {

class Kernel;

/// int A(u)^2 du (the factor of lambda E[m^4] above) for a width x height window of pixels at
/// unit spacing, the kernel h(x / zoom) in pixel units (zoom pixels per texture unit) averaged
/// over `orientations` angles in [0, pi) (1: the kernel's own). The u integral is a Riemann sum
/// over a grid of s x s sub-pixel phases (s from the kernel's size in pixels: a lattice sum of a
/// kernel only a pixel wide depends on where the impulse sits between pixels), each phase a
/// linear correlation of the window's indicator with h and h^2 by FFT (numeric/fft.h).
double window_population_integral(const Kernel& kernel, double zoom, int width, int height,
                                  int orientations = 1);

/// The sub-pixel phases per axis window_population_integral uses for a kernel of radius
/// `radius_px` pixels in a width x height window (at most 8; fewer when the transforms would
/// exceed about 2^26 points, where the window is then large against the kernel).
int window_population_phases(double radius_px, int width, int height);

}  // namespace impulse::kernels
