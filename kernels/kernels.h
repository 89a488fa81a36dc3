// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::kernels — the kernels h of the shaped Poisson point process (Lewis 1986 §3) with
// their exact second-order statistics, kernels designed from a spectrum, an autocorrelation or
// an exemplar, distribution shaping and the band-limited pyramid. Depends on numeric only.

#include "kernels/kernel.h"    // analytic and sampled kernels, their integrals and spectra
#include "kernels/pyramid.h"   // band-limited kernel pyramid (Lewis 1986 §3.1)
#include "kernels/quadrature.h"  // Gauss-Legendre panels and J0 for kernel statistics
#include "kernels/shaping.h"   // distribution shaping (Lewis 1986 §4) and ITAM
#include "kernels/shot_noise.h"  // the law of shot noise from its characteristic function
#include "kernels/spectral.h"  // kernels from a spectrum, an autocorrelation, an exemplar
#include "kernels/window_variance.h"  // the impulse population's scatter of a window's variance
