// SPDX-License-Identifier: Apache-2.0
#pragma once
// The scene object of the Python module `impulse` (python/module.cpp binds it): a loaded scene
// and its renderer, with the frame as a float buffer handed to numpy without a copy.

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "scenes/scenes.h"

namespace impulse::python {

/// The radially averaged spectrum the scene's theory states for its frames: power[i] at
/// frequency[i] cycles per pixel, value^2 per (cycle/pixel)^2 (what a periodogram estimates).
struct SpectrumTable {
    std::vector<double> frequency, power;
};

/// A scene loaded from a file or from TOML text, rendered frame by frame. Changing the scene
/// (a flow or an orientation field from an array) rebuilds its renderer. Rendering holds a
/// lock: two Python threads may share a Scene (the renderer reuses particle state).
class SceneObject {
public:
    SceneObject(scenes::Scene scene, std::vector<std::string> overrides);

    const scenes::Scene& scene() const { return m_scene; }
    const std::vector<std::string>& overrides() const { return m_overrides; }
    /// Throws ValueError for a frame outside [0, output.frames).
    void check_frame(int64_t frame) const;
    /// The float field of `frame` (the CLI's EXR values, bit for bit).
    std::unique_ptr<numeric::Frame> render(int64_t frame);
    /// The channels of `frame` (scenes::Renderer::render_channels; docs/channels.md).
    scenes::FrameChannels render_channels(int64_t frame, const scenes::ChannelSet& set);
    /// Display RGB of `frame` in [0, 1], 3 floats per pixel (the shading of PNG output).
    std::vector<float> render_rgb(int64_t frame);
    /// The value -> display mapping (output.range, else mean +- 3 sd).
    output::ValueMapping mapping();
    /// The closed-form spectrum at frame time t_s at the given frequencies (cycles per pixel);
    /// nullopt, with the reason in `why`, when the theory states none for this scene.
    std::optional<std::vector<double>> spectrum(const std::vector<double>& k, double t_s,
                                                std::string& why) const;
    /// Layer `layer`'s flow becomes `grid` (velocity in texture units per second).
    void set_flow(size_t layer, sim::VectorGrid grid, double gain);
    /// Layer `layer`'s kernels turn along `grid` (angles or directions).
    void set_orientation(size_t layer, sim::OrientationGrid grid, double jitter);

private:
    scenes::Renderer& renderer();
    void check_layer(size_t layer, const std::string& what) const;

    scenes::Scene m_scene;
    std::vector<std::string> m_overrides;
    std::unique_ptr<scenes::Renderer> m_renderer;  ///< built at the first render
    std::mutex m_mutex;
};

}  // namespace impulse::python
