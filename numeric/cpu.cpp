// SPDX-License-Identifier: Apache-2.0
#include "numeric/cpu.h"

#include <cstdlib>
#include <string>

#include "numeric/errors.h"

namespace impulse::numeric {
namespace {

SimdPath cpu_path() {
#if defined(__x86_64__) || defined(__i386__)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
        __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") &&
        __builtin_cpu_supports("fma"))
        return SimdPath::Avx512;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return SimdPath::Avx2;
#endif
    // Other CPUs (arm64) run the baseline loops, which their compiler vectorises itself
    // (docs/contributing.md "Other CPUs").
    return SimdPath::Baseline;
}

/// The cap from IMPULSE_SIMD (unset or empty: no cap).
SimdPath env_cap() {
    const char* e = std::getenv("IMPULSE_SIMD");
    if (!e || !*e) return SimdPath::Avx512;
    const std::string v = e;
    for (SimdPath p : {SimdPath::Baseline, SimdPath::Avx2, SimdPath::Avx512})
        if (v == simd_name(p)) return p;
    throw ValueError("IMPULSE_SIMD = \"" + v + "\": expected one of baseline, avx2, avx512");
}

}  // namespace

const char* simd_name(SimdPath path) {
    switch (path) {
        case SimdPath::Avx512: return "avx512";
        case SimdPath::Avx2: return "avx2";
        default: return "baseline";
    }
}

SimdPath simd_path() {
    static const SimdPath path = [] {
        const SimdPath cpu = cpu_path(), cap = env_cap();
        return cap < cpu ? cap : cpu;
    }();
    return path;
}

// AVX2 without FMA is not a path of its own: every CPU with AVX2 that impulse meets has FMA,
// and the loops built for AVX2 without FMA round the same, so both ask for the AVX2 level.
bool cpu_has_avx2() { return simd_path() >= SimdPath::Avx2; }

bool cpu_has_avx2_fma() { return simd_path() >= SimdPath::Avx2; }

bool cpu_has_avx512() { return simd_path() >= SimdPath::Avx512; }

}  // namespace impulse::numeric
