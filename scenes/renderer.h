// SPDX-License-Identifier: Apache-2.0
#pragma once
// The scene renderer: frame f of a scene into a float buffer, and where scenes are found.
// Part of impulse::scenes (scenes/scenes.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scenes/scene.h"

namespace impulse::scenes {

/// Renders frames of a scene. Frame f is a pure function of (scene, f): rendering frames in
/// order reuses particle state, rendering any frame alone integrates from birth, with the
/// same bits.
class Renderer {
public:
    explicit Renderer(Scene scene);
    ~Renderer();
    Renderer(Renderer&&) noexcept;
    const Scene& scene() const;
    /// The float field of frame `frame` (0-based) into `out` (resized): the sum of the layers,
    /// through the scene's transform when it has one.
    void render(int64_t frame, render::Frame& out, const render::EvalOptions& options = {});
    /// Frame `frame`'s channels (docs/channels.md): the field as render gives it (always), and
    /// as `set` asks, each visible layer's own field, the exact df/dx and df/dy (composite and
    /// per layer; render::accumulate_gradient at the pixel centres) and forward and backward
    /// motion vectors. Deterministic as render. Throws SceneError naming `what` (the flag or
    /// key) when the scene cannot give them (perspective cameras, shaped or warped layers...).
    void render_channels(int64_t frame, const ChannelSet& set, FrameChannels& out,
                         const render::EvalOptions& options = {},
                         const std::string& what = "channels");
    /// Live impulses of layer `layer` at frame `frame` (for analysis and tests).
    const sim::Impulses& impulses(size_t layer) const;
    /// Estimated live impulses per frame over all layers, and peak memory in MiB.
    double estimated_impulses() const;
    double estimated_memory_mib() const;
    /// Estimated flow integration steps of the first frame over all layers (each impulse moved
    /// from its birth: LayerSimulator::first_frame_steps); limits.max_flow_steps bounds it.
    double estimated_flow_steps() const;
    /// Value mapping for display: output.range, else the transform's range, else mean +- 3
    /// standard deviations; with keyframed layers the widest such range over the output's
    /// frames (scene_theory at the first and last frame, every key time inside, one lifetime
    /// after each, and 64 times between), so the mapping is the same in every frame.
    output::ValueMapping mapping() const;
    /// How layer `layer`'s impulses are evaluated on frame `frame`'s view (docs/multirate.md):
    /// its lattice rule (spacing 1, error 0: every impulse at every pixel); nullopt where the
    /// layer draws no impulses on the frame's view itself (a source layer, a hidden layer, the
    /// camera's pyramid or perspective).
    std::optional<render::LatticeRule> lattice(size_t layer, int64_t frame = 0);

private:
    struct State;
    std::unique_ptr<State> m_state;
};

/// Directory of the built-in scenes (set at build time, overridable with IMPULSE_SCENES_DIR).
std::string builtin_scene_dir();
/// Resolve a scene argument: an existing file, or a built-in scene name ("clouds").
std::string resolve_scene(const std::string& name_or_path);

}  // namespace impulse::scenes
