// SPDX-License-Identifier: Apache-2.0
// Rendering a scene: one simulator and kernel per layer, layers summed into one float frame.

#include <cmath>
#include <cstdlib>
#include <filesystem>
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

Theory layer_theory(const LayerConfig& layer) {
    // A shaped layer has the target marginal's moments (Lewis 1986 §4).
    if (layer.marginal) return {layer.marginal->target().mean(), layer.marginal->target().variance()};
    // Campbell's theorem: Var = lambda E[a^2] int h^2, times (1/T) int w^2 dt for a process
    // with births at beta = lambda / T and a temporal envelope w (design.md §1).
    const kernels::Kernel k(layer.kernel);
    const auto& p = layer.process;
    double v = p.intensity * sim::amplitude_second_moment(p.amplitude) * k.integral_sq();
    if (p.lifetime_s > 0) v *= sim::envelope_sq_integral(p.envelope, p.lifetime_s) / p.lifetime_s;
    return {layer.mean, v * layer.gain * layer.gain};
}

Theory scene_theory(const Scene& scene) {
    Theory t;
    for (const auto& l : scene.layers) {
        const Theory lt = layer_theory(l);
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
        S.sims.emplace_back(l.process, l.flow, timing, l.kernel.radius);
    }
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
                                    S.sims[i].birth_region(S.camera->estimate_region(i, v)));
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
    const Theory t = scene_theory(s);
    const double sd = std::sqrt(t.variance);
    return {t.mean - 3.0 * sd, t.mean + 3.0 * sd};
}

void Renderer::render(int64_t frame, render::Frame& out, const render::EvalOptions& options) {
    State& S = *m_state;
    const auto& o = S.scene.output;
    out.resize(o.width, o.height);
    const double t = (std::llround(o.start_s * o.fps) + frame) / o.fps;
    const render::View view = S.scene.camera.view(o.width, o.height, t);
    double mean = 0.0;
    for (size_t i = 0; i < S.sims.size(); ++i) {
        sim::Impulses& imp = S.impulses[i];
        S.sims[i].impulses_at(frame, S.camera->region(i, view, t), imp);
        const auto& layer = S.scene.layers[i];
        if (layer.gain != 1.0)
            for (auto& w : imp.weight) w = static_cast<float>(w * layer.gain);
        if (S.marginals[i]) {  // shaped (Lewis 1986 §4): its own field, through g, then added
            S.scratch.resize(o.width, o.height);
            S.camera->accumulate(i, imp, view, t, S.scratch, options);
            S.marginals[i]->apply(S.scratch.data, layer.mean);
            for (size_t p = 0; p < out.data.size(); ++p) out.data[p] += S.scratch.data[p];
            continue;
        }
        S.camera->accumulate(i, imp, view, t, out, options);
        mean += layer.mean;
    }
    if (mean != 0.0)
        for (auto& v : out.data) v = static_cast<float>(v + mean);
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
