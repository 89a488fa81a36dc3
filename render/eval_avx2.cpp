// SPDX-License-Identifier: Apache-2.0
// AVX2 build of the evaluator's inner loops (compiled with -mavx2 -mfma; no contraction, so FMA
// only where the source writes std::fma).
#define IMPULSE_EVAL_NAME eval_tile_avx2
#define IMPULSE_EVAL_LANES 8
#include "render/eval_loops.inc"
