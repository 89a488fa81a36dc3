// SPDX-License-Identifier: Apache-2.0
#pragma once
// The commands of the `impulse` tool (internal to app/): render (app/render.cpp), scenes and info
// (app/info.cpp), and what they share.

#include <string>
#include <vector>

namespace impulse::scenes {
struct Scene;
struct OutputSize;
}

namespace impulse::app {

struct RenderOptions {
    std::string scene, output, frames, size, crop, codec;
    std::string channels;  ///< --channels LIST ("": the scene's output.channels, if any)
    std::vector<std::string> sets;
    std::string seed;  ///< --seed as given ("": the scene's own); checked to be in [0, 2^63 - 1]
    int threads = 0;
    int tile = 128;
    bool resume = false;
    bool quiet = false;
};

struct InfoOptions {
    std::string scene, size, crop;
    std::vector<std::string> sets;
};

int run_render(const RenderOptions& options);
/// The scene `impulse render` with `options` renders (--set, --crop, --seed, --codec and --size
/// applied), its warnings printed on stderr. Throws as the loader.
scenes::Scene load_render_scene(const RenderOptions& options);
/// A whole number of `option`'s value `text` (its digits `digits`) in [0, 2^63 - 1]; out of
/// range is an error (ValueError "OPTION TEXT: expected EXPECTED"), not clamped (strtoll and
/// CLI11 clamp).
long long whole_number(const std::string& option, const std::string& text, const std::string& digits,
                       const std::string& expected);
/// --size or --crop `text` "WxH" in [1, 32768]^2 ({0, 0} when empty); ValueError naming
/// `option` otherwise.
scenes::OutputSize parse_size(const std::string& option, const std::string& text);
/// The scene overrides of --set, --crop (output.size: a window at the scene's own scale) and
/// --seed, for render and info alike.
std::vector<std::string> overrides_for(const std::vector<std::string>& sets, const std::string& crop,
                                       const std::string& seed);
int run_scenes();
int run_info(const InfoOptions& options);

/// Where the frame number goes in a sequence pattern: a run of N '#' (N digits, zero-padded; a
/// single '#' is 4 digits) or printf's "%0Nd" / "%d".
struct PatternSpot {
    bool found = false;
    size_t pos = 0, length = 0;  ///< the pattern's characters in the path
    int width = 0;               ///< digits, zero-padded (0: as many as the number has)
};
/// The one pattern in `path` (found = false if none). Throws ValueError for two patterns or a
/// width over 19 digits.
PatternSpot find_pattern(const std::string& path);
/// Expand a sequence pattern: "####" or "%04d" -> zero-padded frame number. Returns "" if the
/// path is not a pattern; throws as find_pattern.
std::string expand_pattern(const std::string& pattern, long long frame);
/// The smallest frame number whose file exists for `pattern` (a pattern in the file name), or
/// -1 when there is none.
long long first_frame_present(const std::string& pattern);
/// The frame numbers whose files exist for `pattern` (a pattern in the file name), ascending;
/// empty when there is none or the pattern is in the directory part.
std::vector<long long> frames_present(const std::string& pattern);
/// Throws IoError naming `path` when its directory does not exist or is not writable.
void ensure_directory(const std::string& path);
/// True when the scene's shading gives colour (a ramp or relief at some time), not plain grey.
bool colour_shading(const scenes::Scene& s);
/// Parse "A-B" or "A" into an inclusive range; throws ValueError.
std::pair<long long, long long> parse_frame_range(const std::string& text, long long frames);

}  // namespace impulse::app
