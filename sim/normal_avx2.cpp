// SPDX-License-Identifier: Apache-2.0
// Box–Muller from our own ln and cos, four lanes per register (this file is compiled with
// -mavx2, no FMA): sim/normal.cpp's steps lane by lane, in the same order, so the same bits.
// Four registers per step are independent, which hides the divide's and the square root's
// latency.

#include "sim/normal.h"

#if defined(__AVX2__)
#include <immintrin.h>

namespace impulse::sim::detail {

namespace {

using namespace normal_poly;

__m256d add(__m256d a, __m256d b) { return _mm256_add_pd(a, b); }
__m256d mul(__m256d a, __m256d b) { return _mm256_mul_pd(a, b); }
__m256d set(double a) { return _mm256_set1_pd(a); }

/// Four lanes as the polynomial templates of sim/normal.h want them.
struct Lanes {
    explicit Lanes(double a) : v(set(a)) {}
    explicit Lanes(__m256d a) : v(a) {}
    __m256d v;
};
Lanes operator+(Lanes a, Lanes b) { return Lanes(add(a.v, b.v)); }
Lanes operator*(Lanes a, Lanes b) { return Lanes(mul(a.v, b.v)); }

/// log_of (sim/normal.cpp) of four positive normal doubles.
__m256d log_of(__m256d u) {
    const __m256i bits = _mm256_add_epi64(_mm256_castpd_si256(u),
                                          _mm256_set1_epi64x(int64_t(kOneBits - kSqrtHalfBits)));
    // e + 1023 as the double 2^52 + e + 1023 (its bits are those of 2^52 with e + 1023 in the
    // low mantissa bits), then e exactly: AVX2 has no int64 -> double conversion.
    const __m256i magic = _mm256_set1_epi64x(0x4330000000000000ll);
    const __m256d biased = _mm256_castsi256_pd(_mm256_or_si256(_mm256_srli_epi64(bits, 52), magic));
    const __m256d e = _mm256_sub_pd(biased, set(4503599627370496.0 + 1023.0));
    const __m256d m = _mm256_castsi256_pd(
        _mm256_add_epi64(_mm256_and_si256(bits, _mm256_set1_epi64x(int64_t(kMantissaBits))),
                         _mm256_set1_epi64x(int64_t(kSqrtHalfBits))));
    const __m256d f = _mm256_sub_pd(m, set(1.0));
    const __m256d s = _mm256_div_pd(f, add(set(2.0), f));
    const __m256d z = mul(s, s);
    const __m256d q = log_series(Lanes(z)).v;
    const __m256d s2 = add(s, s);
    return add(mul(e, set(kLn2Hi)), add(mul(e, set(kLn2Lo)), add(s2, mul(s2, mul(z, q)))));
}

/// cos_2pi (sim/normal.cpp) of four v in [0, 1].
__m256d cos_2pi(__m256d v) {
    const __m256d a = _mm256_min_pd(v, _mm256_sub_pd(set(1.0), v));
    const __m256d d = _mm256_sub_pd(set(0.25), a);
    return mul(d, sin_series(Lanes(mul(d, d))).v);
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
#else  // not x86-64 (arm64): cpu_has_avx2() is false, so this is never called (numeric/cpu.h)
#include <cstdlib>

void impulse::sim::detail::normals_from_uniforms_avx2(size_t, const double*, const double*, float*) {
    std::abort();
}
void impulse::sim::detail::normals_from_uniforms_avx2(size_t, const double*, const double*,
                                                      double*) {
    std::abort();
}
#endif
