// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse render --channels` (internal to app/): which channels a run writes, whether its
// output can hold them, and each frame's file (docs/channels.md).

#include <string>
#include <vector>

#include "output/output.h"
#include "scenes/scenes.h"

namespace impulse::app {

/// What a run writes besides the field.
struct ChannelPlan {
    bool active = false;
    scenes::ChannelSet set;
    std::string what;                ///< "--channels LIST" or "output.channels", for messages
    std::vector<std::string> names;  ///< the file's channel names, in order
};

/// The plan for --channels `flag` (else the scene's [output] channels) written to `output`
/// (a frame's path). Throws ValueError naming the flag or key for an unknown name, a video, or
/// more channels than the format holds (PNG, TIFF, JPEG: `normal` alone, as an RGB normal map,
/// or `value` alone); nothing has been written then.
ChannelPlan plan_channels(const scenes::Scene& scene, const std::string& flag,
                          const std::string& output, bool video);

/// Writes frame `f`'s channels to `target` as `plan` says: a multi-channel EXR (R G B A, then
/// the names of docs/channels.md), or a normal map (N * 0.5 + 0.5) or the grey field.
void write_channel_frame(const scenes::Scene& scene, const ChannelPlan& plan,
                         const scenes::FrameChannels& ch, long long f, const std::string& target,
                         const output::ValueMapping& mapping, const output::Metadata& metadata);

}  // namespace impulse::app
