// SPDX-License-Identifier: Apache-2.0
// AVX-512 build of the evaluator's inner loops (compiled with -mavx512f/vl/dq/bw -mfma and
// 512-bit vectors preferred; no contraction, so FMA only where the source writes std::fma).
#define IMPULSE_EVAL_NAME eval_tile_avx512
#define IMPULSE_EVAL_LANES 16
#include "render/eval_loops.inc"
