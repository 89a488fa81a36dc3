// SPDX-License-Identifier: Apache-2.0
// Baseline x86-64 build of the curl-noise inner loop.
#define IMPULSE_CURL_NAME curl_add_base
#include "sim/curl_loops.inc"
