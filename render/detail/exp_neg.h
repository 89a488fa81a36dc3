// SPDX-License-Identifier: Apache-2.0
#pragma once
// The polynomial exp of the per-ISA loop files (render/eval_loops.inc, render/persp_loops.inc),
// written once. Each loop file is compiled once per instruction set, so the function lives in an
// anonymous namespace: every translation unit keeps its own copy built for its own ISA (one
// inline function shared by them could be merged by the linker into a single ISA's code).

#include <cstring>

namespace impulse::render::detail {
namespace {

/// exp(x) for x <= 0 in float, vectorisable and independent of the C library (so every
/// machine rounds alike): x = n ln2 + f, 2^n from the exponent bits, e^f by a degree-7 Taylor
/// polynomial on |f| <= ln2/2 (truncation error < 3e-9 relative). Returns 0 below -87.
[[gnu::always_inline]] inline float exp_neg(float x) {
    const float xc = x < -87.0f ? -87.0f : x;
    const float n = static_cast<float>(static_cast<int>(xc * 1.44269504088896341f - 0.5f));
    const float f = (xc - n * 0.693145751953125f) - n * 1.42860682030941723212e-6f;
    float p = 1.0f / 5040.0f;
    p = p * f + 1.0f / 720.0f;
    p = p * f + 1.0f / 120.0f;
    p = p * f + 1.0f / 24.0f;
    p = p * f + 1.0f / 6.0f;
    p = p * f + 0.5f;
    p = p * f + 1.0f;
    p = p * f + 1.0f;
    // Below -87 the scale is 0 and p (in [0.7, 1.5]) times it +0: the select on the integer
    // bits rather than on the result keeps the loops around this function vectorisable (GCC
    // does not if-convert two selects on one condition); the same bits as returning 0.
    const int bits = x < -87.0f ? 0 : (static_cast<int>(n) + 127) << 23;
    float scale;
    std::memcpy(&scale, &bits, sizeof scale);
    return p * scale;
}

}  // namespace
}  // namespace impulse::render::detail
