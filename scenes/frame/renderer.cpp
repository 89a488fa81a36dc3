// SPDX-License-Identifier: Apache-2.0
// Rendering a scene: one simulator and kernel per layer, layers summed into one float frame.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

#include "scenes/detail/camera.h"
#include "scenes/detail/channels.h"
#include "scenes/detail/compose.h"
#include "scenes/detail/marginal.h"
#include "scenes/detail/reader.h"
#include "scenes/scene_dir.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

#ifndef IMPULSE_SCENES_DIR
#define IMPULSE_SCENES_DIR "scenes"
#endif

namespace impulse::scenes {

render::View CameraConfig::view(int width, int height, double t) const {
    render::View v;
    v.width = width, v.height = height;
    v.scale = 1.0 / zoom.value(t);
    v.x0 = center_x.value(t) - 0.5 * width * v.scale;
    v.y0 = center_y.value(t) - 0.5 * height * v.scale;
    return v;
}

double Scene::frame_time(int64_t frame) const {
    return (std::llround(output.start_s * output.fps) + frame) / output.fps;
}

double Scene::layer_time(size_t layer, int64_t frame) const {
    const double loop_s = layers.at(layer).process.loop_s;
    const int64_t n = std::llround(output.start_s * output.fps) + frame;
    if (loop_s <= 0) return n / output.fps;
    // Whole frames (the loader checks loop is one), so the keys repeat bit for bit.
    const int64_t period = std::llround(loop_s * output.fps);
    return static_cast<double>(n - period * static_cast<int64_t>(std::floor(double(n) / period))) /
           output.fps;
}

output::Shading Scene::shading_at(double t) const {
    output::Shading s = shading;
    s.relief = shading_keys.relief.value(t);
    s.light_azimuth_deg = shading_keys.light_azimuth.value(t);
    s.light_elevation_deg = shading_keys.light_elevation.value(t);
    s.ambient = shading_keys.ambient.value(t);
    if (camera.sea.enabled) s.background = detail::sea_background(camera, s, t);
    if (s.filter_after) s.subpixel_sd = detail::subpixel_sd(*this, t);
    return s;
}

namespace {

/// Runs f, naming the scene and layer i in a ValueError it throws: a flow too fast for the
/// layer's max_travel is found only when a view's birth region is computed. Rethrown as a
/// SceneError, so a layer read by another (an orientation source) is not named twice.
template <class F>
decltype(auto) in_layer(const Scene& scene, size_t i, F&& f) {
    try {
        return f();
    } catch (const ValueError& e) {
        throw SceneError(scene.path + ": layer[" + std::to_string(i) + "]: " + e.what());
    }
}

/// (1/T) int_0^T s(t - a) w(a)^n da (n = 1 or 2) for births thinned by s =
/// process.density_scale (births at t - a, loop-reduced as the simulator reduces them), so that
/// Var = lambda_max E[a^2] int h^2 times the n = 2 weight and Mean = lambda_max E[a] int h times
/// the n = 1 weight (Campbell's theorem for a Poisson process of rate beta(t_b) = lambda s(t_b) /
/// T, design.md §1). Without thinning it is (1/T) int w^n: 3/8 (n = 2) and 1/2 (n = 1) for
/// hann, 1 for box.
double birth_weight(const sim::ProcessConfig& p, double t, int n = 2) {
    const double T = p.lifetime_s;
    if (!p.density_scale)
        return (n == 2 ? sim::envelope_sq_integral(p.envelope, T) : sim::envelope_integral(p.envelope, T)) / T;
    // Midpoint rule on 8192 panels: error O(h^2) where s is smooth, O(h) = 1e-4 of the
    // integral at a step key (the thinned rate jumps there).
    constexpr int kPanels = 8192;
    const double h = T / kPanels;
    double sum = 0.0;
    for (int i = 0; i < kPanels; ++i) {
        const double a = (i + 0.5) * h;
        double tb = t - a;
        if (p.loop_s > 0) tb -= std::floor(tb / p.loop_s) * p.loop_s;
        const double w = sim::envelope_weight(p.envelope, a, T);
        sum += p.density_scale(tb) * (n == 2 ? w * w : w);
    }
    return sum * h / T;
}

/// Whether two kernel parameter sets build the same kernel.
bool same_kernel(const kernels::KernelParams& a, const kernels::KernelParams& b) {
    return a.type == b.type && a.radius == b.radius && a.sigma == b.sigma &&
           a.frequency == b.frequency && a.bandwidth == b.bandwidth && a.phase == b.phase &&
           a.orientation == b.orientation && a.aspect == b.aspect && a.sampled == b.sampled;
}

/// Campbell's theorem for the layer without its marginal, at layer time t.
Theory unshaped_theory(const LayerConfig& layer, double t) {
    const kernels::Kernel k(layer.kernel_keys.empty() ? layer.kernel : layer.kernel_at(t));
    const auto& p = layer.process;
    double v = p.intensity * sim::amplitude_second_moment(p.amplitude) * k.integral_sq();
    // Positive amplitudes add lambda E[a] int h to the mean (0 for the zero-mean laws).
    double m = p.intensity * sim::amplitude_mean(p.amplitude) * k.integral();
    if (p.lifetime_s > 0) v *= birth_weight(p, t, 2), m *= birth_weight(p, t, 1);
    const double gain = layer.gain.value(t) * layer.carrier_weight(t);
    return {layer.mean.value(t) + gain * m, v * gain * gain};
}

/// A source layer without its marginal at layer time t: the source's theory through the gain.
Theory source_theory(const LayerConfig& layer, double t) {
    const Theory s = layer.source->theory(t);
    const double gain = layer.gain.value(t);
    return {layer.mean.value(t) + gain * s.mean, gain * gain * s.variance};
}

/// Bytes the source layers hold (Renderer::estimated_memory_mib): each source's tile, its
/// pyramid under a perspective camera when the layer is drawn in camera space (`rendered`) and
/// its buffers per frame (LayerSource::memory_bytes), a second frame where the gain is not 1
/// (Renderer::State::raw), and under a perspective camera the pixels' footprints, made once for
/// all source layers (two doubles and four floats a pixel: PixelFootprints).
double source_bytes(const Scene& s, const std::vector<bool>& rendered, double pixels) {
    const bool perspective = s.camera.type == CameraConfig::Type::Perspective;
    double bytes = 0.0;
    bool footprints = false;
    for (size_t i = 0; i < s.layers.size(); ++i) {
        const LayerConfig& l = s.layers[i];
        if (!l.source) continue;
        bytes += l.source->memory_bytes(pixels, perspective && rendered[i]);
        if (!(l.gain.is_constant() && l.gain.value(0.0) == 1.0)) bytes += pixels * 4.0;
        footprints = footprints || (perspective && rendered[i]);
    }
    if (footprints) bytes += pixels * double(2 * sizeof(double) + 4 * sizeof(float));
    return bytes;
}

}  // namespace

Theory layer_theory(const LayerConfig& layer, double t_s) {
    const double t = layer.layer_time(t_s);
    // A shaped layer has the target marginal's moments (Lewis 1986 §4).
    if (layer.marginal) {
        if (layer.marginal_keys.empty())
            return {layer.marginal->target().mean(), layer.marginal->target().variance()};
        const kernels::Distribution target(layer.marginal_at(t));
        return {target.mean(), target.variance()};
    }
    if (layer.source) return source_theory(layer, t);
    // Campbell's theorem: Var = lambda E[a^2] int h^2, times (1/T) int w^2 dt for a process
    // with births at beta = lambda / T and a temporal envelope w (design.md §1); Mean = lambda
    // E[a] int h, times (1/T) int w dt.
    return unshaped_theory(layer, t);
}

LayerMoments layer_moments(const LayerConfig& layer, double t_s) {
    LayerMoments m;
    if (layer.source) return m;
    const double t = layer.layer_time(t_s);
    const kernels::Kernel k(layer.kernel_keys.empty() ? layer.kernel : layer.kernel_at(t));
    const auto& p = layer.process;
    // Campbell: kappa_n = lambda E[a^n] E[w^n] int h^n, so kappa_4 / kappa_2^2 =
    // (E[a^4] / E[a^2]^2) (E[w^4] / E[w^2]^2) / (lambda (int h^2)^2 / int h^4). The last is the
    // number of live impulses within the kernel's effective area (int h^2)^2 / int h^4.
    double lambda = p.intensity;
    if (p.lifetime_s > 0) lambda *= birth_weight(p, t) / (sim::envelope_sq_integral(p.envelope, p.lifetime_s) / p.lifetime_s);
    const double area = k.integral_sq() * k.integral_sq() / k.integral_4();
    const double ea2 = sim::amplitude_second_moment(p.amplitude);
    const double wfac = p.lifetime_s > 0
                            ? sim::envelope_fourth_integral(p.envelope, p.lifetime_s) * p.lifetime_s /
                                  std::pow(sim::envelope_sq_integral(p.envelope, p.lifetime_s), 2)
                            : 1.0;
    m.effective_impulses = lambda * area / wfac;
    m.excess_kurtosis = sim::amplitude_fourth_moment(p.amplitude) / (ea2 * ea2) / m.effective_impulses;
    return m;
}

namespace {

/// The visible layers blended in order onto the empty (zero) picture, each independent of the
/// result before it, at frame time t_s; the weights at their largest over the animation (a
/// fade's range is the fully faded-in one). With `blurred`, impulse layers' variances follow the
/// camera's motion blur.
Theory composed_theory(const Scene& scene, double t_s, bool blurred) {
    Theory t;
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const LayerConfig& l = scene.layers[i];
        if (!l.compose.visible) continue;
        Theory lt = layer_theory(l, t_s);
        if (blurred && !l.marginal) lt.variance *= motion_blur_variance_factor(scene, i, t_s);
        t = detail::blend_theory(t, l, lt, l.compose.opacity.max_abs());
    }
    return t;
}

}  // namespace

Theory scene_theory(const Scene& scene, double t_s) { return composed_theory(scene, t_s, false); }

Theory blurred_scene_theory(const Scene& scene, double t_s) {
    return composed_theory(scene, t_s, true);
}

bool is_sum_of_layers(const Scene& scene) {
    for (const auto& l : scene.layers) {
        const Composition& c = l.compose;
        if (!c.visible || c.blend != Blend::Add || !c.opacity.is_constant() ||
            c.opacity.value(0.0) != 1.0 || c.warp ||
            (l.source && !l.source->no_spectrum_reason().empty()))
            return false;
    }
    return true;
}

struct Renderer::State {
    Scene scene;
    std::vector<kernels::Kernel> kernels;
    std::vector<sim::LayerSimulator> sims;
    std::vector<sim::Impulses> impulses;  ///< per layer, on the frame's view
    std::vector<std::shared_ptr<const kernels::MarginalTransform>> marginals;  ///< per layer
    /// Per layer, what the current kernel and marginal transfer were built from (keyframed
    /// layers rebuild them when the evaluated values change: frame independence holds because
    /// each is a pure function of the layer time).
    std::vector<kernels::KernelParams> kernel_built;
    std::vector<std::vector<double>> marginal_built;
    /// Per layer, the curvature of the kernel its motion blur's sub-steps follow, with that
    /// kernel (docs/motion_blur.md).
    std::vector<std::optional<std::pair<kernels::KernelParams, kernels::KernelCurvature>>>
        curvature;
    /// Camera-dependent evaluation: pyramids, perspective (scenes/camera_render.cpp).
    std::unique_ptr<detail::CameraPipeline> camera;
    /// [camera.sea]: the same layers seen by the mirror camera (scenes/sea.cpp).
    std::unique_ptr<Renderer> mirror;
    render::Frame mirror_field;

    // Composition (docs/scenes.md "Composition").
    /// The field of layers oriented by another layer's, filled before each of their evaluations.
    std::vector<std::shared_ptr<detail::LatticeOrientation>> orientations;
    std::vector<bool> warp_source;  ///< a warp reads its own field on the frame's view
    std::vector<bool> rendered;     ///< visible or read by a warp of one (for the estimates)
    std::vector<render::Frame> fields;  ///< own fields on the frame's view, this frame
    std::vector<bool> field_ready;

    /// Camera: as the camera sees the layer (pyramid, perspective); Texture: the kernel itself
    /// at the pixel centres of an orthographic view (sampled fields of a layer).
    enum class Space { Camera, Texture };
    struct Pass {
        int64_t frame;
        double t;
        const render::EvalOptions* options;
    };

    /// The layer's own field on the frame's view (computed once per frame).
    const render::Frame& main_field(size_t i, const Pass& pass, const render::View& view);
    /// The layer's own field on `v`: impulses, warp, mean or marginal (not opacity or blend).
    /// `main`: v is the frame's view in camera space, whose fields are kept for the frame.
    void field(size_t i, const Pass& pass, const render::View& v, Space space, bool main,
               render::Frame& out, sim::Impulses& impulses);
    /// Layer i's lattice rule on a view of `units_per_pixel` (docs/multirate.md), for the
    /// kernel it draws now and its finest scale; cached per kernel and scale.
    const render::LatticeRule& lattice_rule(size_t i, int64_t frame, const render::View& v,
                                            Space space);
    /// Whether layer i's impulses on a view in `space` go through a lattice: a tolerance above
    /// 0 and an orthographic view (through the camera's pyramid too, but for a scale field).
    bool multirate(size_t i, Space space) const {
        if (!(scene.render.tolerance > 0.0) || read_for_position(i) || scene.layers[i].compose.warp)
            return false;
        if (space == Space::Texture || !camera->active()) return true;
        return !camera->perspective() && !scene.layers[i].scale;
    }
    /// Whether another layer reads layer i's values as a displacement (a warp's source) or
    /// its gradient (an orientation's source): their errors move or turn that layer's kernels,
    /// and the moved layer's error is its gradient times the displacement's, not bounded by
    /// the source's own tolerance; such layers are evaluated directly.
    bool read_for_position(size_t i) const {
        if (warp_source[i]) return true;
        for (const auto& l : scene.layers)
            if (l.compose.orientation && l.compose.orientation->source == i) return true;
        return false;
    }
    /// Whether layer i is drawn through the camera's pyramid in `space`.
    bool filtered(Space space) const { return space == Space::Camera && camera->active(); }
    /// The region layer i's impulses are needed on for view v: the lattice's, or the camera's.
    numeric::Region impulse_region(size_t i, const render::View& v, Space space, const Pass& pass);
    /// Adds layer i's impulses on `v` to `out`: through the lattice, or as the camera sees them.
    void draw(size_t i, const sim::Impulses& imp, const render::View& v, Space space,
              const Pass& pass, render::Frame& out);
    struct CachedRule {
        kernels::KernelParams kernel;
        double units_per_pixel;
        bool filtered;
        render::LatticeRule rule;
    };
    std::vector<std::vector<CachedRule>> lattice_rules;  ///< per layer
    /// The sum of the layer's impulses on `v` (added to `out`).
    void raw(size_t i, const Pass& pass, const render::View& v, Space space, render::Frame& out,
             sim::Impulses& impulses);
    /// The layer's impulses covering `box`, gain applied, oriented by its source layer if any.
    void layer_impulses(size_t i, const Pass& pass, const numeric::Region& box, sim::Impulses& out);
    /// Layer i's shutter (closed without [camera] shutter) for its current kernel.
    sim::Shutter shutter(size_t i);
    /// Samples layer i's orientation source on a lattice covering the impulses of `box`.
    void orient(size_t i, const Pass& pass, const numeric::Box& box);
    /// Rebuilds layer i's marginal transfer for layer time tl when its target or source varies.
    void update_marginal(size_t i, double tl);
    /// Refuses a frame buffer of `pixels` beyond limits.max_memory_mib.
    void check_buffer(double pixels, const std::string& what) const;
    /// The texture-space boxes layer i's impulses are asked for at most over the animation
    /// (the widest view, a warp's reach): what the budget estimates measure.
    numeric::Region estimate_region(size_t i) const;
    /// The sum of `f(simulator, region)` over what a frame simulates: each rendered impulse
    /// layer over its estimate region, and the orientation source it samples where its
    /// impulses are.
    template <class F>
    double sum_simulated(F f) const;
};

template <class F>
double Renderer::State::sum_simulated(F f) const {
    double n = 0.0;
    for (size_t i = 0; i < sims.size(); ++i) {
        // A hidden layer no frame reads (a flow's stream function only) is never rendered; a
        // source layer draws no impulses.
        if (!rendered[i] || scene.layers[i].source) continue;
        const numeric::Region box = estimate_region(i);
        const Composition& c = scene.layers[i].compose;
        n += in_layer(scene, i, [&] { return f(sims[i], box); });
        if (c.orientation && !scene.layers[c.orientation->source].source) {
            const size_t j = c.orientation->source;
            const numeric::Region near = box.expanded(scene.layers[i].kernel.radius);
            n += in_layer(scene, j, [&] { return f(sims[j], near); });
        }
    }
    return n;
}

numeric::Region Renderer::State::estimate_region(size_t i) const {
    // The largest view over the animation bounds the birth region (zoom keys are extrema).
    double min_zoom = 1e300;
    for (const auto& k : scene.camera.zoom.keys) min_zoom = std::min(min_zoom, k.second);
    render::View v = scene.camera.view(scene.output.width, scene.output.height, 0.0);
    v.scale = 1.0 / min_zoom;
    numeric::Region box = camera->estimate_region(i, v);
    // A warp reads the layer up to its largest displacement beyond the view: about 5 sd of
    // the sources over a frame of a million pixels, 6 sd taken.
    const Composition& c = scene.layers[i].compose;
    if (c.warp) box = box.expanded(6.0 * c.warp->amount.max_abs());
    return box;
}

Renderer::Renderer(Scene scene) : m_state(std::make_unique<State>()) {
    State& S = *m_state;
    S.scene = std::move(scene);
    if (S.scene.volume)
        throw ValueError(S.scene.path + ": a volume scene ([volume]): render it with impulse render "
                         "(OpenVDB frames or a ray-marched preview), not the 2-D renderer");
    const auto& out = S.scene.output;
    sim::Timing timing{out.fps, std::llround(out.start_s * out.fps)};
    const size_t count = S.scene.layers.size();
    S.orientations.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const auto& l = S.scene.layers[i];
        S.kernels.emplace_back(l.kernel);
        S.kernel_built.push_back(l.kernel);
        S.curvature.emplace_back();
        sim::ProcessConfig process = l.process;
        if (l.compose.orientation) {
            S.orientations[i] =
                std::make_shared<detail::LatticeOrientation>(l.compose.orientation->level_lines);
            process.orientation_field = S.orientations[i];
        }
        try {
            S.sims.emplace_back(process, l.flow, timing, l.max_radius() * l.max_scale());
        } catch (const BudgetError& e) {  // e.g. a density beyond the sampler: name the layer
            throw BudgetError(S.scene.path + ": layer[" + std::to_string(i) + "]: " + e.what());
        }
    }
    S.marginal_built.resize(count);
    S.impulses.resize(count);
    S.fields.resize(count);
    S.field_ready.assign(count, false);
    S.warp_source.assign(count, false);
    S.rendered.assign(count, false);
    for (size_t i = 0; i < count; ++i) {
        const auto& c = S.scene.layers[i].compose;
        S.rendered[i] = c.visible;
        if (c.warp)
            for (size_t j : c.warp->source) S.warp_source[j] = true;
    }
    for (bool changed = true; changed;) {  // warp sources of rendered layers are rendered
        changed = false;
        for (size_t i = 0; i < count; ++i) {
            const auto& c = S.scene.layers[i].compose;
            if (!S.rendered[i] || !c.warp) continue;
            for (size_t j : c.warp->source)
                if (!S.rendered[j]) S.rendered[j] = changed = true;
        }
    }
    for (size_t i = 0; i < count; ++i) {
        const auto& src = S.scene.layers[i].source;
        if (src && S.rendered[i] && S.scene.camera.type == CameraConfig::Type::Perspective &&
            !src->perspective())
            throw SceneError(S.scene.path + ": layer[" + std::to_string(i) + "]: " +
                             src->no_perspective_reason());
    }
    S.camera = std::make_unique<detail::CameraPipeline>(S.scene, S.kernels);
    if (S.scene.camera.sea.enabled) {
        Scene m = S.scene;
        m.camera = detail::mirror_camera(S.scene.camera);
        const auto size = detail::mirror_size(S.scene.camera.sea, m.output.width, m.output.height);
        m.output.width = size[0], m.output.height = size[1];
        m.transform = output::FieldTransform{};  // applied once, to the sea and sky together
        S.mirror = std::make_unique<Renderer>(std::move(m));
    }
    // Refuse what would exhaust memory or time, with the estimate (design.md §4).
    const double n = estimated_impulses();
    if (n > S.scene.limits.max_impulses) {
        std::ostringstream s;
        s << S.scene.path << ": the scene needs an estimated " << n
          << " impulses per frame, over the budget of " << S.scene.limits.max_impulses
          << " (limits.max_impulses; lower density or size, or raise the limit)";
        throw BudgetError(s.str());
    }
    const double steps = estimated_flow_steps();
    if (steps > S.scene.limits.max_flow_steps) {
        std::ostringstream s;
        s << S.scene.path << ": the first frame needs an estimated " << steps
          << " flow steps (each impulse moved from its birth), over the budget of "
          << S.scene.limits.max_flow_steps
          << " (limits.max_flow_steps; lower lifetime, fps, substeps or density, or raise the limit)";
        throw BudgetError(s.str());
    }
    const double mib = estimated_memory_mib();
    if (mib > S.scene.limits.max_memory_mib) {
        std::ostringstream s;
        const double pixels = double(S.scene.output.width) * S.scene.output.height;
        const double sources = source_bytes(S.scene, S.rendered, pixels) / (1024.0 * 1024.0);
        s << S.scene.path << ": the scene needs an estimated " << mib << " MiB per frame";
        if (sources > 0.0) s << " (" << sources << " MiB of it the source layers' tiles, pyramids and buffers)";
        s << ", over the budget of " << S.scene.limits.max_memory_mib << " MiB (limits.max_memory_mib)";
        throw BudgetError(s.str());
    }
    // An empirical F_x is measured once, on a calibration render at frame 0 (frame independent).
    for (const auto& l : S.scene.layers)
        S.marginals.push_back(l.marginal && l.marginal_cdf == kernels::SourceCdf::Empirical
                                  ? detail::calibrate_marginal(l, timing)
                                  : l.marginal);
}

Renderer::~Renderer() = default;
Renderer::Renderer(Renderer&&) noexcept = default;
const Scene& Renderer::scene() const { return m_state->scene; }
const sim::Impulses& Renderer::impulses(size_t layer) const { return m_state->impulses.at(layer); }

double Renderer::estimated_impulses() const {
    return m_state->sum_simulated([](const sim::LayerSimulator& sim, const numeric::Region& r) {
        return sim::expected_impulses(sim.config(), sim.birth_region(r));
    });
}

double Renderer::estimated_flow_steps() const {
    return m_state->sum_simulated([](const sim::LayerSimulator& sim, const numeric::Region& r) {
        return sim.first_frame_steps(r);
    });
}

double Renderer::estimated_memory_mib() const {
    const State& S = *m_state;
    const auto& o = S.scene.output;
    const double pixels = double(o.width) * o.height;
    // Bytes per pixel of the larger of the CLI's two output paths (app/render.cpp):
    //  - images: two float frames (frame f + 1 renders while f is saved), the float RGB of the
    //    shading (12) and the image writer's 8- or 16-bit copy (up to 6): 26;
    //  - video: one float frame and the encoder's input picture (up to 6, 4:4:4 at 16 bits;
    //    the RGB passes through in bands of rows): at most 10, plus the encoder's own frames,
    //    which are not counted (x264 holds ~190 MiB at 3840x2160 for a short clip, more with
    //    its lookahead full).
    // ~120 bytes of state per impulse (two generations of the live set plus the prepared arrays);
    // what source layers hold (their tiles and pyramids).
    double bytes = pixels * 26.0 + estimated_impulses() * 120.0 + source_bytes(S.scene, S.rendered, pixels);
    // A flow's caches (a curl-noise or stream-function potential lattice) over the region its
    // layer's impulses are integrated in.
    for (size_t i = 0; i < S.sims.size(); ++i)
        if (S.rendered[i] && !S.scene.layers[i].source)
            bytes += in_layer(S.scene, i, [&] { return S.sims[i].flow_cache_bytes(S.estimate_region(i)); });
    // Composition: a frame per layer that is not simply added (a source layer's field is always
    // drawn into its own); a warped layer's grown frame (margin as in estimated_impulses) and its
    // two displacement frames.
    for (const auto& l : S.scene.layers) {
        const Composition& c = l.compose;
        if (c.blend != Blend::Add || !(c.opacity.is_constant() && c.opacity.value(0) == 1.0) ||
            l.marginal || c.warp || l.source)
            bytes += pixels * 4.0;
        if (c.warp) {
            const double m = 2.0 * (6.0 * c.warp->amount.max_abs() * S.scene.camera.zoom.max_abs() + 2.0);
            bytes += ((o.width + m) * (o.height + m) + 2.0 * pixels) * 4.0;
        }
    }
    return bytes / (1024.0 * 1024.0);
}

output::ValueMapping Renderer::mapping() const {
    const Scene& s = m_state->scene;
    if (s.output.range) return {(*s.output.range)[0], (*s.output.range)[1]};
    if (s.transform.type != output::FieldTransform::Type::None)
        return output::transform_range(s.transform);  // the transformed values' known range
    bool keyed = false;
    for (const auto& l : s.layers) keyed = keyed || l.keyframed();
    if (!keyed) {
        const Theory t = scene_theory(s);
        const double sd = std::sqrt(t.variance);
        return {t.mean - 3.0 * sd, t.mean + 3.0 * sd};
    }
    // The widest mean +- 3 sd over the output's frames: at the first and last frame, 64 times
    // between, and every key time (and one lifetime after it, where a density key has acted
    // through a whole lifetime of births) inside; a looped layer's keys repeat every loop.
    const double t0 = s.frame_time(0), t1 = s.frame_time(s.output.frames - 1);
    std::set<double> times = {t0, t1};
    for (int i = 1; i < 64; ++i) times.insert(t0 + (t1 - t0) * i / 64.0);
    for (const auto& l : s.layers) {
        std::vector<const numeric::Keyframed*> ks = {&l.density, &l.mean, &l.gain};
        for (const auto& k : l.kernel_keys) ks.push_back(&k.value);
        for (const auto& k : l.marginal_keys) ks.push_back(&k.value);
        const double P = l.process.loop_s;
        for (const auto* k : ks)
            for (const auto& key : k->keys)
                for (double shift : {0.0, l.process.lifetime_s}) {
                    const double t = key.first + shift;
                    if (P <= 0) {
                        if (t >= t0 && t <= t1) times.insert(t);
                        continue;
                    }
                    // Every repeat inside the frames (up to 64: the theory repeats with P too).
                    double r = t + std::ceil((t0 - t) / P) * P;
                    for (int m = 0; m < 64 && r <= t1; ++m, r += P) times.insert(r);
                }
    }
    double lo = INFINITY, hi = -INFINITY;
    for (double t : times) {
        const Theory th = scene_theory(s, t);
        const double sd = std::sqrt(th.variance);
        lo = std::min(lo, th.mean - 3.0 * sd);
        hi = std::max(hi, th.mean + 3.0 * sd);
    }
    return {lo, hi};
}

std::optional<render::LatticeRule> Renderer::lattice(size_t layer, int64_t frame) {
    State& S = *m_state;
    const LayerConfig& l = S.scene.layers.at(layer);
    if (l.source || !S.rendered[layer] || !S.multirate(layer, State::Space::Camera))
        return std::nullopt;
    const auto& o = S.scene.output;
    const double t = S.scene.frame_time(frame);
    return S.lattice_rule(layer, frame, S.scene.camera.view(o.width, o.height, t),
                          State::Space::Camera);
}

void Renderer::render(int64_t frame, render::Frame& out, const render::EvalOptions& options) {
    State& S = *m_state;
    const auto& o = S.scene.output;
    out.resize(o.width, o.height);
    const double t = S.scene.frame_time(frame);
    const render::View view = S.scene.camera.view(o.width, o.height, t);
    const State::Pass pass{frame, t, &options};
    std::fill(S.field_ready.begin(), S.field_ready.end(), false);
    // The visible layers in order onto the empty picture (docs/scenes.md "Composition").
    double mean = 0.0;  // means of the layers added straight into the frame, not yet added
    for (size_t i = 0; i < S.sims.size(); ++i) {
        const auto& layer = S.scene.layers[i];
        const Composition& c = layer.compose;
        if (!c.visible) continue;
        const double opacity = c.opacity.value(t);
        const bool warped = c.warp && c.warp->amount.value(t) != 0.0;
        if (c.blend == Blend::Add && opacity == 1.0 && !S.marginals[i] && !warped &&
            !S.warp_source[i] && !layer.source) {
            // A plain sum: impulses straight into the frame, the mean added at the end.
            sim::Impulses& imp = S.impulses[i];
            S.layer_impulses(i, pass, S.impulse_region(i, view, State::Space::Camera, pass), imp);
            S.draw(i, imp, view, State::Space::Camera, pass, out);
            mean += layer.mean.value(S.scene.layer_time(i, frame));
            continue;
        }
        const render::Frame& own = S.main_field(i, pass, view);
        if (c.blend != Blend::Add && mean != 0.0) {  // what lies under a non-additive blend
            for (auto& v : out.data) v = static_cast<float>(v + mean);
            mean = 0.0;
        }
        detail::blend(c.blend, opacity, c.alpha, own, out);
    }
    if (mean != 0.0)
        for (auto& v : out.data) v = static_cast<float>(v + mean);
    if (S.mirror) {  // the sea below the horizon: the mirror camera's deck, reflected
        S.mirror->render(frame, S.mirror_field, options);
        detail::apply_sea(S.scene.camera.perspective(o.width, o.height, t), S.scene.camera.sea,
                          S.scene.camera.filter, t, scene_theory(S.scene, t).mean, S.mirror_field, out);
    }
    if (S.scene.transform.type != output::FieldTransform::Type::None) {
        // Marble and wood (Lewis 1989 §5.1) of the field in standard deviations.
        const Theory th = scene_theory(S.scene, t);
        try {
            output::apply_transform(S.scene.transform, view, th.mean, std::sqrt(th.variance),
                                    out);
        } catch (const ValueError& e) {
            throw SceneError(S.scene.path + ": shading.transform: " + e.what());
        }
    }
}

void Renderer::render_channels(int64_t frame, const ChannelSet& set, FrameChannels& out,
                               const render::EvalOptions& options, const std::string& what) {
    State& S = *m_state;
    detail::check_channels(S.scene, set, what);
    render(frame, out.value, options);
    const auto& o = S.scene.output;
    const double t = S.scene.frame_time(frame);
    const render::View view = S.scene.camera.view(o.width, o.height, t);
    const State::Pass pass{frame, t, &options};
    out.layers.clear(), out.layer_names.clear();
    for (size_t i = 0; i < S.scene.layers.size(); ++i)
        if (S.scene.layers[i].compose.visible) {
            out.layers.push_back(i);
            const std::string& n = S.scene.layers[i].compose.name;
            out.layer_names.push_back(n.empty() ? "layer" + std::to_string(i) : n);
        }
    const size_t n = out.layers.size();
    out.layer_value.assign(set.value ? n : 0, {});
    out.layer_dx.assign(set.gradient() ? n : 0, {});
    out.layer_dy.assign(set.gradient() ? n : 0, {});
    out.dx = {}, out.dy = {};
    sim::Impulses imp;
    for (size_t k = 0; k < n; ++k) {
        const size_t i = out.layers[k];
        if (set.value) S.field(i, pass, view, State::Space::Camera, false, out.layer_value[k], imp);
        if (!set.gradient()) continue;
        // check_channels admits only added impulse layers: the composite's derivative is the
        // sum of theirs times their opacity.
        S.layer_impulses(i, pass, S.camera->region(i, view, t), imp);
        render::accumulate_gradient(S.kernels[i], imp, view, out.layer_dx[k], out.layer_dy[k],
                                    options);
        const double opacity = S.scene.layers[i].compose.opacity.value(t);
        if (k == 0) out.dx.resize(o.width, o.height), out.dy.resize(o.width, o.height);
        for (size_t p = 0; p < out.dx.data.size(); ++p) {
            out.dx.data[p] = static_cast<float>(out.dx.data[p] + opacity * out.layer_dx[k].data[p]);
            out.dy.data[p] = static_cast<float>(out.dy.data[p] + opacity * out.layer_dy[k].data[p]);
        }
    }
    if (set.gradient() && n == 0) out.dx.resize(o.width, o.height), out.dy.resize(o.width, o.height);
    for (auto& m : out.motion) m = {};
    if (set.motion) detail::motion_vectors(S.scene, frame, out.layers, out.motion);
}

const render::Frame& Renderer::State::main_field(size_t i, const Pass& pass,
                                                 const render::View& view) {
    if (!field_ready[i]) {
        field(i, pass, view, Space::Camera, true, fields[i], impulses[i]);
        field_ready[i] = true;
    }
    return fields[i];
}

void Renderer::State::field(size_t i, const Pass& pass, const render::View& v, Space space,
                            bool main, render::Frame& out, sim::Impulses& imp) {
    const LayerConfig& layer = scene.layers[i];
    const double amount = layer.compose.warp ? layer.compose.warp->amount.value(pass.t) : 0.0;
    out.resize(v.width, v.height);
    if (amount != 0.0) {
        // Domain warp: the layer at x + amount z(x), z the sources' standardised values on this
        // view. The layer is evaluated on the view grown by the largest displacement of the
        // frame (so every lookup lands inside, whatever the values) and resampled bicubically.
        std::array<std::vector<float>, 2> d;
        double largest = 0.0;
        for (int k = 0; k < 2; ++k) {
            const size_t j = layer.compose.warp->source[k];
            render::Frame local;
            sim::Impulses local_impulses;
            const render::Frame* src = &local;
            if (main)
                src = &main_field(j, pass, v);
            else
                field(j, pass, v, space, false, local, local_impulses);
            const Theory th = layer_theory(scene.layers[j], pass.t);
            const double px = amount / (std::sqrt(th.variance) * v.scale);  // pixels per sd
            d[k].resize(src->data.size());
            for (size_t p = 0; p < d[k].size(); ++p) {
                d[k][p] = static_cast<float>((src->data[p] - th.mean) * px);
                largest = std::max(largest, std::abs(double(d[k][p])));
            }
        }
        const int margin = static_cast<int>(std::ceil(largest)) + 2;  // + the bicubic's reach
        render::View grown = v;
        grown.width += 2 * margin, grown.height += 2 * margin;
        grown.x0 -= margin * v.scale, grown.y0 -= margin * v.scale;
        check_buffer(double(grown.width) * grown.height,
                     "the domain warp of layer[" + std::to_string(i) + "] (displacements up to " +
                         std::to_string(std::lround(largest * v.scale)) + " texture units)");
        render::Frame src;
        src.resize(grown.width, grown.height);
        raw(i, pass, grown, space, src, imp);
        detail::warp_resample(src, margin, d[0], d[1], out);
    } else {
        raw(i, pass, v, space, out, imp);
    }
    const double tl = scene.layer_time(i, pass.frame);  // the layer's keys run on its own time
    const double mean = layer.mean.value(tl);
    if (marginals[i]) {  // shaped (Lewis 1986 §4): through g, which adds the mean first
        update_marginal(i, tl);
        marginals[i]->apply(out.data, mean);
    } else if (mean != 0.0) {
        for (auto& x : out.data) x = static_cast<float>(x + mean);
    }
}

void Renderer::State::raw(size_t i, const Pass& pass, const render::View& v, Space space,
                          render::Frame& out, sim::Impulses& imp) {
    const LayerConfig& layer = scene.layers[i];
    if (layer.source) {  // the layer-source seam: the same in camera and texture space
        const double tl = scene.layer_time(i, pass.frame);
        const double gain = layer.gain.value(tl);
        // A perspective frame reads the source at each pixel's footprint on the plane.
        const bool perspective = space == Space::Camera &&
                                 scene.camera.type == CameraConfig::Type::Perspective;
        auto draw = [&](render::Frame& to) {
            if (perspective) {
                try {
                    return camera->add_source(*layer.source, pass.t, tl, to);
                } catch (const BudgetError& e) {  // the source's estimate, named by layer
                    throw BudgetError(scene.path + ": layer[" + std::to_string(i) + "]: " + e.what());
                }
            }
            layer.source->add(v, tl, to);
        };
        if (gain == 1.0) return draw(out);
        render::Frame f;
        f.resize(v.width, v.height);
        draw(f);
        for (size_t p = 0; p < f.data.size(); ++p)
            out.data[p] = static_cast<float>(out.data[p] + gain * f.data[p]);
        return;
    }
    layer_impulses(i, pass, impulse_region(i, v, space, pass), imp);
    draw(i, imp, v, space, pass, out);
}

const render::LatticeRule& Renderer::State::lattice_rule(size_t i, int64_t frame,
                                                        const render::View& v, Space space) {
    const double units_per_pixel = v.scale;
    const bool through_pyramid = filtered(space);
    if (lattice_rules.size() < scene.layers.size()) lattice_rules.resize(scene.layers.size());
    const LayerConfig& layer = scene.layers[i];
    // The kernel the layer draws at this time (layer_impulses turns keyed orientations on the
    // impulses instead, so the orientation stays the layer's): a pure function of the time,
    // so the rule does not depend on which frames were rendered before.
    kernels::KernelParams k = layer.kernel;
    if (!layer.kernel_keys.empty()) {
        k = layer.kernel_at(scene.layer_time(i, frame));
        k.orientation = layer.kernel.orientation;
    }
    auto& cache = lattice_rules[i];
    for (const CachedRule& c : cache)
        if (c.units_per_pixel == units_per_pixel && c.filtered == through_pyramid &&
            same_kernel(c.kernel, k))
            return c.rule;
    // The finest kernel the layer draws: its scale field's smallest scale class.
    const double r = kernels::kScaleClassRatio;
    const double s = std::pow(r, std::floor(std::log(layer.min_scale()) / std::log(r) + 1e-9));
    const kernels::Kernel finest(layer.scale ? render::scaled_kernel(k, s) : k);
    // Through the pyramid (a fixed kernel: keys are refused there but for the orientation),
    // the level the view draws.
    const kernels::Kernel& drawn = through_pyramid ? camera->filtered_kernel(i, v) : finest;
    if (cache.size() >= 8) cache.erase(cache.begin());  // keyed kernels: a few recent ones
    // The rule's working grids count in the memory limit (a quarter of it): the limit bounds
    // its time too (fuzzing runs scenes at 2 MiB).
    const double rule_bytes = 0.25 * scene.limits.max_memory_mib * 1024.0 * 1024.0;
    cache.push_back({k, units_per_pixel, through_pyramid,
                     render::choose_lattice(drawn, units_per_pixel, scene.render.tolerance, true,
                                            rule_bytes)});
    return cache.back().rule;
}

numeric::Region Renderer::State::impulse_region(size_t i, const render::View& v, Space space,
                                                const Pass& pass) {
    if (!multirate(i, space)) return space == Space::Camera ? camera->region(i, v, pass.t) : v.box();
    const render::LatticeRule& rule = lattice_rule(i, pass.frame, v, space);
    const render::View lattice = render::lattice_view(v, rule);
    if (filtered(space)) return camera->region(i, lattice, pass.t, 1.0 / rule.spacing);
    return lattice.box();
}

void Renderer::State::draw(size_t i, const sim::Impulses& imp, const render::View& v,
                           Space space, const Pass& pass, render::Frame& out) {
    const render::EvalOptions& options = *pass.options;
    if (!multirate(i, space)) {
        if (space == Space::Camera) return camera->accumulate(i, imp, v, pass.t, out, options);
        return render::accumulate(kernels[i], imp, v, out, options);
    }
    const render::LatticeRule& rule = lattice_rule(i, pass.frame, v, space);
    if (!filtered(space)) return render::accumulate_lattice(kernels[i], imp, v, rule, out, options);
    if (rule.spacing == 1) return camera->accumulate(i, imp, v, pass.t, out, options);
    // The pyramid's levels at the nodes, chosen for the pixels' footprint.
    const render::View lattice = render::lattice_view(v, rule);
    render::Frame nodes;
    nodes.resize(lattice.width, lattice.height);
    camera->accumulate(i, imp, lattice, pass.t, nodes, options, 1.0 / rule.spacing);
    render::add_reconstruction(nodes, rule, v, out);
}

void Renderer::State::layer_impulses(size_t i, const Pass& pass, const numeric::Region& box,
                                     sim::Impulses& out) {
    if (orientations[i]) orient(i, pass, box.bounds());
    const LayerConfig& layer = scene.layers[i];
    const double tl = scene.layer_time(i, pass.frame);  // the layer's keys run on its own time
    double turn = 0.0;
    if (!layer.kernel_keys.empty()) {
        // The kernel at tl; its orientation turns every impulse instead (so the pyramid of an
        // anti-aliased layer, built once, serves it too).
        kernels::KernelParams k = layer.kernel_at(tl);
        turn = k.orientation - layer.kernel.orientation;
        k.orientation = layer.kernel.orientation;
        if (!same_kernel(k, kernel_built[i])) {
            kernels[i] = kernels::Kernel(k);
            kernel_built[i] = k;
        }
    }
    in_layer(scene, i, [&] { sims[i].impulses_at(pass.frame, box, shutter(i), out); });
    const double gain = layer.gain.value(tl) * layer.carrier_weight(tl);
    if (gain != 1.0)
        for (auto& w : out.weight) w = static_cast<float>(w * gain);
    if (turn != 0.0)
        for (auto& th : out.theta) th = static_cast<float>(th + turn);
    out.scale.clear();
    if (layer.scale) {  // at each impulse's position at the frame time, as orientation fields
        out.scale.resize(out.size());
        layer.scale->scales(tl, out.size(), out.x.data(), out.y.data(), out.scale.data());
    }
}

sim::Shutter Renderer::State::shutter(size_t i) {
    const CameraConfig& c = scene.camera;
    if (c.shutter <= 0.0) return {};
    auto& known = curvature[i];
    if (!known || !same_kernel(known->first, kernels[i].params()))
        known.emplace(kernels[i].params(), kernels::kernel_curvature(kernels[i]));
    return c.shutter_at(scene.output.fps, known->second);
}

void Renderer::State::orient(size_t i, const Pass& pass, const numeric::Box& box) {
    // The source's own field (kernel itself, in texture space) on a lattice of spacing R / 8
    // whose nodes are whole multiples of the spacing, covering every impulse the simulator
    // emits for `box` (within the layer's support radius of it) with the bicubic stencil's two
    // nodes to spare.
    const size_t j = scene.layers[i].compose.orientation->source;
    const auto& src = scene.layers[j].source;
    const double h = (src ? src->correlation_length() : kernels[j].radius()) / 8.0;
    const numeric::Box b = box.expanded(scene.layers[i].kernel.radius * scene.layers[i].max_scale());
    const int64_t i0 = static_cast<int64_t>(std::floor(b.x0 / h)) - 2;
    const int64_t j0 = static_cast<int64_t>(std::floor(b.y0 / h)) - 2;
    const int64_t i1 = static_cast<int64_t>(std::floor(b.x1 / h)) + 3;
    const int64_t j1 = static_cast<int64_t>(std::floor(b.y1 / h)) + 3;
    check_buffer(double(i1 - i0 + 1) * double(j1 - j0 + 1),
                 "the orientation of layer[" + std::to_string(i) + "] sampled from layer[" +
                     std::to_string(j) + "]");
    render::View lattice;
    lattice.width = static_cast<int>(i1 - i0 + 1), lattice.height = static_cast<int>(j1 - j0 + 1);
    lattice.x0 = (double(i0) - 0.5) * h, lattice.y0 = (double(j0) - 0.5) * h;
    lattice.scale = h;
    render::Frame values;
    sim::Impulses imp;
    field(j, pass, lattice, Space::Texture, false, values, imp);
    orientations[i]->set(std::move(values), i0, j0, h);
}

void Renderer::State::check_buffer(double pixels, const std::string& what) const {
    const double mib = pixels * 4.0 / (1024.0 * 1024.0);
    if (mib > scene.limits.max_memory_mib) {
        std::ostringstream s;
        s << scene.path << ": " << what << " needs a buffer of " << mib
          << " MiB, over the budget of " << scene.limits.max_memory_mib
          << " MiB (limits.max_memory_mib)";
        throw BudgetError(s.str());
    }
}

void Renderer::State::update_marginal(size_t i, double tl) {
    const LayerConfig& layer = scene.layers[i];
    // An empirical F_x and a fixed layer keep the transfer built at load (or calibrated).
    const bool source_varies = !layer.density.is_constant() || !layer.kernel_keys.empty();
    if (layer.marginal_cdf == kernels::SourceCdf::Empirical ||
        (layer.marginal_keys.empty() && !source_varies))
        return;
    const kernels::MarginalParams P = layer.marginal_at(tl);
    const Theory raw = unshaped_theory(layer, tl);
    std::vector<double> built = {P.a, P.b, P.rate, P.mu, P.scale, P.sigma, P.nu, raw.mean,
                                 raw.variance};
    if (built == marginal_built[i]) return;
    if (layer.marginal_cdf == kernels::SourceCdf::ShotNoise)
        marginals[i] = detail::shot_noise_marginal(layer, P, tl, layer.kernel_values.get());
    else
        marginals[i] = std::make_shared<const kernels::MarginalTransform>(
            P, raw.mean, std::sqrt(raw.variance));
    marginal_built[i] = std::move(built);
}

namespace {
std::string& builtin_scene_dir_set() {
    static std::string dir;
    return dir;
}
}  // namespace

void set_builtin_scene_dir(const std::string& dir) { builtin_scene_dir_set() = dir; }

std::string builtin_scene_dir() {
    if (const char* e = std::getenv("IMPULSE_SCENES_DIR")) return e;
    if (!builtin_scene_dir_set().empty()) return builtin_scene_dir_set();
    // An installed tool whose source tree is gone: PREFIX/share/impulse/scenes beside PREFIX/bin.
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(IMPULSE_SCENES_DIR, ec)) return IMPULSE_SCENES_DIR;
    const fs::path installed = fs::read_symlink("/proc/self/exe", ec).parent_path().parent_path() /
                               "share/impulse/scenes";
    if (!ec && fs::is_directory(installed, ec)) return installed.string();
    return IMPULSE_SCENES_DIR;
}

std::string resolve_scene(const std::string& arg) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_regular_file(arg, ec)) return arg;
    const fs::path builtin = fs::path(builtin_scene_dir()) / (arg + ".toml");
    if (arg.find('/') == std::string::npos && fs::is_regular_file(builtin, ec)) return builtin.string();
    std::vector<std::string> stems;
    for (const auto& e : fs::directory_iterator(builtin_scene_dir(), ec))
        if (e.path().extension() == ".toml") stems.push_back(e.path().stem().string());
    std::sort(stems.begin(), stems.end());
    std::string names;
    for (const auto& n : stems) names += (names.empty() ? "" : ", ") + n;
    const auto near =
        arg.find('/') == std::string::npos ? detail::nearest(arg, stems) : std::nullopt;
    throw IoError(arg + ": no such scene file or built-in scene" +
                  (near ? " (did you mean \"" + *near + "\"?)" : "") + " (built-in: " + names + ")");
}

}  // namespace impulse::scenes
