// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::render — impulse evaluation: tiled sparse convolution of the live impulses with the
// kernel (Lewis 1986 eq. 2), the naive per-pixel reference, and cameras with anti-aliasing
// (perspective, the band-limited kernel pyramid). Depends on numeric, kernels and sim; knows
// nothing of images, video, scene files or the CLI (those are output/, scenes/, app/).

#include "render/evaluate.h"     // orthographic frames
#include "render/lattice.h"      // multi-rate: a lattice from the spectrum, then reconstruction
#include "render/gradient.h"     // exact df/dx, df/dy of orthographic frames
#include "render/perspective.h"  // cameras with anti-aliasing (kernel pyramid)
