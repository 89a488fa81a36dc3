// SPDX-License-Identifier: Apache-2.0
#pragma once
// Option values given as text, parsed whole: a bad value is one line naming the option, the
// value and what was expected (ValueError). The one place app/ parses numbers and sizes
// (docs/contributing.md "A subcommand"); file extensions come from output::lower_extension.

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string>
#include <vector>

#include "numeric/errors.h"

namespace impulse::app {

/// The whole of `text` as a number (finite for floating point), else ValueError
/// "option text: expected ...".
template <class T>
T parse_whole(const std::string& option, const std::string& text, const std::string& expected) {
    T v{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    bool ok = ec == std::errc() && end == text.data() + text.size() && !text.empty();
    if constexpr (std::is_floating_point_v<T>) ok = ok && std::isfinite(v);
    if (!ok) throw ValueError(option + " " + text + ": expected " + expected);
    return v;
}

/// An integer in [lo, hi], else ValueError "option text: expected an integer in [lo, hi]".
inline int parse_int(const std::string& option, const std::string& text, int lo, int hi) {
    const std::string expected = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
    const auto v = parse_whole<long long>(option, text, expected);
    if (v < lo || v > hi) throw ValueError(option + " " + text + ": expected " + expected);
    return static_cast<int>(v);
}

/// The whole numbers of a size "N", "WxH" or "WxHxD": `text` split at each 'x', every part one
/// to 18 decimal digits (no sign, no spaces). Empty when `text` is not of that form; the caller
/// checks the count and the range and words the message.
inline std::vector<long long> parse_dimensions(const std::string& text) {
    std::vector<long long> parts;
    size_t at = 0;
    while (true) {
        const size_t x = std::min(text.find('x', at), text.size());
        long long v = 0;
        const char* first = text.data() + at;
        const char* last = text.data() + x;
        const auto [end, ec] = std::from_chars(first, last, v);
        if (last - first > 18 || ec != std::errc() || end != last || v < 0 || *first == '-') return {};
        parts.push_back(v);
        if (x == text.size()) return parts;
        at = x + 1;
    }
}

/// "x,y,z": three finite numbers.
inline std::array<double, 3> parse_triple(const std::string& option, const std::string& text) {
    std::array<double, 3> v{};
    size_t at = 0;
    for (int c = 0; c < 3; ++c) {
        const size_t comma = c < 2 ? text.find(',', at) : text.size();
        if (comma == std::string::npos) throw ValueError(option + " " + text + ": expected x,y,z");
        v[c] = parse_whole<double>(option, text.substr(at, comma - at), "x,y,z (three numbers)");
        at = comma + 1;
    }
    return v;
}

}  // namespace impulse::app
