// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::volume — the shaped Poisson point process in 3-D (docs/volume.md): impulses born in
// a box (Poisson in space and time, keyed by the counter RNG), advected by 3-D flows with the
// same lifetimes, fades and sqrt(J) weighting as the 2-D particle system (design.md §1), their
// solid kernels (synth::SolidKernel) splatted into a dense grid and shaped into cloud density;
// and a ray-marched preview of such a grid. Depends on numeric, kernels, sim and synth.

#include "volume/cloud.h"     // octaves of 3-D processes -> dense density grid, shaping, theory
#include "volume/flow.h"      // 3-D flows: uniform wind, uniform divergence, curl noise
#include "volume/march.h"     // ray-marched preview with a directional light
#include "volume/process.h"   // one 3-D process: births, motion, sqrt(J), live impulses
