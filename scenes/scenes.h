// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::scenes — scene files (TOML) turned into typed configuration, and the scene
// renderer: the C++ API a program uses to render frame f of a scene into a float buffer.
// The schema is documented in docs/scenes.md.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "kernels/kernels.h"
#include "render/render.h"
#include "sim/sim.h"

namespace impulse::scenes {

/// [output]: what is written.
struct OutputConfig {
    int width = 512, height = 512;   ///< pixels, 1 .. 32768
    int64_t frames = 1;              ///< number of frames, >= 1
    double fps = 30.0;               ///< frames per second, > 0
    double start_s = 0.0;            ///< time of frame 0, a multiple of 1/fps
    std::string codec = "auto";      ///< auto | h264 | prores | ffv1 | vp9
    int crf = 18;                    ///< video quality (h264 0..51, vp9 0..63)
    std::string preset = "medium";   ///< x264 preset
    std::optional<std::array<double, 2>> range;  ///< value -> display mapping; default mean +- 3 sd
    int bits = 8;                    ///< 8 or 16 bits per channel for PNG/TIFF
};

/// [camera]: orthographic view of the texture plane.
struct CameraConfig {
    sim::Keyframed center_x, center_y;  ///< texture point at the frame centre (default: size/2)
    sim::Keyframed zoom = 1.0;          ///< pixels per texture unit, > 0
    /// The view at time t for a frame of the given size.
    render::View view(int width, int height, double t_s) const;
};

/// [limits]: refuse requests that would exhaust memory or time.
struct Limits {
    double max_impulses = 5e7;    ///< live impulses per frame, all layers
    double max_memory_mib = 8192; ///< estimated peak memory of one frame
};

/// One [[layer]].
struct LayerConfig {
    kernels::KernelParams kernel;
    sim::ProcessConfig process;  ///< intensity derived from density / kernel area
    double density = 16.0;       ///< expected live impulses per kernel area
    double mean = 0.0;           ///< constant added to the layer
    double gain = 1.0;           ///< amplitude scale
    std::shared_ptr<sim::Flow> flow;  ///< null: no motion
};

struct Scene {
    std::string path;  ///< file it came from ("" for a string)
    OutputConfig output;
    CameraConfig camera;
    Limits limits;
    std::vector<LayerConfig> layers;
    render::Shading shading;  ///< [shading]: how the field becomes display colour
    std::string hash;  ///< FNV-1a of the scene text and overrides, hex
    std::vector<std::string> warnings;  ///< accepted but suspicious values, one line each
};

/// Derive a layer's process.intensity (density / kernel area) and process.cell_size from its
/// density and kernel. The loader does it; call it after building or changing a layer in code.
/// Throws ValueError for an invalid kernel.
void prepare_layer(LayerConfig& layer);

/// Load a scene file, applying `--set key=value` overrides (dotted paths, array elements by
/// index: "layer.0.kernel.radius=8"). Throws SceneError with "file:line:col: key = value:
/// expected ..." on any problem, including unknown keys (with the nearest valid name).
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});
/// Same for scene text; `name` stands in for the file name in messages.
Scene load_scene_string(std::string_view text, const std::string& name,
                        const std::vector<std::string>& overrides = {});

/// Closed-form statistics of a layer (Campbell's theorem, design.md §1).
struct Theory {
    double mean = 0.0;
    double variance = 0.0;
};
Theory layer_theory(const LayerConfig& layer);
/// Sum over layers (independent layers add).
Theory scene_theory(const Scene& scene);

/// Renders frames of a scene. Frame f is a pure function of (scene, f): rendering frames in
/// order reuses particle state, rendering any frame alone integrates from birth, with the
/// same bits.
class Renderer {
public:
    explicit Renderer(Scene scene);
    ~Renderer();
    Renderer(Renderer&&) noexcept;
    const Scene& scene() const;
    /// The float field of frame `frame` (0-based) into `out` (resized).
    void render(int64_t frame, render::Frame& out, const render::EvalOptions& options = {});
    /// Live impulses of layer `layer` at frame `frame` (for analysis and tests).
    const sim::Impulses& impulses(size_t layer) const;
    /// Estimated live impulses per frame over all layers, and peak memory in MiB.
    double estimated_impulses() const;
    double estimated_memory_mib() const;
    /// Value mapping for display: output.range, or mean +- 3 standard deviations.
    render::ValueMapping mapping() const;

private:
    struct State;
    std::unique_ptr<State> m_state;
};

/// Directory of the built-in scenes (set at build time, overridable with IMPULSE_SCENES_DIR).
std::string builtin_scene_dir();
/// Resolve a scene argument: an existing file, or a built-in scene name ("clouds").
std::string resolve_scene(const std::string& name_or_path);

}  // namespace impulse::scenes
