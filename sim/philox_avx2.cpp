// SPDX-License-Identifier: Apache-2.0
// Philox4x32-10 on sixteen counters at once (this file is compiled with -mavx2). The rounds are
// Random123's (philox.h: _philox4x32round, _philox4x32bumpkey), lane by lane; two independent
// chains of eight lanes hide the multiplies' latency.

#include <immintrin.h>

#include "sim/rng.h"

namespace impulse::sim::detail {

namespace {

/// (hi, lo) of the 32 x 32 -> 64 bit products a[j] * m in every lane.
void mulhilo(__m256i a, __m256i m, __m256i& hi, __m256i& lo) {
    const __m256i even = _mm256_mul_epu32(a, m);                         // lanes 0, 2, 4, 6
    const __m256i odd = _mm256_mul_epu32(_mm256_srli_epi64(a, 32), m);  // lanes 1, 3, 5, 7
    hi = _mm256_blend_epi32(_mm256_srli_epi64(even, 32), odd, 0xAA);
    lo = _mm256_blend_epi32(even, _mm256_slli_epi64(odd, 32), 0xAA);
}

struct Ctr {
    __m256i c0, c1, c2, c3;
};

void round(Ctr& c, __m256i k0, __m256i k1) {
    const __m256i m0 = _mm256_set1_epi32(static_cast<int>(0xD2511F53u));
    const __m256i m1 = _mm256_set1_epi32(static_cast<int>(0xCD9E8D57u));
    __m256i hi0, lo0, hi1, lo1;
    mulhilo(c.c0, m0, hi0, lo0);
    mulhilo(c.c2, m1, hi1, lo1);
    c = {_mm256_xor_si256(_mm256_xor_si256(hi1, c.c1), k0), lo1,
         _mm256_xor_si256(_mm256_xor_si256(hi0, c.c3), k1), lo0};
}

}  // namespace

void philox4x32_x16_avx2(const uint32_t key[2], uint32_t w0, uint32_t w1, uint32_t w2, uint32_t d0,
                         uint32_t step, uint32_t hi, uint32_t out[4][16]) {
    // d = (d0 + j step) ^ hi in 32-bit lanes wraps exactly as the scalar uint32_t does.
    const __m256i j = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i vstep = _mm256_set1_epi32(static_cast<int>(step));
    const __m256i vhi = _mm256_set1_epi32(static_cast<int>(hi));
    const __m256i da = _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(d0)),
                                        _mm256_mullo_epi32(j, vstep));
    const __m256i db = _mm256_add_epi32(da, _mm256_slli_epi32(vstep, 3));
    const __m256i c0 = _mm256_set1_epi32(static_cast<int>(w0));
    const __m256i c1 = _mm256_set1_epi32(static_cast<int>(w1));
    const __m256i c2 = _mm256_set1_epi32(static_cast<int>(w2));
    Ctr a{c0, c1, c2, _mm256_xor_si256(da, vhi)}, b{c0, c1, c2, _mm256_xor_si256(db, vhi)};
    uint32_t k0 = key[0], k1 = key[1];
    for (int r = 0; r < 10; ++r) {
        if (r > 0) k0 += 0x9E3779B9u, k1 += 0xBB67AE85u;
        const __m256i vk0 = _mm256_set1_epi32(static_cast<int>(k0));
        const __m256i vk1 = _mm256_set1_epi32(static_cast<int>(k1));
        round(a, vk0, vk1);
        round(b, vk0, vk1);
    }
    const __m256i words[2][4] = {{a.c0, a.c1, a.c2, a.c3}, {b.c0, b.c1, b.c2, b.c3}};
    for (int h = 0; h < 2; ++h)
        for (int i = 0; i < 4; ++i)
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(out[i] + 8 * h), words[h][i]);
}

}  // namespace impulse::sim::detail
