// SPDX-License-Identifier: Apache-2.0
#pragma once
// Option values given as text, parsed whole: a bad value is one line naming the option, the
// value and what was expected (ValueError).

#include <array>
#include <charconv>
#include <cmath>
#include <string>

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
