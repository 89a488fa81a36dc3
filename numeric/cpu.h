// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the CPU can run, asked once (numeric/cpu.cpp): every vectorised loop of impulse is an
// AVX2 copy of a baseline loop with the same bits, chosen at run time from these. The environment
// variable IMPULSE_SIMD=baseline makes both false (the baseline loops on any CPU).

namespace impulse::numeric {

/// True when the CPU runs AVX2 code.
bool cpu_has_avx2();
/// True when the CPU runs AVX2 and FMA code.
bool cpu_has_avx2_fma();

}  // namespace impulse::numeric
