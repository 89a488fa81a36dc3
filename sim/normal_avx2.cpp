// SPDX-License-Identifier: Apache-2.0
// Box–Muller from our own ln and cos, four lanes per register (this file is compiled with
// -mavx2, no FMA): sim/normal.cpp's steps lane by lane, in the same order, so the same bits.
// Four registers per step are independent, which hides the divide's and the square root's
// latency.

#include <immintrin.h>

#include "sim/normal.h"

namespace impulse::sim::detail {

namespace {

using namespace normal_poly;

__m256d add(__m256d a, __m256d b) { return _mm256_add_pd(a, b); }
__m256d mul(__m256d a, __m256d b) { return _mm256_mul_pd(a, b); }
__m256d set(double a) { return _mm256_set1_pd(a); }

/// log_of (sim/normal.cpp) of four positive normal doubles.
__m256d log_of(__m256d u) {
    const __m256i bits = _mm256_castpd_si256(u);
    // The biased exponent b as the double 2^52 + b (its bits are those of 2^52 with b in the
    // low mantissa bits), then e = b - 1023 exactly: AVX2 has no int64 -> double conversion.
    const __m256d magic = _mm256_castsi256_pd(_mm256_set1_epi64x(0x4330000000000000ll));
    const __m256d biased = _mm256_castsi256_pd(
        _mm256_or_si256(_mm256_srli_epi64(bits, 52), _mm256_castpd_si256(magic)));
    __m256d e = _mm256_sub_pd(biased, set(4503599627370496.0 + 1023.0));
    __m256d m = _mm256_castsi256_pd(
        _mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi64x(0x000FFFFFFFFFFFFFll)),
                        _mm256_set1_epi64x(0x3FF0000000000000ll)));
    const __m256d high = _mm256_cmp_pd(m, set(kSqrt2), _CMP_GE_OQ);
    m = _mm256_blendv_pd(m, mul(m, set(0.5)), high);
    e = _mm256_blendv_pd(e, add(e, set(1.0)), high);
    const __m256d f = _mm256_sub_pd(m, set(1.0));
    const __m256d s = _mm256_div_pd(f, add(set(2.0), f));
    const __m256d z = mul(s, s);
    __m256d q = set(kLogQ[8]);
    for (int j = 7; j >= 0; --j) q = add(mul(q, z), set(kLogQ[j]));
    const __m256d s2 = add(s, s);
    return add(mul(e, set(kLn2Hi)), add(mul(e, set(kLn2Lo)), add(s2, mul(s2, mul(z, q)))));
}

/// cos_2pi (sim/normal.cpp) of four v in [0, 1].
__m256d cos_2pi(__m256d v) {
    const __m256d a =
        _mm256_blendv_pd(v, _mm256_sub_pd(set(1.0), v), _mm256_cmp_pd(v, set(0.5), _CMP_GT_OQ));
    const __m256d d = _mm256_sub_pd(set(0.25), a);
    const __m256d z = mul(d, d);
    __m256d p = set(kSin[10]);
    for (int n = 9; n >= 0; --n) p = add(mul(p, z), set(kSin[n]));
    return mul(d, p);
}

/// Four normals.
__m256d normal4(const double* u, const double* v) {
    const __m256d r = _mm256_sqrt_pd(mul(set(-2.0), log_of(_mm256_loadu_pd(u))));
    return mul(r, cos_2pi(_mm256_loadu_pd(v)));
}

void store4(float* out, __m256d a) { _mm_storeu_ps(out, _mm256_cvtpd_ps(a)); }
void store4(double* out, __m256d a) { _mm256_storeu_pd(out, a); }

template <typename T>
void normals(size_t n, const double* u, const double* v, T* out) {
    size_t j = 0;
    for (; j + 16 <= n; j += 16) {
        const __m256d a = normal4(u + j, v + j), b = normal4(u + j + 4, v + j + 4);
        const __m256d c = normal4(u + j + 8, v + j + 8), d = normal4(u + j + 12, v + j + 12);
        store4(out + j, a);
        store4(out + j + 4, b);
        store4(out + j + 8, c);
        store4(out + j + 12, d);
    }
    for (; j + 4 <= n; j += 4) store4(out + j, normal4(u + j, v + j));
    if (j == n) return;
    // The last one to three through the same lanes, padded with u = 1, v = 0.
    double pu[4] = {1.0, 1.0, 1.0, 1.0}, pv[4] = {0.0, 0.0, 0.0, 0.0};
    T po[4];
    for (size_t k = 0; j + k < n; ++k) pu[k] = u[j + k], pv[k] = v[j + k];
    store4(po, normal4(pu, pv));
    for (size_t k = 0; j + k < n; ++k) out[j + k] = po[k];
}

}  // namespace

void normals_from_uniforms_avx2(size_t n, const double* u, const double* v, float* out) {
    normals(n, u, v, out);
}

void normals_from_uniforms_avx2(size_t n, const double* u, const double* v, double* out) {
    normals(n, u, v, out);
}

}  // namespace impulse::sim::detail
