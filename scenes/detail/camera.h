// SPDX-License-Identifier: Apache-2.0
#pragma once
// Cameras and orientation fields in scene files, and the camera-dependent part of rendering a
// layer (internal to impulse::scenes).

#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes::detail {

/// The [camera] keys other than the orthographic center/zoom (already read into `c`): type,
/// the perspective keys, the anti-aliasing keys. Fails on perspective keys given to an
/// orthographic camera and vice versa, and on cameras that cannot see the plane.
void read_camera_view(Reader& r, CameraConfig& c, int width, int height);

/// layer.orientation: a mode name ("fixed", "random", "flow", "vorticity") or a field table
/// { type = "constant" | "radial" | "circular" | "polyline" | "sine" | "image" | "layer", ... }.
/// Images are read here (OpenImageIO) relative to `base`. Type "layer" (another layer's field,
/// set by the renderer) hands the table to `layer_source`, then reads `jitter`.
void read_orientation(Reader& layer, sim::ProcessConfig& process,
                      const std::filesystem::path& base,
                      const std::function<void(Reader&)>& layer_source);

/// [camera.sea] of a perspective sky camera `c` (scenes/frame/sea.cpp): depth, roughness, wavelength,
/// wind, color. Fails on a sea under an orthographic or ground camera, or one whose horizon is
/// above the frame at some key (nothing of the sea would show).
void read_sea(Reader& sea, CameraConfig& c, int width, int height);

/// The camera that sees, at every pixel, the cloud deck along the reflected ray of the pixel
/// mirrored about the centre row (docs/perspective.md §9): a sky camera at height + 2 depth
/// below the deck, at pitch -pitch, with no sea of its own.
CameraConfig mirror_camera(const CameraConfig& c);

/// The mirror camera's picture size for a frame of width x height: sea.mirror_resolution of the
/// height rounded up, at least mirror_min_height rows and at most the frame's, and at least as
/// wide as the frame's view (apply_sea scales to it).
std::array<int, 2> mirror_size(const SeaConfig& sea, int width, int height);

/// Replaces the pixels of `field` below `camera`'s horizon by the sea: the mirror camera's
/// field `mirror` (of any size from mirror_size: the same fov, so scaled about its centre)
/// looked up bilinearly along each pixel's ray reflected at the wave normal, as
/// mean + F (mirror - mean), F the Schlick reflectance. Deterministic (per pixel, + - * / sqrt
/// sin cos, rows in parallel).
void apply_sea(const render::PerspectiveCamera& camera, const SeaConfig& sea, double filter_px,
               double t_s, double mean, const render::Frame& mirror, render::Frame& field);

/// The background of a sky camera with a sea at time t_s (output::Shading::background): the sky
/// gradient from the top of the frame to the horizon, and below it the sky colour of the
/// mirrored elevation, Fresnel-weighted against the sea's colour.
std::vector<float> sea_background(const CameraConfig& camera, const output::Shading& shading,
                                  double t_s);

/// Filtering after shading (scenes/frame/subpixel.cpp, docs/shading.md "The sub-pixel sd"): the sd of
/// the field within each row's pixel filter that the filtered frame does not show, one value per
/// row of the scene's output size at frame time t_s (output::Shading::subpixel_sd); one value
/// for an orthographic camera. Empty where the remedy does not apply (filter = "before", a frame
/// that is not filtered, or one whose field is not a plain sum of impulse layers).
std::vector<float> subpixel_sd(const Scene& scene, double t_s);

/// Per-layer kernel pyramids and the per-frame perspective geometry, used by Renderer::render.
class CameraPipeline {
public:
    CameraPipeline(const Scene& scene, const std::vector<kernels::Kernel>& kernels);
    ~CameraPipeline();
    /// True when frames go through the pyramid (perspective, or orthographic anti-aliasing).
    bool active() const { return m_active; }
    /// Texture region layer `layer`'s impulses must cover at time t_s (`view`: the orthographic
    /// view; its box when nothing applies). A point when the layer is faded to its mean.
    /// `footprint_scale`: an orthographic view's pixel footprint is that many of `view`'s
    /// pixels (a lattice of h pixels takes 1 / h: its nodes are filtered as the pixels are).
    numeric::Region region(size_t layer, const render::View& view, double t_s,
                           double footprint_scale = 1.0);
    /// Adds the layer's impulses to `out` (frame size) as the camera sees them at time t_s.
    void accumulate(size_t layer, const sim::Impulses& impulses, const render::View& view,
                    double t_s, render::Frame& out, const render::EvalOptions& options,
                    double footprint_scale = 1.0);
    /// True for a perspective camera.
    bool perspective() const;
    /// The kernel an orthographic view draws layer `layer` with (the finer of the pyramid's
    /// blended levels): what its lattice rule follows (docs/multirate.md §5).
    const kernels::Kernel& filtered_kernel(size_t layer, const render::View& view) const;
    /// The largest region over the camera's keys (for budget estimates); `view0`: the
    /// orthographic view at its widest.
    numeric::Region estimate_region(size_t layer, const render::View& view0) const;
    /// The layer's pyramid (null when not active).
    const kernels::KernelPyramid* pyramid(size_t layer) const;
    /// Adds a source layer's field at its layer time t_layer as the perspective camera sees it
    /// at frame time t_s (frame size): LayerSource::add_perspective on the frame's pixel
    /// footprints (kept while the rays are).
    void add_source(const LayerSource& source, double t_s, double t_layer, render::Frame& out);
    /// Counts of the last perspective evaluation of a layer.
    const render::PerspectiveStats& stats(size_t layer) const { return m_stats.at(layer); }

private:
    void prepare(double t_s);
    /// Adds impulses drawn with pyramid `pyr` (the layer's, or one of its scale classes').
    void accumulate_with(size_t layer, const kernels::KernelPyramid& pyr,
                         const sim::Impulses& impulses, const render::View& view, double t_s,
                         render::Frame& out, const render::EvalOptions& options,
                         double footprint_scale);
    /// The anti-aliasing options with the pixel footprint scaled.
    render::AntiAlias aa_at(double footprint_scale) const;
    /// The pyramid of the layer's kernel scaled by a class scale (built on first use, kept).
    const kernels::KernelPyramid& class_pyramid(size_t layer, double scale) const;
    /// The pyramid whose support reaches furthest: the layer's, or its largest scale class's.
    const kernels::KernelPyramid& reach_pyramid(size_t layer) const;
    /// The impulses' support radius the simulator adds: kernel radius times the largest scale.
    double kernel_reach(size_t layer) const;
    const Scene* m_scene;
    const std::vector<kernels::Kernel>* m_kernels;
    bool m_active = false;
    render::AntiAlias m_aa;
    std::vector<std::unique_ptr<kernels::KernelPyramid>> m_pyramids;
    kernels::PyramidParams m_pyramid_params;
    /// Per layer with a scale field: the pyramids of its classes by scale, built when a frame
    /// first needs them (0.1-0.3 s each).
    mutable std::vector<std::map<double, std::unique_ptr<kernels::KernelPyramid>>> m_class_pyramids;
    std::vector<render::PerspectiveStats> m_stats;
    /// Per layer: the perspective evaluation's memory, kept from frame to frame (tens of MB that
    /// would otherwise be new to the process, page fault by page fault, every frame).
    std::vector<std::unique_ptr<render::PerspectiveWorkspace>> m_workspaces;
    // perspective geometry of the frame at m_t
    std::optional<double> m_t;
    std::unique_ptr<render::PerspectiveView> m_view;
    render::PixelCoords m_coords;
    PixelFootprints m_footprints;  ///< of m_view, made on first use (width 0: not yet)
};

}  // namespace impulse::scenes::detail
