// SPDX-License-Identifier: Apache-2.0
#pragma once
// The readers of a scene file's sections (internal to impulse::scenes), one file each, called by
// read_scene (loader.cpp): a layer's kernel (kernel_config.cpp), its flows (flow_config.cpp), a
// layer drawn by another synthesizer (source_config.cpp), the camera (camera_config.cpp); the
// shading, marginal, region, composition, orientation and transform readers have their own
// headers.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scenes/detail/compose.h"
#include "scenes/detail/reader.h"
#include "scenes/scenes.h"
#include "scenes/detail/source.h"

namespace impulse::volume {
class FlowSum3;
}

namespace impulse::scenes::detail {

inline const auto kPositive = [](double v) { return v > 0.0; };
inline const auto kNonNegative = [](double v) { return v >= 0.0; };

/// A number as a person writes it (30, 2.5), for messages.
std::string num(double v);
/// A colour: [r, g, b] or [r, g, b, a] with components in [0, 1], or "#rrggbb" (alpha 1).
bool parse_color(const toml::node& n, float c[4]);
/// Mix the scene-wide seed into a layer's seed (splitmix64 finaliser).
uint64_t mix_seed(uint64_t global, uint64_t layer);

/// The [layer.kernel] table; keyframed fields go to `keys` (their values at t = 0 into the
/// result). `pyramid`: the camera anti-aliases through a kernel pyramid, built once per layer,
/// so only the orientation (a rotation of every impulse) may vary in time. A design's working
/// memory is held to `max_memory_mib` (limits.max_memory_mib).
kernels::KernelParams read_kernel(std::optional<Reader> r, Reader& layer,
                                  const std::filesystem::path& base, std::vector<KernelKey>& keys,
                                  bool pyramid, double max_memory_mib);
/// The design keys of a `spectrum` or `autocorrelation` kernel in table `r` (energy, nyquist,
/// rolloff, max_radius; one of model, expression, table and the model's parameters) and the
/// design in o.dims dimensions (2: [layer.kernel]; 3: [layer.solid]); o.radius and o.window are
/// the caller's. Library errors are reported at the key whose value caused them.
kernels::DesignedKernel read_design(Reader& r, bool acf, const std::filesystem::path& base,
                                    kernels::DesignOptions o);
/// The layer's [[layer.flow]] tables summed into one flow (null without any); type "layer"
/// flows are handed to `compose` (another layer's field, set by the renderer). `uniform`, when
/// given, receives the velocities of the uniform terms.
std::shared_ptr<sim::Flow> read_flows(
    Reader& layer, const sim::ProcessConfig& process, const std::filesystem::path& base,
    CompositionReader& compose, size_t index,
    std::vector<std::pair<numeric::Keyframed, numeric::Keyframed>>* uniform = nullptr);
/// A `type = "sequence"` flow table `f` of `layer` (scenes/language/sequence_config.cpp): finds and checks
/// every frame, then pushes the sampled flow onto `sum`.
void read_sequence_flow(Reader& f, const sim::ProcessConfig& process, Reader& layer,
                        const std::filesystem::path& base, sim::FlowSum& sum);
/// A `type = "sequence"` table `f` of [[volume.flow]] (scenes/language/sequence_config.cpp): the same
/// keys in 3-D (`scale` and `offset` per axis, no plane), OpenVDB files only.
void read_volume_sequence_flow(Reader& f, double lifetime_s, bool jacobian, Reader& volume,
                               const std::filesystem::path& base, volume::FlowSum3& sum);
/// The velocity of a `type = "uniform"` flow table: `velocity = [vx, vy]` or keyframed `vx`,
/// `vy` (texture units per second; absent: 0).
std::pair<numeric::Keyframed, numeric::Keyframed> read_uniform_velocity(Reader& flow);
/// A [[layer]] drawn by another synthesizer (source = "fbm", "subdivision", "solid"); `budget`:
/// what the limit leaves its tile; `zoom`: the camera's smallest zoom (pixels per texture unit);
/// `perspective`: the camera is one.
void read_source_layer(Reader& r, size_t i, uint64_t global_seed, const std::filesystem::path& base,
                       const TileBudget& budget, double zoom, bool perspective,
                       CompositionReader& compose, LayerConfig& L);
/// A volume scene's [volume] and [preview] tables (scenes/language/volume_config.cpp); `fps` and the
/// preview size come from [output]; `base` resolves a sequence's path.
std::shared_ptr<const VolumeSceneConfig> read_volume_scene(Reader& top, uint64_t global_seed,
                                                          const OutputConfig& output,
                                                          const std::filesystem::path& base);
/// layer.scale (scenes/language/scale_config.cpp): a kernel scale field, a number or a table with a
/// type; refused with a marginal (read it after the marginal).
void read_scale(Reader& layer, const std::filesystem::path& base, LayerConfig& L);
/// The [camera] table (absent: the orthographic default framing a width x height output).
CameraConfig read_camera(std::optional<Reader> r, int width, int height);

}  // namespace impulse::scenes::detail
