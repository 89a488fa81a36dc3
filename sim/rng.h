// SPDX-License-Identifier: Apache-2.0
#pragma once
// Counter-based random numbers (Random123 Philox4x32-10): a draw is a pure function of what it
// is for — (seed, stream, cell, index) — never of the order of the calls (design.md §3,
// Lewis 1989 §2.1 "internally consistent").

#include <Random123/philox.h>
#include <Random123/uniform.hpp>

#include <array>
#include <cstdint>

namespace impulse::sim::detail {

/// True when the CPU runs AVX2 code (checked once).
bool cpu_has_avx2();

/// Philox4x32-10 (Salmon et al. 2011) of the 16 counters (w0, w1, w2, (d0 + j step) ^ hi)
/// under `key`, word i of counter j into out[i][j]: the integers r123::Philox4x32 gives, as two
/// interleaved eight-lane chains (sim/philox_avx2.cpp, compiled with -mavx2; call only when
/// cpu_has_avx2()).
void philox4x32_x16_avx2(const uint32_t key[2], uint32_t w0, uint32_t w1, uint32_t w2, uint32_t d0,
                         uint32_t step, uint32_t hi, uint32_t out[4][16]);

/// Four uniforms in (0, 1] for the counter (a, b, c, d) under key (seed, stream).
class CounterRng {
public:
    CounterRng(uint64_t seed, uint32_t stream) {
        m_key = {{static_cast<uint32_t>(seed),
                  static_cast<uint32_t>(seed >> 32) ^ (stream * 0x9E3779B9u)}};
    }
    std::array<double, 4> uniforms(int64_t a, int64_t b, int64_t c, uint32_t d) const {
        r123::Philox4x32::ctr_type ctr = {{static_cast<uint32_t>(a), static_cast<uint32_t>(b),
                                           static_cast<uint32_t>(c), d ^ fold(a, b, c)}};
        return to_u01(m_gen(ctr, m_key));
    }
    /// The Philox words behind uniforms(a, b, c, d0 + j * step), word i into out[i][j], for
    /// j < 16 (u01 turns a word into its uniform): the same integers, from AVX2 on a CPU that has
    /// it (a still layer draws its candidates this way).
    void words16(int64_t a, int64_t b, int64_t c, uint32_t d0, uint32_t step,
                 uint32_t out[4][16]) const {
        const uint32_t hi = fold(a, b, c);
        if (cpu_has_avx2()) {
            const uint32_t key[2] = {m_key[0], m_key[1]};
            philox4x32_x16_avx2(key, static_cast<uint32_t>(a), static_cast<uint32_t>(b),
                                static_cast<uint32_t>(c), d0, step, hi, out);
            return;
        }
        for (uint32_t j = 0; j < 16; ++j) {
            r123::Philox4x32::ctr_type ctr = {{static_cast<uint32_t>(a), static_cast<uint32_t>(b),
                                               static_cast<uint32_t>(c), (d0 + j * step) ^ hi}};
            const auto r = m_gen(ctr, m_key);
            for (int i = 0; i < 4; ++i) out[i][j] = r[i];
        }
    }
    static double u01(uint32_t word) { return r123::u01<double>(word); }

private:
    /// The high halves of the cell indices are folded into the counter's last word with the
    /// index so cells 2^32 apart do not collide.
    static uint32_t fold(int64_t a, int64_t b, int64_t c) {
        return static_cast<uint32_t>((a >> 32) * 0x85EBCA6Bu ^ (b >> 32) * 0xC2B2AE35u ^
                                     (c >> 32) * 0x27D4EB2Fu);
    }
    static std::array<double, 4> to_u01(const r123::Philox4x32::ctr_type& r) {
        return {u01(r[0]), u01(r[1]), u01(r[2]), u01(r[3])};
    }
    r123::Philox4x32 m_gen;
    r123::Philox4x32::key_type m_key;
};

/// Stream tag (xored into the layer) of the birth-region thinning uniforms ("REGN").
inline constexpr uint32_t kRegionStream = 0x5245474Eu;

/// Poisson(mean) by inversion of one uniform u in (0, 1] (deterministic, no rejection loop).
int poisson_inverse(double mean, double u);

}  // namespace impulse::sim::detail
