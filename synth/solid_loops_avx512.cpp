// SPDX-License-Identifier: Apache-2.0
// AVX-512 build of the solid noise loops (this file is compiled with -mavx512f and 512-bit
// vectors, no FMA and no contraction: every lane rounds as the baseline does, the same bits).
#define IMPULSE_SOLID_LOOPS avx512
#include "synth/solid_loops.inc"
