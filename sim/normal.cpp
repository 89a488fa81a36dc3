// SPDX-License-Identifier: Apache-2.0
// Box–Muller from our own ln and cos, scalar (see sim/normal.h for why). Every step is the one
// sim/normal_avx2.cpp does lane by lane, in the same order.

#include "sim/normal.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "numeric/rng.h"

namespace impulse::sim::detail {

namespace {

using namespace normal_poly;

/// ln u for a positive normal double u.
double log_of(double u) {
    // u = m 2^e with m in [sqrt(1/2), sqrt(2)), so ln u = e ln 2 + ln m; e and m exactly from
    // the bits, without a branch (the offset trick of musl's log.c): the bits of a positive
    // double grow with it, and those of sqrt(1/2) 2^e are kSqrtHalfBits + e 2^52, so
    // e = floor((bits - kSqrtHalfBits) / 2^52) and m's bits are the rest + kSqrtHalfBits.
    const uint64_t bits = std::bit_cast<uint64_t>(u) + (kOneBits - kSqrtHalfBits);
    const double e = static_cast<double>(static_cast<int64_t>(bits >> 52) - 1023);
    const double m = std::bit_cast<double>((bits & kMantissaBits) + kSqrtHalfBits);
    const double f = m - 1.0;  // exact (Sterbenz): m in [1/2, 2]
    const double s = f / (2.0 + f);
    const double z = s * s;
    const double s2 = s + s;
    // e ln 2 = e kLn2Hi (exact) + e kLn2Lo; the small parts are added first.
    return e * kLn2Hi + (e * kLn2Lo + (s2 + s2 * (z * log_series(z))));
}

/// cos(2 pi v) for v in [0, 1].
double cos_2pi(double v) {
    // cos(2 pi v) = cos(2 pi a) with a = min(v, 1 - v) in [0, 1/2], = sin(2 pi d) with
    // d = 1/4 - a in [-1/4, 1/4]. Both subtractions are exact where the result is small
    // (Sterbenz), so the relative error holds near the zeros v = 1/4, 3/4 too.
    const double a = std::min(v, 1.0 - v);
    const double d = 0.25 - a;
    return d * sin_series(d * d);
}

}  // namespace

double normal_from_uniforms(double u, double v) {
    // Box–Muller (1958): sqrt(-2 ln u) cos(2 pi v) is N(0, 1) for independent uniforms u, v.
    return std::sqrt(-2.0 * log_of(u)) * cos_2pi(v);
}

void NormalBatch::run(float* out) const {
    const size_t n = m_u.size();
    if (numeric::cpu_has_avx2()) {
        normals_from_uniforms_avx2(n, m_u.data(), m_v.data(), out);
        return;
    }
    for (size_t j = 0; j < n; ++j)
        out[j] = static_cast<float>(normal_from_uniforms(m_u[j], m_v[j]));
}

}  // namespace impulse::sim::detail
