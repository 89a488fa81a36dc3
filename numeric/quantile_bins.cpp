// SPDX-License-Identifier: Apache-2.0
#include "numeric/quantile_bins.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>

#include "numeric/errors.h"

namespace impulse::numeric {
namespace {

/// A finite float's bits turned into an unsigned integer of the same order (negative floats
/// have their bits reversed, positive ones their sign bit set), in the upper half of a 64-bit
/// key whose lower half is the index: one integer comparison orders by (key, index), where a
/// pair's comparison costs several (and, under libFuzzer's comparison tracing, a callback each).
uint64_t packed(float key, size_t index) {
    const uint32_t bits = std::bit_cast<uint32_t>(key + 0.0f);  // -0 + 0 = +0: one zero
    const uint32_t ordered = (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
    return (uint64_t(ordered) << 32) | uint64_t(index);
}

/// Rearranges v[begin, end) so that each position in `at` (ascending, distinct, inside the
/// range) holds what a full sort would put there and each stretch between two of them what a
/// full sort puts there, in some order: nth_element at the middle position, then each half.
void select_positions(std::vector<uint64_t>& v, std::span<const size_t> at, size_t begin, size_t end) {
    if (at.empty()) return;
    const size_t m = at.size() / 2;
    std::nth_element(v.begin() + long(begin), v.begin() + long(at[m]), v.begin() + long(end));
    select_positions(v, at.first(m), begin, at[m]);
    select_positions(v, at.subspan(m + 1), at[m] + 1, end);
}

}  // namespace

std::vector<size_t> order_into_quantile_bins(std::span<const float> key, int bins) {
    const size_t n = key.size();
    if (n >= (size_t(1) << 32))
        throw ValueError("quantile bins of " + std::to_string(n) + " keys: expected fewer than 2^32");
    std::vector<uint64_t> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = packed(key[i], i);
    std::vector<size_t> bounds;  // each bin's start, once (bins of no element share one)
    for (int b = 0; b < bins; ++b)
        if (const size_t i0 = quantile_bin_start(n, b, bins);
            i0 < n && (bounds.empty() || i0 != bounds.back()))
            bounds.push_back(i0);
    select_positions(v, bounds, 0, n);
    std::vector<size_t> order(n);
    for (size_t i = 0; i < n; ++i) order[i] = size_t(v[i] & 0xffffffffu);
    return order;
}

}  // namespace impulse::numeric
