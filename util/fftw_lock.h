// SPDX-License-Identifier: Apache-2.0
#pragma once
// One process-wide lock for FFTW's planner. fftw_plan_* and fftw_destroy_plan are not
// thread-safe (whatever the flags, FFTW_ESTIMATE included: they share the planner's global
// state); fftw_execute is. An inline function's static local is a single object across the
// program, so every library that plans FFTs can take the same lock.

#include <mutex>

namespace impulse {

/// The mutex every FFTW planner call (plan creation and destruction) must hold.
inline std::mutex& fftw_planner_mutex() {
    static std::mutex m;
    return m;
}

}  // namespace impulse
