// SPDX-License-Identifier: Apache-2.0
// The scene object of the Python module: rendering, shading and the closed-form spectrum.

#include "python/scene_object.h"

#include "numeric/errors.h"

namespace impulse::python {

SceneObject::SceneObject(scenes::Scene scene, std::vector<std::string> overrides)
    : m_scene(std::move(scene)), m_overrides(std::move(overrides)) {}

void SceneObject::check_frame(int64_t frame) const {
    const int64_t n = m_scene.output.frames;
    if (frame < 0 || frame >= n)
        throw ValueError("frame " + std::to_string(frame) + ": outside [0, " + std::to_string(n) +
                         ") (the scene has output.frames = " + std::to_string(n) + ")");
}

scenes::Renderer& SceneObject::renderer() {
    if (!m_renderer) m_renderer = std::make_unique<scenes::Renderer>(m_scene);
    return *m_renderer;
}

std::unique_ptr<numeric::Frame> SceneObject::render(int64_t frame) {
    check_frame(frame);
    auto out = std::make_unique<numeric::Frame>();
    const std::lock_guard<std::mutex> lock(m_mutex);
    renderer().render(frame, *out);
    return out;
}

scenes::FrameChannels SceneObject::render_channels(int64_t frame, const scenes::ChannelSet& set) {
    check_frame(frame);
    scenes::FrameChannels out;
    const std::lock_guard<std::mutex> lock(m_mutex);
    renderer().render_channels(frame, set, out, {}, "render_channels");
    return out;
}

std::vector<float> SceneObject::render_rgb(int64_t frame) {
    const std::unique_ptr<numeric::Frame> field = render(frame);
    std::vector<float> rgb;
    // The keyframed shading at the frame's time, as `impulse render` shades a PNG frame.
    output::shade(*field, mapping(), m_scene.shading_at(m_scene.frame_time(frame)), rgb);
    return rgb;
}

output::ValueMapping SceneObject::mapping() {
    const std::lock_guard<std::mutex> lock(m_mutex);
    return renderer().mapping();
}

namespace {

/// Layer `l`'s spectrum in pixel units at |k| = rho cycles per pixel: S_px(rho) = zoom^2
/// S_tex(rho zoom), a pixel being 1/zoom texture units. An impulse layer has S_tex = lambda
/// E[a^2] gain^2 (1/T int w^2) |H|^2 (Lewis 1986 eq. 4, Campbell's theorem per frequency), its
/// scale taken from layer_theory's variance over int h^2; the angular mean of |H|^2 is what a
/// radially averaged periodogram estimates.
std::optional<double> layer_spectrum(const scenes::LayerConfig& l, double t_layer, double zoom,
                                     double rho) {
    if (l.source) {
        const auto s = l.source->power_spectrum(rho * zoom);
        if (!s) return std::nullopt;
        const double g = l.gain.value(t_layer);
        return zoom * zoom * g * g * *s;
    }
    const kernels::Kernel k(l.kernel_at(t_layer));
    const double scale = scenes::layer_theory(l, t_layer).variance / k.integral_sq();
    return zoom * zoom * scale * k.radial_power_spectrum(rho * zoom);
}

}  // namespace

std::optional<std::vector<double>> SceneObject::spectrum(const std::vector<double>& k, double t_s,
                                                         std::string& why) const {
    const scenes::Scene& s = m_scene;
    if (!scenes::is_sum_of_layers(s))
        why = "the scene composes its layers otherwise than by adding them";
    else if (s.camera.type != scenes::CameraConfig::Type::Orthographic)
        why = "a perspective camera: the spectrum changes across the frame";
    else if (s.transform.type != output::FieldTransform::Type::None)
        why = "a [shading.transform] makes the texture something else than the summed field";
    if (!why.empty()) return std::nullopt;
    const double zoom = s.camera.zoom.value(t_s);
    std::vector<double> power(k.size(), 0.0);
    for (size_t i = 0; i < s.layers.size(); ++i) {
        const double t_layer = s.layers[i].layer_time(t_s);
        for (size_t j = 0; j < k.size(); ++j) {
            const auto p = layer_spectrum(s.layers[i], t_layer, zoom, k[j]);
            if (!p) {
                why = "layer[" + std::to_string(i) + "]'s source states no spectrum";
                return std::nullopt;
            }
            power[j] += *p;
        }
    }
    return power;
}

void SceneObject::check_layer(size_t layer, const std::string& what) const {
    if (layer >= m_scene.layers.size())
        throw ValueError(what + ": layer " + std::to_string(layer) + ": the scene has " +
                         std::to_string(m_scene.layers.size()) + " layers");
    if (m_scene.layers[layer].source)
        throw ValueError(what + ": layer " + std::to_string(layer) + " is drawn by a source (" +
                         std::string(m_scene.layers[layer].source->kind()) + "), not by impulses");
}

void SceneObject::set_flow(size_t layer, sim::VectorGrid grid, double gain) {
    check_layer(layer, "set_flow");
    std::shared_ptr<sim::Flow> flow = sim::make_grid_flow(std::move(grid), gain);
    const std::lock_guard<std::mutex> lock(m_mutex);
    m_scene.layers[layer].flow = std::move(flow);
    m_renderer.reset();
}

void SceneObject::set_orientation(size_t layer, sim::OrientationGrid grid, double jitter) {
    check_layer(layer, "set_orientation");
    if (!(jitter >= 0.0))
        throw ValueError("set_orientation: jitter " + std::to_string(jitter) +
                         ": expected an angle >= 0 in radians");
    auto field = sim::make_grid_orientation(std::move(grid));
    const std::lock_guard<std::mutex> lock(m_mutex);
    sim::ProcessConfig& p = m_scene.layers[layer].process;
    p.orientation = sim::OrientationMode::Field;
    p.orientation_field = std::move(field);
    p.orientation_jitter = jitter;
    m_scene.layers[layer].compose.orientation.reset();  // the array replaces another layer's field
    m_renderer.reset();
}

}  // namespace impulse::python
