// SPDX-License-Identifier: Apache-2.0
#include "numeric/cpu.h"

namespace impulse::numeric {

bool cpu_has_avx2() {
    static const bool has = __builtin_cpu_supports("avx2");
    return has;
}

bool cpu_has_avx2_fma() {
    static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return has;
}

}  // namespace impulse::numeric
