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
#include "output/output.h"
#include "render/render.h"
#include "scenes/channels.h"
#include "scenes/source.h"
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
    std::string compression;         ///< EXR compression, one of output::kExrCompressions
    /// [output] channels: what `render` writes besides the field (names of kChannelNames;
    /// empty: the field alone), as --channels (docs/channels.md).
    std::vector<std::string> channels;
};

/// [camera.sea]: a sea below a sky camera's horizon (docs/perspective.md §9). Each pixel below
/// the horizon reflects its ray at a wavy sea `depth` below the camera and sees the cloud deck
/// along the reflected ray (rendered by a mirror camera), Fresnel-weighted (Schlick) against the
/// water's own colour.
struct SeaConfig {
    bool enabled = false;
    double depth = 2.0;         ///< the sea's distance below the camera, texture units, > 0
    double roughness = 0.05;    ///< rms slope of the waves, in [0, 0.5] (0: a mirror)
    double wavelength = 6.0;    ///< longest wave, texture units, > 0; 8 waves down to 0.08 of it
    double wind_deg = 0.0;      ///< direction the waves travel, degrees on the plane (as heading)
    float color[3] = {0.02f, 0.09f, 0.15f};  ///< the water's colour where it reflects little
    /// The mirror camera's picture: its height as a fraction of the frame's, in [1/8, 1], but
    /// no fewer rows than mirror_min_height (nor more than the frame's). The reflection is seen
    /// through waves and a reflectance of 0.02-0.3, so at 1080p half size (a quarter of the
    /// pixels, looked up bilinearly) does not show; in small frames the mirror's own pixels would.
    double mirror_resolution = 0.5;
    int mirror_min_height = 540;  ///< rows, >= 1
};

/// [camera]: an orthographic (default) or perspective view of the texture plane, and the
/// anti-aliasing by band-limited kernels (docs/scenes.md "[camera]").
struct CameraConfig {
    enum class Type { Orthographic, Perspective };
    Type type = Type::Orthographic;
    // orthographic
    numeric::Keyframed center_x, center_y;  ///< texture point at the frame centre (default: size/2)
    numeric::Keyframed zoom = 1.0;          ///< pixels per texture unit, > 0
    // perspective (scenes/camera_config.cpp)
    numeric::Keyframed position_x, position_y;  ///< the camera's foot on the plane (default: size/2)
    numeric::Keyframed altitude = 100.0;    ///< key `height`: distance from the plane, texture units, > 0
    numeric::Keyframed pitch = 20.0;        ///< degrees below (ground) / above (sky) the horizon, [-90, 90]
    numeric::Keyframed heading = 0.0;       ///< degrees on the plane: 0 looks towards -y, 90 towards +x
    numeric::Keyframed fov = 60.0;          ///< vertical field of view, degrees, in (0, 180)
    render::Plane plane = render::Plane::Ground;
    // anti-aliasing
    enum class AntiAliasMode { Auto, Blend, Nearest, Off };
    /// auto: on for perspective cameras, and for orthographic ones that zoom below 1 at some key.
    AntiAliasMode antialias = AntiAliasMode::Auto;
    double filter = 0.5;       ///< pixel filter standard deviation in pixels, > 0
    double cutoff = 0.01;      ///< fade to the mean below this fraction of the sd, in (0, 0.5]
    bool anisotropic = true;   ///< false: isotropic levels from the footprint's major axis
    SeaConfig sea;             ///< [camera.sea] (perspective sky cameras only)
    // motion blur (docs/motion_blur.md)
    double shutter = 0.0;      ///< fraction of the frame interval the shutter is open, [0, 1]
    /// When the shutter opens, in frame intervals from the frame time, in [-1, 1]: key
    /// shutter_offset = "center" (-shutter/2, the default), "start" (0: opening at the frame),
    /// "end" (-shutter: closing at it) or a number.
    double shutter_open = 0.0;
    /// Sub-step error bound: each impulse's blurred kernel within this fraction of its peak
    /// amplitude, in (0, 1].
    double shutter_error = 1e-3;

    /// The view at time t for a frame of the given size.
    render::View view(int width, int height, double t_s) const;
    /// The perspective camera at time t (type Perspective).
    render::PerspectiveCamera perspective(int width, int height, double t_s) const;
    /// Whether frames go through the kernel pyramid.
    bool antialiased() const;
    /// The anti-aliasing options for the renderer.
    render::AntiAlias antialias_options() const;
    /// The shutter at `fps` frames a second for impulses of kernel `k`: open over
    /// [t + shutter_open / fps, t + (shutter_open + shutter) / fps], sub-steps from
    /// shutter_error and the kernel's curvature (docs/motion_blur.md).
    sim::Shutter shutter_at(double fps, const kernels::KernelCurvature& k) const;
};

/// [limits]: refuse requests that would exhaust memory or time.
struct Limits {
    double max_impulses = 5e7;    ///< live impulses per frame, all layers
    double max_memory_mib = 8192; ///< estimated peak memory of one frame
    /// Pixel evaluations of a perspective frame's near field, per layer (the sum of its
    /// impulses' pixel boxes), checked on every frame before they are evaluated.
    double max_pixel_evaluations = 1e10;
    /// Flow integration steps of the first frame, all layers (Renderer::estimated_flow_steps):
    /// each impulse is moved from its birth, so a long lifetime at a high rate is slow to start.
    double max_flow_steps = 1e10;
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
    numeric::Keyframed amount = 0.0;     ///< texture units per standard deviation of the sources, >= 0
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
    numeric::Keyframed opacity = 1.0;    ///< weight of the layer in its blend, in [0, 1]
    /// Over: alpha = opacity * smoothstep(lo, hi, value), value = the layer's own field; absent:
    /// alpha = opacity.
    std::optional<std::array<double, 2>> alpha;
    std::optional<WarpConfig> warp;
    std::optional<LayerOrientation> orientation;  ///< process.orientation is then Field
    std::vector<size_t> flow_sources;  ///< layers streaming this layer's flow (type = "layer")
};

/// A keyframed field of a layer's kernel: kernel.*field = value(t) (docs/scenes.md "Keyframes").
struct KernelKey {
    double kernels::KernelParams::*field = nullptr;
    numeric::Keyframed value;
};

/// A keyframed parameter of a layer's target marginal: params.*field = value(t).
struct MarginalKey {
    double kernels::MarginalParams::*field = nullptr;
    numeric::Keyframed value;
};

/// [layer.scale] (docs/scenes.md "Kernel scale fields"): a factor s(x, t) by which each impulse's
/// kernel is scaled at the impulse's position at the frame time, with amplitude 1/s so the
/// variance stays the layer's (render::accumulate). Deterministic and thread-safe.
class ScaleField {
public:
    virtual ~ScaleField() = default;
    /// s at the n points (x[i], y[i]) at layer time t_s, into s[i].
    virtual void scales(double t_s, size_t n, const double* x, const double* y,
                        float* s) const = 0;
    /// The largest s anywhere at any time (the simulator's support radius is R times it).
    virtual double max_scale() const = 0;
    /// The smallest s anywhere at any time (the finest kernel: what the lattice rule follows).
    virtual double min_scale() const = 0;
};

/// One [[layer]]. Its keyframed parameters are evaluated at the layer time (layer_time).
struct LayerConfig {
    /// What the layer draws: null, the impulse process described by the fields below (kernel,
    /// process, density, flow); else a field from another synthesizer (scenes/source.h), and
    /// of the fields below only mean, gain, marginal and compose apply.
    std::shared_ptr<const LayerSource> source;
    kernels::KernelParams kernel;  ///< the kernel; keyframed fields hold their value at t = 0
    std::vector<KernelKey> kernel_keys;  ///< keyframed kernel fields; empty: a fixed kernel
    /// intensity: the largest live intensity over time, density / kernel area (births are
    /// thinned down from it by process.density_scale when density or kernel area vary).
    sim::ProcessConfig process;
    numeric::Keyframed density = 16.0;  ///< expected live impulses per kernel area, > 0
    numeric::Keyframed mean = 0.0;      ///< constant added to the layer
    numeric::Keyframed gain = 1.0;      ///< amplitude scale
    std::shared_ptr<sim::Flow> flow;  ///< null: no motion
    /// The velocities (vx, vy in texture units per second, keyframed) of the uniform terms among
    /// the layer's [[layer.flow]] tables: they carry the whole layer rigidly, which the analysis'
    /// time correlation through a window follows (docs/stationarity.md); other terms are not in it.
    std::vector<std::pair<numeric::Keyframed, numeric::Keyframed>> uniform_flows;
    /// Distribution shaping g = F_y^-1(F_x(.)) of the layer's values (Lewis 1986 §4); null:
    /// none. Built with F_x per marginal_cdf at t = 0; the Renderer rebuilds it per frame when
    /// marginal_keys or the unshaped layer's law vary in time.
    std::shared_ptr<const kernels::MarginalTransform> marginal;
    std::vector<MarginalKey> marginal_keys;  ///< keyframed parameters of the target
    /// F_x of the marginal: the shot-noise law (impulse layers' default), Gaussian (source
    /// layers' default), or empirical (the Renderer measures it on a calibration render of the
    /// layer at frame 0).
    kernels::SourceCdf marginal_cdf = kernels::SourceCdf::ShotNoise;
    /// Shot-noise F_x with a fixed kernel: the kernel's value law, computed once at load.
    std::shared_ptr<const kernels::KernelValueLaw> kernel_values;
    /// Set when `precorrect = true` replaced `kernel` by the ITAM-corrected kernel (so the shaped
    /// layer has the original kernel's spectrum): what it achieved. process.intensity and
    /// cell_size still refer to the original kernel.
    std::shared_ptr<const kernels::PrecorrectionReport> precorrection;
    Composition compose;  ///< blend, opacity, visibility, warp, orientation source
    /// [layer.scale]: each impulse's kernel scaled by s(x, t); null: the kernel's own size.
    std::shared_ptr<const ScaleField> scale;
    /// [layer.dispersion] (scenes/dispersion_config.cpp): Omega, the rate in rad/s at which the
    /// Gabor carrier advances on its envelope; the layer's weights are multiplied by
    /// cos(Omega t), its quadrature twin's (carrier_quadrature, kernel phase + pi/2) by
    /// -sin(Omega t). 0: no dispersion.
    double carrier_rate = 0.0;
    bool carrier_quadrature = false;

    /// The kernel at layer time t_s: `kernel` with the keyframed fields evaluated.
    kernels::KernelParams kernel_at(double t_s) const;
    /// The largest support radius over time (seeding cells and culling use it).
    double max_radius() const;
    /// The largest kernel scale of the scale field (1 without one): the impulses' support
    /// reaches max_radius() * max_scale().
    double max_scale() const { return scale ? scale->max_scale() : 1.0; }
    double min_scale() const { return scale ? scale->min_scale() : 1.0; }
    /// The marginal's target parameters at layer time t_s (marginal must be set).
    kernels::MarginalParams marginal_at(double t_s) const;
    /// The weight of the carrier's quadrature component at layer time t_s (1 without
    /// dispersion): cos(carrier_rate t), or -sin(carrier_rate t) for the twin.
    double carrier_weight(double t_s) const;
    /// Whether density, mean, gain, the kernel or the marginal vary in time.
    bool keyframed() const;
    /// The time at which the layer's keys are evaluated for frame time t_s: t_s, wrapped into
    /// [0, loop) in a looped layer (as its flow's time is).
    double layer_time(double t_s) const;
};

/// [shading] numbers that may vary in time; the values at t = 0 are in Scene::shading.
struct ShadingKeys {
    numeric::Keyframed relief = 0.0, light_azimuth = 135.0, light_elevation = 35.0, ambient = 0.25;
};

/// A picture size in pixels (render's --size; {0, 0}: none).
struct OutputSize {
    int width = 0, height = 0;
};

/// A volume scene's content (scenes/volume_scene.h).
struct VolumeSceneConfig;

/// [render]: how frames are evaluated (docs/multirate.md).
struct RenderConfig {
    /// rms error allowed to multi-rate evaluation, as a fraction of each layer's sd, in
    /// [0, render::kMaxLatticeTolerance]; the default 0.005 (render::kRecommendedLatticeTolerance)
    /// with the spectrum kept at every frequency an 8-bit frame shows (render/lattice.h); 0:
    /// every impulse at every pixel (direct evaluation), bit for bit.
    double tolerance = 0.005;
};

struct Scene {
    std::string path;  ///< file it came from ("" for a string)
    uint64_t seed = 0; ///< the scene-wide seed (top-level `seed`, `--seed`)
    OutputConfig output;
    CameraConfig camera;
    Limits limits;
    RenderConfig render;
    std::vector<LayerConfig> layers;
    /// Set for a volume scene (then `layers` is empty and the Renderer refuses it).
    std::shared_ptr<const VolumeSceneConfig> volume;
    output::Shading shading;  ///< [shading]: how the field becomes display colour (at t = 0)
    ShadingKeys shading_keys;  ///< its keyframed numbers (shading_at evaluates them)
    /// [shading.transform]: marble or wood, applied to the summed field by Renderer::render
    /// (type None: the field as it is).
    output::FieldTransform transform;
    std::string hash;  ///< FNV-1a of the scene text, included files and overrides, hex
    /// The `size` it was loaded at (render's --size) when that is not the file's own
    /// output.size; {0, 0} otherwise (recorded in the frames' metadata as impulse:size).
    OutputSize resized;
    std::vector<std::string> warnings;  ///< accepted but suspicious values, one line each

    /// Time of frame `frame` (0-based) in seconds: (start_s fps + frame) / fps.
    double frame_time(int64_t frame) const;
    /// Layer `layer`'s time at frame `frame`: the frame time, wrapped into [0, loop) in whole
    /// frames for a looped layer (so frame loop fps repeats frame 0 bit for bit).
    double layer_time(size_t layer, int64_t frame) const;
    /// The shading at frame time t_s (keyframed numbers evaluated).
    output::Shading shading_at(double t_s) const;
};

/// Derive a layer's process.intensity (density / kernel area, the largest over time),
/// process.density_scale (the thinning when density or the kernel area vary in time) and
/// process.cell_size (the largest kernel radius) from its density and kernel. The loader does
/// it; call it after building or changing a layer in code. Throws ValueError for an invalid
/// kernel.
void prepare_layer(LayerConfig& layer);

/// Load a scene file, applying `--set key=value` overrides (dotted paths, array elements by
/// index: "layer.0.kernel.radius=8"). Throws SceneError with "file:line:col: key = value:
/// expected ..." on any problem, including unknown keys (with the nearest valid name).
///
/// `size` (the CLI's --size) renders the scene's own view at another resolution: the same
/// texture region, kernels, flows and regions in the same texture units, a picture with
/// size.width x size.height pixels. An orthographic camera's zoom (pixels per texture unit) is
/// scaled by size.height / output height, keeping the vertical extent as a perspective
/// camera's vertical fov does (another aspect ratio shows more or less at the sides); centres
/// that default to the middle of the frame stay where the scene's own size puts them. {0, 0} or
/// the scene's own size: nothing changes (same bits). `--set output.size` crops instead.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {},
                 OutputSize size = {});
/// Same for scene text; `name` stands in for the file name in messages.
Scene load_scene_string(std::string_view text, const std::string& name,
                        const std::vector<std::string>& overrides = {}, OutputSize size = {});

/// At frame time t_s: for a source layer mean(t) + gain(t) mean_s and gain(t)^2 var_s from the
/// source's theory; for an impulse layer mean(t) and gain(t)^2 E[a^2] int h_t^2 (lambda / T) int_0^T s(t - a)
/// w(a)^2 da, s the birth thinning (process.density_scale; 1 when the rate is constant), so
/// a keyframed density acts through the births of the last lifetime. A shaped layer has its
/// target's moments at t.
Theory layer_theory(const LayerConfig& layer, double t_s = 0.0);
/// Higher moments of an impulse layer before shaping (Campbell's cumulants, design.md §1):
/// `effective_impulses` = lambda (int h^2)^2 / int h^4 x E[w^2]^2 / E[w^4], the live impulses
/// that overlap at a point (the "10 or more" of Lewis 1989 §4.1: a peaked kernel's effective
/// area is much smaller than its truncation disc), and the field's excess kurtosis
/// (E[a^4] / E[a^2]^2) / effective_impulses: 3 pi / density for a still cosine layer with normal
/// amplitudes. Zero for source layers.
struct LayerMoments {
    double effective_impulses = 0.0;
    double excess_kurtosis = 0.0;
};
LayerMoments layer_moments(const LayerConfig& layer, double t_s = 0.0);
/// The composed result's mean and variance at frame time t_s: the visible layers blended in
/// order, each independent of the others (exact for add and multiply; max, min and over with an
/// alpha range in the Gaussian approximation, see docs/scenes.md "Composition"). Sums add means
/// and variances.
Theory scene_theory(const Scene& scene, double t_s = 0.0);
/// The same with the camera's motion blur (docs/motion_blur.md "Theory"): each impulse layer's
/// variance times motion_blur_variance_factor. The display mapping keeps scene_theory, so a
/// shutter does not change a frame's exposure.
Theory blurred_scene_theory(const Scene& scene, double t_s = 0.0);

/// Motion blur's effect on an impulse layer's second-order statistics (docs/motion_blur.md
/// "Theory"): every kernel replaced by its mean along a straight path b = v shutter / fps, v the
/// flow's velocity at the shutter's middle at 64 points over the frame's view (a uniform flow:
/// one path; others by this quadrature over the flow). The envelope's and sqrt(J)'s change over
/// the shutter are neglected.
struct MotionBlur {
    std::vector<std::array<double, 2>> paths;  ///< distinct b_p in texture units; empty: no blur
    std::vector<double> weight;                ///< each path's share of the points (sum 1)
    /// |H_b|^2 / |H|^2 = mean_p sinc^2(pi k . b_p), k in cycles per texture unit.
    double spectrum_factor(double kx, double ky) const;
    /// spectrum_factor's angular mean over |k| = rho.
    double radial_factor(double rho) const;
    /// Var_b / Var = mean_p 2 int_0^1 (1 - s) C(s b_p) ds / C(0), C the autocorrelation of `k`.
    double variance_factor(const kernels::Kernel& k) const;
};
/// Layer `layer`'s motion blur at frame time t_s (no paths without [camera] shutter, for a
/// source layer, a still one or one without flow).
MotionBlur layer_motion_blur(const Scene& scene, size_t layer, double t_s = 0.0);
/// layer_motion_blur's variance_factor for the layer's kernel at t_s (1 without blur).
double motion_blur_variance_factor(const Scene& scene, size_t layer, double t_s = 0.0);

/// True when the frame is the plain sum of layers (every layer visible, added at opacity 1,
/// unwarped; source layers only where they state a spectrum, LayerSource::no_spectrum_reason):
/// what the spectral theory of `impulse analyze` covers.
bool is_sum_of_layers(const Scene& scene);

/// Linear water waves of wavenumber k (radians per unit) under `gravity` over `depth` (<= 0:
/// deep water): omega^2 = g k tanh(k h), group speed d omega / dk.
struct WaveDispersion {
    double omega = 0.0;        ///< radians per second
    double group_speed = 0.0;  ///< texture units per second
};
WaveDispersion dispersion_relation(double k, double gravity, double depth);

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
