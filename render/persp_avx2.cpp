// SPDX-License-Identifier: Apache-2.0
// AVX2 build of the perspective evaluator's inner loops (compiled with -mavx2, no FMA).
#define IMPULSE_PERSP_LOOPS kPerspLoopsAvx2
#include "render/persp_loops.inc"
