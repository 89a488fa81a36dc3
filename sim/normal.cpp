// SPDX-License-Identifier: Apache-2.0
// Box–Muller from our own ln and cos, scalar (see sim/normal.h for why). Every step is the one
// sim/normal_avx2.cpp does lane by lane, in the same order.

#include "sim/normal.h"

#include <bit>
#include <cmath>

#include "sim/rng.h"

namespace impulse::sim::detail {

namespace {

using namespace normal_poly;

/// ln u for a positive normal double u.
double log_of(double u) {
    // u = m 2^e with m in [sqrt(1/2), sqrt(2)): e and m from the bits, exactly (fdlibm's
    // reduction), so ln u = e ln 2 + ln m.
    const uint64_t bits = std::bit_cast<uint64_t>(u);
    double e = static_cast<double>(static_cast<int64_t>(bits >> 52) - 1023);
    double m = std::bit_cast<double>((bits & 0x000FFFFFFFFFFFFFull) | 0x3FF0000000000000ull);
    if (m >= kSqrt2) {
        m = m * 0.5;
        e = e + 1.0;
    }
    const double f = m - 1.0;  // exact (Sterbenz): m in [1/2, 2]
    const double s = f / (2.0 + f);
    const double z = s * s;
    double q = kLogQ[8];
    for (int j = 7; j >= 0; --j) q = q * z + kLogQ[j];
    const double s2 = s + s;
    // e ln 2 = e kLn2Hi (exact) + e kLn2Lo; the small parts are added first.
    return e * kLn2Hi + (e * kLn2Lo + (s2 + s2 * (z * q)));
}

/// cos(2 pi v) for v in [0, 1].
double cos_2pi(double v) {
    // cos(2 pi v) = cos(2 pi a) with a = min(v, 1 - v) in [0, 1/2], = sin(2 pi d) with
    // d = 1/4 - a in [-1/4, 1/4]. Both subtractions are exact where the result is small
    // (Sterbenz), so the relative error holds near the zeros v = 1/4, 3/4 too.
    const double a = v > 0.5 ? 1.0 - v : v;
    const double d = 0.25 - a;
    const double z = d * d;
    double p = kSin[10];
    for (int n = 9; n >= 0; --n) p = p * z + kSin[n];
    return d * p;
}

}  // namespace

double normal_from_uniforms(double u, double v) {
    // Box–Muller (1958): sqrt(-2 ln u) cos(2 pi v) is N(0, 1) for independent uniforms u, v.
    return std::sqrt(-2.0 * log_of(u)) * cos_2pi(v);
}

void NormalBatch::run(float* out) const {
    const size_t n = m_u.size();
    if (cpu_has_avx2()) {
        normals_from_uniforms_avx2(n, m_u.data(), m_v.data(), out);
        return;
    }
    for (size_t j = 0; j < n; ++j)
        out[j] = static_cast<float>(normal_from_uniforms(m_u[j], m_v[j]));
}

}  // namespace impulse::sim::detail
