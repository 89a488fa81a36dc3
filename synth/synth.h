// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::synth — the seeds' synthesizers other than the shaped point process: generalized
// stochastic subdivision (Lewis 1986 §2, Lewis 1987; docs/subdivision.md) and fractional
// Brownian surfaces by Fourier, incremental Fourier and exact synthesis (Kaplan & Kuo 1996,
// Stein 2002; docs/fbm.md) and solid noise by sparse convolution and on lattices (Lewis 1989;
// docs/solid.md). Depends on numeric, kernels and sim.

#include "synth/fbm.h"          // fBm surfaces: fourier, incremental, exact
#include "synth/lattice.h"      // lattice solid noises: value, perlin, wiener
#include "synth/solid.h"        // solid noise by sparse convolution (3-D, 4-D)
#include "synth/subdivision.h"  // generalized stochastic subdivision, 1-D and 2-D
