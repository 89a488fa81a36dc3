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

/// [camera]: an orthographic (default) or perspective view of the texture plane, and the
/// anti-aliasing by band-limited kernels (docs/scenes.md "[camera]").
struct CameraConfig {
    enum class Type { Orthographic, Perspective };
    Type type = Type::Orthographic;
    // orthographic
    sim::Keyframed center_x, center_y;  ///< texture point at the frame centre (default: size/2)
    sim::Keyframed zoom = 1.0;          ///< pixels per texture unit, > 0
    // perspective (scenes/camera_config.cpp)
    sim::Keyframed position_x, position_y;  ///< the camera's foot on the plane (default: size/2)
    sim::Keyframed altitude = 100.0;    ///< key `height`: distance from the plane, texture units, > 0
    sim::Keyframed pitch = 20.0;        ///< degrees below (ground) / above (sky) the horizon, [-90, 90]
    sim::Keyframed heading = 0.0;       ///< degrees on the plane: 0 looks towards -y, 90 towards +x
    sim::Keyframed fov = 60.0;          ///< vertical field of view, degrees, in (0, 180)
    render::Plane plane = render::Plane::Ground;
    // anti-aliasing
    enum class AntiAliasMode { Auto, Blend, Nearest, Off };
    /// auto: on for perspective cameras, and for orthographic ones that zoom below 1 at some key.
    AntiAliasMode antialias = AntiAliasMode::Auto;
    double filter = 0.5;       ///< pixel filter standard deviation in pixels, > 0
    double cutoff = 0.01;      ///< fade to the mean below this fraction of the sd, in (0, 0.5]
    bool anisotropic = true;   ///< false: isotropic levels from the footprint's major axis

    /// The view at time t for a frame of the given size.
    render::View view(int width, int height, double t_s) const;
    /// The perspective camera at time t (type Perspective).
    render::PerspectiveCamera perspective(int width, int height, double t_s) const;
    /// Whether frames go through the kernel pyramid.
    bool antialiased() const;
    /// The anti-aliasing options for the renderer.
    render::AntiAlias antialias_options() const;
};

/// [limits]: refuse requests that would exhaust memory or time.
struct Limits {
    double max_impulses = 5e7;    ///< live impulses per frame, all layers
    double max_memory_mib = 8192; ///< estimated peak memory of one frame
};

/// How a layer enters the picture: its blend onto the result of the layers before it
/// (docs/scenes.md "Composition").
enum class Blend { Add, Multiply, Max, Min, Over };
inline constexpr std::array<std::string_view, 5> kBlendNames = {"add", "multiply", "max", "min",
                                                                 "over"};

/// A domain warp: the layer's field is looked up at x + amount(t) (z_x(x), z_y(x)), z the
/// standardised values (v - mean) / sd of two source layers (Campbell mean and sd).
struct WarpConfig {
    std::array<size_t, 2> source{};  ///< layers giving the x and y displacement (may be equal)
    sim::Keyframed amount = 0.0;     ///< texture units per standard deviation of the sources, >= 0
};

/// Kernel rotation from another layer's field at each impulse's position at the frame time.
struct LayerOrientation {
    size_t source = 0;
    bool level_lines = false;  ///< false: along the gradient; true: along the level lines
};

/// A layer's part in the composition and the layers it reads.
struct Composition {
    std::string name;                ///< "" when unnamed
    bool visible = true;             ///< false: rendered only as a source for other layers
    Blend blend = Blend::Add;
    sim::Keyframed opacity = 1.0;    ///< weight of the layer in its blend, in [0, 1]
    /// Over: alpha = opacity * smoothstep(lo, hi, value), value = the layer's own field; absent:
    /// alpha = opacity.
    std::optional<std::array<double, 2>> alpha;
    std::optional<WarpConfig> warp;
    std::optional<LayerOrientation> orientation;  ///< process.orientation is then Field
    std::vector<size_t> flow_sources;  ///< layers streaming this layer's flow (type = "layer")
};

/// One [[layer]].
struct LayerConfig {
    kernels::KernelParams kernel;
    sim::ProcessConfig process;  ///< intensity derived from density / kernel area
    double density = 16.0;       ///< expected live impulses per kernel area
    double mean = 0.0;           ///< constant added to the layer
    double gain = 1.0;           ///< amplitude scale
    std::shared_ptr<sim::Flow> flow;  ///< null: no motion
    /// Distribution shaping g = F_y^-1(F_x(.)) of the layer's values (Lewis 1986 §4); null:
    /// none. Built with the Gaussian F_x of the unshaped layer's closed-form mean and variance.
    std::shared_ptr<const kernels::MarginalTransform> marginal;
    /// F_x of the marginal: Gaussian, or empirical (the Renderer measures it on a calibration
    /// render of the layer at frame 0).
    kernels::SourceCdf marginal_cdf = kernels::SourceCdf::Gaussian;
    /// Set when `precorrect = true` replaced `kernel` by the ITAM-corrected kernel (so the shaped
    /// layer has the original kernel's spectrum): what it achieved. process.intensity and
    /// cell_size still refer to the original kernel.
    std::shared_ptr<const kernels::PrecorrectionReport> precorrection;
    Composition compose;  ///< blend, opacity, visibility, warp, orientation source
};

struct Scene {
    std::string path;  ///< file it came from ("" for a string)
    uint64_t seed = 0; ///< the scene-wide seed (top-level `seed`, `--seed`)
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
/// The composed result's mean and variance: the visible layers blended in order, each independent
/// of the others (exact for add and multiply; max, min and over with an alpha range in the
/// Gaussian approximation, see docs/scenes.md "Composition"). Sums add means and variances.
Theory scene_theory(const Scene& scene);
/// True when the frame is the plain sum of all layers (every layer visible, added at opacity 1,
/// unwarped): what the spectral theory of `impulse analyze` covers.
bool is_sum_of_layers(const Scene& scene);

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
