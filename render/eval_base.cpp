// SPDX-License-Identifier: Apache-2.0
// Baseline x86-64 build of the evaluator's inner loops.
#define IMPULSE_EVAL_NAME eval_tile_base
#define IMPULSE_EVAL_LANES 8
#include "render/eval_loops.inc"
