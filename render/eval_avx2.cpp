// SPDX-License-Identifier: Apache-2.0
// AVX2 build of the evaluator's inner loops (this file is compiled with -mavx2, no FMA).
#define IMPULSE_EVAL_NAME eval_tile_avx2
#include "render/eval_loops.inc"
