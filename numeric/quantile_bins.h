// SPDX-License-Identifier: Apache-2.0
#pragma once
// Equal-count quantile bins of a list of keys: what a full sort puts in each bin, for
// O(n log bins) work instead of O(n log n) (an exemplar ramp's colours by luminance).

#include <cstddef>
#include <span>
#include <vector>

namespace impulse::numeric {

/// Where bin b of `bins` equal-count bins of n sorted elements starts: n * b / bins (b = bins
/// gives n).
inline size_t quantile_bin_start(size_t n, int b, int bins) { return n * size_t(b) / size_t(bins); }

/// A permutation of the indices 0..n-1 of `key` in which each bin's stretch,
/// [quantile_bin_start(b), quantile_bin_start(b + 1)), holds the indices a full sort by
/// (key, index) puts there, in some order, and every bin's start the very index a full sort
/// puts there (so a bin of no elements may read the one at its start). Keys must be finite (a
/// NaN has no place in an order); -0 and +0 are one key. Throws impulse::ValueError for 2^32
/// keys or more.
std::vector<size_t> order_into_quantile_bins(std::span<const float> key, int bins);

}  // namespace impulse::numeric
