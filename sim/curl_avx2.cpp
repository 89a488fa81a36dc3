// SPDX-License-Identifier: Apache-2.0
// AVX2 build of the curl-noise inner loop (this file is compiled with -mavx2, no FMA).
#define IMPULSE_CURL_NAME curl_add_avx2
#include "sim/curl_loops.inc"
