// SPDX-License-Identifier: Apache-2.0
#pragma once
// The channels of a frame beside its field (part of impulse::scenes; included by
// scenes/scenes.h): per-layer values, exact derivatives, normals and motion vectors, and the
// names they carry in a multi-channel EXR (docs/channels.md).

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "numeric/frame.h"

namespace impulse::scenes {

struct Scene;

/// The channel names `render --channels` and `[output] channels` accept, in this order.
inline constexpr std::array<std::string_view, 5> kChannelNames = {"value", "dx", "dy", "normal",
                                                                   "motion"};

/// Which channels to compute.
struct ChannelSet {
    bool value = false;   ///< the composite field and each visible layer's own
    bool dx = false, dy = false;  ///< df/dx, df/dy, composite and per layer
    bool normal = false;  ///< tangent-space normals of the height relief * f
    bool motion = false;  ///< forward and backward motion vectors, pixels per frame
    bool gradient() const { return dx || dy || normal; }
    bool any() const { return value || dx || dy || normal || motion; }
};

/// The set named by a comma-separated list ("value,dx,dy"). Throws ValueError naming `what`
/// (the flag or key) for an empty or unknown name, with the nearest valid one.
ChannelSet parse_channels(const std::string& list, const std::string& what);
/// The same for a list of names (a scene's [output] channels).
ChannelSet parse_channels(const std::vector<std::string>& names, const std::string& what);

/// One frame's channels (Renderer::render_channels). Frames not asked for stay empty.
struct FrameChannels {
    numeric::Frame value;               ///< the composite field (Renderer::render's)
    numeric::Frame dx, dy;              ///< composite df/dx, df/dy, field units per pixel
    std::vector<size_t> layers;         ///< the visible layers, in order
    std::vector<std::string> layer_names;  ///< their EXR names: compose.name, else "layerN"
    std::vector<numeric::Frame> layer_value, layer_dx, layer_dy;  ///< per visible layer
    /// forward u, v and backward u, v in pixels per frame, Nuke's convention: forward is where
    /// the content of a pixel is one frame later, backward one frame earlier; u to the right,
    /// v up (docs/channels.md "Motion vectors").
    std::array<numeric::Frame, 4> motion;
};

/// Tangent-space unit normals of the height field relief * f from its derivatives (per pixel,
/// y down the rows), OpenGL's convention (x right, y up, z out of the surface):
/// N = (-relief df/dx, relief df/dy, 1) / |.|; three floats a pixel, into `xyz` (resized).
void normal_map(const numeric::Frame& dx, const numeric::Frame& dy, double relief,
                std::vector<float>& xyz);

/// The relief a normal map uses for a scene: [shading] relief at frame time t_s, or 1 (height
/// one field unit per pixel) when the scene sets none.
double normal_relief(const Scene& scene, double t_s);

/// The camera that sees frame time t_s, as the frames' metadata records it (impulse:camera):
/// "orthographic x0=X y0=Y scale=S size=WxH" (the view: texture point of the top-left corner,
/// texture units per pixel) or "perspective x=X y=Y height=H pitch=P heading=D fov=F plane=ground
/// size=WxH" (degrees), numbers to 17 significant digits.
std::string camera_text(const Scene& scene, double t_s);

}  // namespace impulse::scenes
