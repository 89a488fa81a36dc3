// SPDX-License-Identifier: Apache-2.0
// Baseline x86-64 build of the perspective evaluator's inner loops.
#define IMPULSE_PERSP_LOOPS kPerspLoopsBase
#include "render/persp_loops.inc"
