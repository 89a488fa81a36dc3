// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the CPU can run, asked once (numeric/cpu.cpp): every vectorised loop of impulse is an
// AVX2 or AVX-512 copy of a baseline loop with the same bits, chosen at run time from these.
// The environment variable IMPULSE_SIMD = baseline | avx2 | avx512 caps the choice (for
// comparing the paths' bytes; a path the CPU lacks is never taken).

namespace impulse::numeric {

/// The widest instruction set the vectorised loops may use, in increasing order.
enum class SimdPath { Baseline = 0, Avx2 = 1, Avx512 = 2 };

/// The widest path this CPU runs and IMPULSE_SIMD allows (read once). Throws ValueError when
/// IMPULSE_SIMD is set to anything but baseline, avx2 or avx512.
SimdPath simd_path();
/// "baseline", "avx2" or "avx512".
const char* simd_name(SimdPath path);
/// True when the CPU runs AVX2 code (and IMPULSE_SIMD allows it).
bool cpu_has_avx2();
/// True when the CPU runs AVX2 and FMA code (and IMPULSE_SIMD allows it).
bool cpu_has_avx2_fma();
/// True when the CPU runs AVX-512 F/VL/DQ/BW code with FMA (and IMPULSE_SIMD allows it).
bool cpu_has_avx512();

}  // namespace impulse::numeric
