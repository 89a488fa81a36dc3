// SPDX-License-Identifier: Apache-2.0
// Philox4x32-10 on sixteen counters at a time (this file is compiled with -mavx2). The rounds
// are Random123's (philox.h: _philox4x32round, _philox4x32bumpkey), lane by lane; two chains of
// eight lanes per step, and steps independent of each other, hide the multiplies' latency.

#include "numeric/rng.h"

#if defined(__AVX2__)
#include <immintrin.h>

namespace impulse::numeric {

namespace {

/// (hi, lo) of the 32 x 32 -> 64 bit products a[j] * m in every lane.
void mulhilo(__m256i a, __m256i m, __m256i& hi, __m256i& lo) {
    const __m256i even = _mm256_mul_epu32(a, m);                         // lanes 0, 2, 4, 6
    const __m256i odd = _mm256_mul_epu32(_mm256_srli_epi64(a, 32), m);  // lanes 1, 3, 5, 7
    hi = _mm256_blend_epi32(_mm256_srli_epi64(even, 32), odd, 0xAA);
    lo = _mm256_blend_epi32(even, _mm256_slli_epi64(odd, 32), 0xAA);
}

struct Lanes {
    __m256i w[4];
};

void philox_round(Lanes& c, __m256i k0, __m256i k1) {
    const __m256i m0 = _mm256_set1_epi32(static_cast<int>(0xD2511F53u));
    const __m256i m1 = _mm256_set1_epi32(static_cast<int>(0xCD9E8D57u));
    __m256i hi0, lo0, hi1, lo1;
    mulhilo(c.w[0], m0, hi0, lo0);
    mulhilo(c.w[2], m1, hi1, lo1);
    c = {{_mm256_xor_si256(_mm256_xor_si256(hi1, c.w[1]), k0), lo1,
          _mm256_xor_si256(_mm256_xor_si256(hi0, c.w[3]), k1), lo0}};
}

Lanes load(const uint32_t* const in[4], size_t j) {
    Lanes l;
    for (int i = 0; i < 4; ++i) l.w[i] = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(in[i] + j));
    return l;
}

void store(const Lanes& l, uint32_t* const out[4], size_t j) {
    for (int i = 0; i < 4; ++i) _mm256_storeu_si256(reinterpret_cast<__m256i*>(out[i] + j), l.w[i]);
}

}  // namespace

void philox4x32_avx2(const uint32_t key[2], size_t n, const uint32_t* const in[4],
                     uint32_t* const out[4]) {
    for (size_t j = 0; j < n; j += 16) {
        Lanes a = load(in, j), b = load(in, j + 8);
        uint32_t k0 = key[0], k1 = key[1];
        for (int r = 0; r < 10; ++r) {
            if (r > 0) k0 += 0x9E3779B9u, k1 += 0xBB67AE85u;
            const __m256i vk0 = _mm256_set1_epi32(static_cast<int>(k0));
            const __m256i vk1 = _mm256_set1_epi32(static_cast<int>(k1));
            philox_round(a, vk0, vk1);
            philox_round(b, vk0, vk1);
        }
        store(a, out, j);
        store(b, out, j + 8);
    }
}

}  // namespace impulse::numeric
#else  // not x86-64 (arm64): cpu_has_avx2() is false, so this is never called (numeric/cpu.h)
#include <cstdlib>

void impulse::numeric::philox4x32_avx2(const uint32_t*, size_t, const uint32_t* const*,
                                       uint32_t* const*) {
    std::abort();
}
#endif
