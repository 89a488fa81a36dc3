// SPDX-License-Identifier: Apache-2.0
#pragma once
// Invariant checks (docs/contributing.md "Invariants"). An invariant is what the code assumes
// and no input can break: an index in range, sizes that agree, a variance that is not negative.
// Bad input is never checked this way: it gets its one-line error (numeric/errors.h).
//
// IMPULSE_CHECK(cond) is always on: for invariants whose failure would write wrong bytes
// silently, where the test costs nothing beside the work around it. IMPULSE_DCHECK(cond) is on
// where IMPULSE_DCHECKS is defined (Debug builds and the sanitized and fuzzing builds,
// scripts/sanitized_build.sh) and compiled out of release builds: its condition is not
// evaluated, so release frames keep their bits. A failed check prints one line, "impulse:
// invariant failed: COND (FILE:LINE)", and aborts: a broken invariant is a bug, and the
// sanitizers and libFuzzer report an abort as a crash with its stack.

namespace impulse::detail {
[[noreturn]] void check_failed(const char* condition, const char* file, int line);
}  // namespace impulse::detail

#define IMPULSE_CHECK(cond) \
    ((cond) ? static_cast<void>(0) : ::impulse::detail::check_failed(#cond, __FILE__, __LINE__))

#if defined(IMPULSE_DCHECKS)
#define IMPULSE_DCHECK(cond) IMPULSE_CHECK(cond)
#else
#define IMPULSE_DCHECK(cond) static_cast<void>(sizeof(!(cond)))
#endif
