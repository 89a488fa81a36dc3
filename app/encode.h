// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse encode`: assemble a finished EXR sequence (the frames of a render farm) into a video
// with the display mapping each frame records (impulse:display), as `impulse render -o X.mp4`
// would have made it; a sequence with gaps or with frames of another scene is refused, named.

#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace impulse::app {

/// Options of `impulse encode`, as given ("": from the frames' metadata).
struct EncodeOptions {
    std::string input;   ///< the sequence pattern, e.g. frames/f_####.exr
    std::string output;  ///< the video (.mp4 .mov .mkv .webm)
    std::string
        frames;  ///< "A-B": the frames that must all be present (default: first to last found)
    std::string codec, fps, crf, preset;  ///< default: the scene's (impulse:encoder, impulse:fps)
    bool quiet = false;
};

/// Adds the `encode` subcommand to `app`, filling `options`; returns it.
CLI::App* add_encode(CLI::App& app, EncodeOptions& options);

/// Checks every frame's header (present, same scene and size, its own frame number, a display
/// mapping) before encoding anything; then decodes, shades and encodes frame by frame, written
/// to a temporary renamed into place. Throws ValueError or IoError (one line); nothing is
/// written then.
int run_encode(const EncodeOptions& options);

/// "3, 7-9, 12" for ascending frame numbers (runs joined; at most `limit` items, then "...").
std::string frame_list(const std::vector<long long>& frames, size_t limit = 8);

}  // namespace impulse::app
