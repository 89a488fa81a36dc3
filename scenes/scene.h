// SPDX-License-Identifier: Apache-2.0
#pragma once
// A scene as typed configuration: output, camera, limits, layers, shading (docs/scenes.md).
// Part of impulse::scenes (scenes/scenes.h).

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
    // perspective (scenes/language/camera_config.cpp)
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
    /// [layer.dispersion] (scenes/language/dispersion_config.cpp): Omega, the rate in rad/s at which the
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

}  // namespace impulse::scenes
