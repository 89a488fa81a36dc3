// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to impulse::scenes: what Renderer::render_channels asks of scenes/frame/channels.cpp.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "scenes/scenes.h"

namespace impulse::scenes::detail {

/// Throws SceneError (the scene's path, `what`: the flag or key, and the reason) when the scene
/// cannot give `set`: derivatives and normals of a perspective or filtering camera, of shaped,
/// warped, source or non-additive layers or through a transform; motion vectors of a
/// perspective camera or a source layer.
void check_channels(const Scene& scene, const ChannelSet& set, const std::string& what);

/// Forward and backward motion vectors of frame `frame` into `out` (resized): the flows of the
/// `layers` at each pixel centre, weighted by opacity^2 times each layer's variance, carried one
/// frame interval and seen by the camera at the frame before and after (scenes/channels.h).
void motion_vectors(const Scene& scene, int64_t frame, const std::vector<size_t>& layers,
                    std::array<numeric::Frame, 4>& out);

}  // namespace impulse::scenes::detail
