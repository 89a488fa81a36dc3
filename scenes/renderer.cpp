// SPDX-License-Identifier: Apache-2.0
// Rendering a scene: one simulator and kernel per layer, layers summed into one float frame.

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

#include "scenes/camera_detail.h"
#include "scenes/marginal.h"
#include "scenes/scenes.h"
#include "util/errors.h"

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

render::Shading Scene::shading_at(double t) const {
    render::Shading s = shading;
    s.relief = shading_keys.relief.value(t);
    s.light_azimuth_deg = shading_keys.light_azimuth.value(t);
    s.light_elevation_deg = shading_keys.light_elevation.value(t);
    s.ambient = shading_keys.ambient.value(t);
    return s;
}

namespace {

/// (1/T) int_0^T s(t - a) w(a)^2 da for births thinned by s = process.density_scale (births at
/// t - a, loop-reduced as the simulator reduces them), so that Var = lambda_max E[a^2] int h^2
/// times this (Campbell's theorem for a Poisson process of rate beta(t_b) = lambda s(t_b) / T,
/// design.md §1). Without thinning it is (1/T) int w^2: 3/8 for hann, 1 for box.
double birth_weight(const sim::ProcessConfig& p, double t) {
    const double T = p.lifetime_s;
    if (!p.density_scale) return sim::envelope_sq_integral(p.envelope, T) / T;
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
        sum += p.density_scale(tb) * w * w;
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
    if (p.lifetime_s > 0) v *= birth_weight(p, t);
    const double gain = layer.gain.value(t);
    return {layer.mean.value(t), v * gain * gain};
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
    // Campbell's theorem: Var = lambda E[a^2] int h^2, times (1/T) int w^2 dt for a process
    // with births at beta = lambda / T and a temporal envelope w (design.md §1).
    return unshaped_theory(layer, t);
}

Theory scene_theory(const Scene& scene, double t_s) {
    Theory t;
    for (const auto& l : scene.layers) {
        const Theory lt = layer_theory(l, t_s);
        t.mean += lt.mean;
        t.variance += lt.variance;
    }
    return t;
}

struct Renderer::State {
    Scene scene;
    std::vector<kernels::Kernel> kernels;
    std::vector<sim::LayerSimulator> sims;
    std::vector<sim::Impulses> impulses;
    std::vector<std::shared_ptr<const kernels::MarginalTransform>> marginals;  ///< per layer
    render::Frame scratch;  ///< a shaped layer's own field
    /// Per layer, what the current kernel and marginal transfer were built from (keyframed
    /// layers rebuild them when the evaluated values change: frame independence holds because
    /// each is a pure function of the layer time).
    std::vector<kernels::KernelParams> kernel_built;
    std::vector<std::vector<double>> marginal_built;
    /// Camera-dependent evaluation: pyramids, perspective (scenes/camera_render.cpp).
    std::unique_ptr<detail::CameraPipeline> camera;
};

Renderer::Renderer(Scene scene) : m_state(std::make_unique<State>()) {
    State& S = *m_state;
    S.scene = std::move(scene);
    const auto& out = S.scene.output;
    sim::Timing timing{out.fps, std::llround(out.start_s * out.fps)};
    for (const auto& l : S.scene.layers) {
        S.kernels.emplace_back(l.kernel);
        S.kernel_built.push_back(l.kernel);
        S.sims.emplace_back(l.process, l.flow, timing, l.max_radius());
    }
    S.marginal_built.resize(S.scene.layers.size());
    S.impulses.resize(S.scene.layers.size());
    S.camera = std::make_unique<detail::CameraPipeline>(S.scene, S.kernels);
    // Refuse what would exhaust memory or time, with the estimate (design.md §4).
    const double n = estimated_impulses();
    if (n > S.scene.limits.max_impulses) {
        std::ostringstream s;
        s << S.scene.path << ": the scene needs an estimated " << n
          << " impulses per frame, over the budget of " << S.scene.limits.max_impulses
          << " (limits.max_impulses; lower density or size, or raise the limit)";
        throw BudgetError(s.str());
    }
    const double mib = estimated_memory_mib();
    if (mib > S.scene.limits.max_memory_mib) {
        std::ostringstream s;
        s << S.scene.path << ": the scene needs an estimated " << mib
          << " MiB per frame, over the budget of " << S.scene.limits.max_memory_mib
          << " MiB (limits.max_memory_mib)";
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
    const State& S = *m_state;
    double n = 0.0;
    for (size_t i = 0; i < S.sims.size(); ++i) {
        // The largest view over the animation bounds the birth region (zoom keys are extrema).
        double min_zoom = 1e300;
        for (const auto& k : S.scene.camera.zoom.keys) min_zoom = std::min(min_zoom, k.second);
        render::View v = S.scene.camera.view(S.scene.output.width, S.scene.output.height, 0.0);
        v.scale = 1.0 / min_zoom;
        n += sim::expected_impulses(S.sims[i].config(),
                                    S.sims[i].birth_region(S.camera->estimate_box(i, v)));
    }
    return n;
}

double Renderer::estimated_memory_mib() const {
    const auto& o = m_state->scene.output;
    const double pixels = double(o.width) * o.height;
    // float frame + RGB float + 16-bit conversion buffers; ~120 bytes of state per impulse
    // (two generations of the live set plus the prepared arrays).
    return (pixels * 4.0 * 6.0 + estimated_impulses() * 120.0) / (1024.0 * 1024.0);
}

render::ValueMapping Renderer::mapping() const {
    const Scene& s = m_state->scene;
    if (s.output.range) return {(*s.output.range)[0], (*s.output.range)[1]};
    if (s.transform.type != render::FieldTransform::Type::None)
        return render::transform_range(s.transform);  // the transformed values' known range
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
        std::vector<const sim::Keyframed*> ks = {&l.density, &l.mean, &l.gain};
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

void Renderer::render(int64_t frame, render::Frame& out, const render::EvalOptions& options) {
    State& S = *m_state;
    const auto& o = S.scene.output;
    out.resize(o.width, o.height);
    const double t = S.scene.frame_time(frame);
    const render::View view = S.scene.camera.view(o.width, o.height, t);
    double mean = 0.0;
    for (size_t i = 0; i < S.sims.size(); ++i) {
        sim::Impulses& imp = S.impulses[i];
        S.sims[i].impulses_at(frame, S.camera->box(i, view, t), imp);
        const auto& layer = S.scene.layers[i];
        const double tl = S.scene.layer_time(i, frame);  // the layer's keys run on its own time
        const double gain = layer.gain.value(tl);
        if (gain != 1.0)
            for (auto& w : imp.weight) w = static_cast<float>(w * gain);
        if (!layer.kernel_keys.empty()) {
            // The kernel at tl; its orientation turns every impulse instead (so the pyramid of
            // an anti-aliased layer, built once, serves it too).
            kernels::KernelParams k = layer.kernel_at(tl);
            const double turn = k.orientation - layer.kernel.orientation;
            k.orientation = layer.kernel.orientation;
            if (!same_kernel(k, S.kernel_built[i])) {
                S.kernels[i] = kernels::Kernel(k);
                S.kernel_built[i] = k;
            }
            if (turn != 0.0)
                for (auto& th : imp.theta) th = static_cast<float>(th + turn);
        }
        if (S.marginals[i]) {  // shaped (Lewis 1986 §4): its own field, through g, then added
            update_marginal(i, tl);
            S.scratch.resize(o.width, o.height);
            S.camera->accumulate(i, imp, view, t, S.scratch, options);
            S.marginals[i]->apply(S.scratch.data, layer.mean.value(tl));
            for (size_t p = 0; p < out.data.size(); ++p) out.data[p] += S.scratch.data[p];
            continue;
        }
        S.camera->accumulate(i, imp, view, t, out, options);
        mean += layer.mean.value(tl);
    }
    if (mean != 0.0)
        for (auto& v : out.data) v = static_cast<float>(v + mean);
    if (S.scene.transform.type != render::FieldTransform::Type::None) {
        // Marble and wood (Lewis 1989 §5.1) of the field in standard deviations.
        const Theory th = scene_theory(S.scene);
        render::apply_transform(S.scene.transform, view, th.mean, std::sqrt(th.variance), out);
    }
}

void Renderer::update_marginal(size_t i, double tl) {
    State& S = *m_state;
    const LayerConfig& layer = S.scene.layers[i];
    // An empirical F_x and a fixed layer keep the transfer built at load (or calibrated).
    const bool source_varies = !layer.density.is_constant() || !layer.kernel_keys.empty();
    if (layer.marginal_cdf != kernels::SourceCdf::Gaussian ||
        (layer.marginal_keys.empty() && !source_varies))
        return;
    const kernels::MarginalParams P = layer.marginal_at(tl);
    const Theory raw = unshaped_theory(layer, tl);
    std::vector<double> built = {P.a, P.b, P.rate, P.mu, P.scale, P.sigma, P.nu, raw.mean,
                                 raw.variance};
    if (built == S.marginal_built[i]) return;
    S.marginals[i] = std::make_shared<const kernels::MarginalTransform>(P, raw.mean,
                                                                        std::sqrt(raw.variance));
    S.marginal_built[i] = std::move(built);
}

std::string builtin_scene_dir() {
    if (const char* e = std::getenv("IMPULSE_SCENES_DIR")) return e;
    return IMPULSE_SCENES_DIR;
}

std::string resolve_scene(const std::string& arg) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_regular_file(arg, ec)) return arg;
    const fs::path builtin = fs::path(builtin_scene_dir()) / (arg + ".toml");
    if (arg.find('/') == std::string::npos && fs::is_regular_file(builtin, ec)) return builtin.string();
    std::string names;
    for (const auto& e : fs::directory_iterator(builtin_scene_dir(), ec))
        if (e.path().extension() == ".toml") names += (names.empty() ? "" : ", ") + e.path().stem().string();
    throw IoError(arg + ": no such scene file or built-in scene (built-in: " + names + ")");
}

}  // namespace impulse::scenes
