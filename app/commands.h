// SPDX-License-Identifier: Apache-2.0
#pragma once
// The commands of the `impulse` tool (internal to app/).

#include <string>
#include <vector>

namespace impulse::app {

struct RenderOptions {
    std::string scene, output, frames, size, codec;
    std::vector<std::string> sets;
    std::string seed;  ///< --seed as given ("": the scene's own); checked to be in [0, 2^63 - 1]
    int threads = 0;
    int tile = 128;
    bool resume = false;
    bool quiet = false;
};

struct InfoOptions {
    std::string scene, size;
    std::vector<std::string> sets;
};

int run_render(const RenderOptions& options);
/// A whole number of `option`'s value `text` (its digits `digits`) in [0, 2^63 - 1]; out of
/// range is an error (ValueError "OPTION TEXT: expected EXPECTED"), not clamped (strtoll and
/// CLI11 clamp).
long long whole_number(const std::string& option, const std::string& text, const std::string& digits,
                       const std::string& expected);
int run_scenes();
int run_info(const InfoOptions& options);

/// Expand a sequence pattern: "####" or "%04d" -> zero-padded frame number. Returns "" if the
/// path is not a pattern.
std::string expand_pattern(const std::string& pattern, long long frame);
/// Parse "A-B" or "A" into an inclusive range; throws ValueError.
std::pair<long long, long long> parse_frame_range(const std::string& text, long long frames);

}  // namespace impulse::app
