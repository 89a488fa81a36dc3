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

/// Four uniforms in (0, 1] for the counter (a, b, c, d) under key (seed, stream).
class CounterRng {
public:
    CounterRng(uint64_t seed, uint32_t stream) {
        m_key = {{static_cast<uint32_t>(seed),
                  static_cast<uint32_t>(seed >> 32) ^ (stream * 0x9E3779B9u)}};
    }
    std::array<double, 4> uniforms(int64_t a, int64_t b, int64_t c, uint32_t d) const {
        // The high halves of the cell indices are folded into the counter's last word
        // with the index so cells 2^32 apart do not collide.
        const uint32_t hi = static_cast<uint32_t>((a >> 32) * 0x85EBCA6Bu ^
                                                  (b >> 32) * 0xC2B2AE35u ^ (c >> 32) * 0x27D4EB2Fu);
        r123::Philox4x32::ctr_type ctr = {{static_cast<uint32_t>(a), static_cast<uint32_t>(b),
                                           static_cast<uint32_t>(c), d ^ hi}};
        const auto r = m_gen(ctr, m_key);
        return {r123::u01<double>(r[0]), r123::u01<double>(r[1]), r123::u01<double>(r[2]),
                r123::u01<double>(r[3])};
    }

private:
    r123::Philox4x32 m_gen;
    r123::Philox4x32::key_type m_key;
};

/// Stream tag (xored into the layer) of the birth-region thinning uniforms ("REGN").
inline constexpr uint32_t kRegionStream = 0x5245474Eu;

/// Poisson(mean) by inversion of one uniform u in (0, 1] (deterministic, no rejection loop).
int poisson_inverse(double mean, double u);

}  // namespace impulse::sim::detail
