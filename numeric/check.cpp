// SPDX-License-Identifier: Apache-2.0
// The failure path of numeric/check.h's invariant checks.

#include "numeric/check.h"

#include <cstdio>
#include <cstdlib>

namespace impulse::detail {

void check_failed(const char* condition, const char* file, int line) {
    std::fprintf(stderr, "impulse: invariant failed: %s (%s:%d)\n", condition, file, line);
    std::fflush(stderr);
    std::abort();
}

}  // namespace impulse::detail
