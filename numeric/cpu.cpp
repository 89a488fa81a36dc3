// SPDX-License-Identifier: Apache-2.0
#include "numeric/cpu.h"

#include <cstdlib>
#include <cstring>

namespace impulse::numeric {
namespace {

/// IMPULSE_SIMD=baseline: run the baseline loops whatever the CPU has (to compare their bits
/// with the AVX2 ones on one machine; docs/solid.md "Determinism").
bool forced_baseline() {
    const char* v = std::getenv("IMPULSE_SIMD");
    return v && std::strcmp(v, "baseline") == 0;
}

}  // namespace

bool cpu_has_avx2() {
    static const bool has = __builtin_cpu_supports("avx2") && !forced_baseline();
    return has;
}

bool cpu_has_avx2_fma() {
    static const bool has =
        __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && !forced_baseline();
    return has;
}

}  // namespace impulse::numeric
