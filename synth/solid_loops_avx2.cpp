// SPDX-License-Identifier: Apache-2.0
// AVX2 build of the solid noise loops (this file is compiled with -mavx2, no FMA).
#define IMPULSE_SOLID_LOOPS avx2
#include "synth/solid_loops.inc"
