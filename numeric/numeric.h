// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::numeric — the base library: what every synthesizer, renderer and estimator shares,
// written once. Knows nothing of scenes, particles or images.

#include "numeric/box.h"       // texture-space boxes and regions
#include "numeric/check.h"     // IMPULSE_CHECK, IMPULSE_DCHECK: invariants, not input errors
#include "numeric/cpu.h"       // run-time choice of the AVX2 loops
#include "numeric/errors.h"    // impulse::Error and its kinds
#include "numeric/fft.h"       // real 2-D FFTs on FFTW, one planner lock
#include "numeric/frame.h"     // the orthographic view and the float frame sources render into
#include "numeric/gaussian.h"  // normal pdf, CDF, quantile
#include "numeric/keyframed.h" // time-varying scalars
#include "numeric/quantile_bins.h" // equal-count bins by selection, not a full sort
#include "numeric/rng.h"       // counter-based random numbers (Philox)
#include "numeric/spline.h"    // Catmull-Rom weights
