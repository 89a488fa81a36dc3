// SPDX-License-Identifier: Apache-2.0
// The camera-dependent part of rendering a layer: kernel pyramids per layer, the perspective
// geometry of a frame, the texture region the impulses must cover, and the evaluation.

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include <tbb/parallel_for.h>

#include "scenes/detail/camera.h"

namespace impulse::scenes::detail {

CameraPipeline::CameraPipeline(const Scene& scene, const std::vector<kernels::Kernel>& kernels)
    : m_scene(&scene), m_kernels(&kernels) {
    const CameraConfig& c = scene.camera;
    m_active = c.type == CameraConfig::Type::Perspective || c.antialiased();
    m_stats.resize(kernels.size());
    if (!m_active) return;
    m_aa = c.antialias_options();
    // Levels below a quarter of the cut-off are never drawn (faded out).
    m_pyramid_params.min_sd_fraction = std::min(1e-3, 0.25 * m_aa.cutoff);
    // A source layer draws no impulses: no kernel pyramid (it filters its own tile, the
    // source's GridPyramid), none of the ~2 MiB a default kernel's levels take.
    for (size_t i = 0; i < kernels.size(); ++i) {
        m_pyramids.push_back(scene.layers[i].source ? nullptr
                                                    : std::make_unique<kernels::KernelPyramid>(
                                                          kernels[i], m_pyramid_params));
        m_workspaces.push_back(std::make_unique<render::PerspectiveWorkspace>());
    }
    m_class_pyramids.resize(kernels.size());
}

const kernels::KernelPyramid& CameraPipeline::class_pyramid(size_t layer, double scale) const {
    auto& built = m_class_pyramids.at(layer)[scale];
    if (!built) {  // h(x / s) with its own band-limited levels (docs/scenes.md "Kernel scale fields")
        const kernels::Kernel k(render::scaled_kernel(m_kernels->at(layer).params(), scale));
        built = std::make_unique<kernels::KernelPyramid>(k, m_pyramid_params);
    }
    return *built;
}

const kernels::KernelPyramid& CameraPipeline::reach_pyramid(size_t layer) const {
    const LayerConfig& L = m_scene->layers.at(layer);
    if (!L.scale) return *m_pyramids.at(layer);
    return class_pyramid(layer, render::scale_class_at_least(L.max_scale()));
}

double CameraPipeline::kernel_reach(size_t layer) const {
    return m_kernels->at(layer).radius() * m_scene->layers.at(layer).max_scale();
}

CameraPipeline::~CameraPipeline() = default;

const kernels::KernelPyramid* CameraPipeline::pyramid(size_t layer) const {
    return m_active ? m_pyramids.at(layer).get() : nullptr;
}

void CameraPipeline::prepare(double t) {
    if (m_t && *m_t == t) return;
    const auto& o = m_scene->output;
    const render::PerspectiveCamera cam = m_scene->camera.perspective(o.width, o.height, t);
    m_t = t;
    // A camera without keys (or between equal keys) sees the same rays frame after frame: its
    // per-pixel texture coordinates (a few ms at 1080p) are kept.
    if (m_view && m_view->camera().same_rays(cam)) return;
    m_view = std::make_unique<render::PerspectiveView>(cam);
    m_coords = render::pixel_coords(*m_view);
    m_footprints = PixelFootprints{};
}

namespace {

// Each pixel centre's texture point and footprint (docs/perspective.md §1); s_major = 0 where
// the ray misses the plane or the point is too far for doubles to place.
PixelFootprints pixel_footprints(const render::PerspectiveView& view,
                                 const render::PixelCoords& coords, const render::AntiAlias& aa) {
    PixelFootprints px;
    px.view = &view, px.coords = &coords, px.aa = aa;
    const auto& cam = view.camera();
    px.width = cam.width, px.height = cam.height;
    const size_t n = size_t(px.width) * px.height;
    px.x.assign(n, 0.0), px.y.assign(n, 0.0);
    px.s_major.assign(n, 0.0f), px.s_minor.assign(n, 0.0f), px.ex.assign(n, 1.0f), px.ey.assign(n, 0.0f);
    px.filter_sd_px = aa.enabled ? aa.filter_px * aa.footprint_scale : 0.0;
    px.cutoff = aa.fade ? aa.cutoff : 0.0;
    tbb::parallel_for(0, px.height, [&](int j) {
        for (int i = 0; i < px.width; ++i) {
            const size_t p = size_t(j) * px.width + i;
            double x = 0, y = 0;
            if (!view.texture_point(i + 0.5, j + 0.5, x, y) || !(std::abs(x) < 1e15 && std::abs(y) < 1e15))
                continue;
            const auto f = view.footprint(x, y);
            if (!(std::isfinite(f.s_major) && f.s_major > 0.0 && std::isfinite(f.s_minor))) continue;
            px.x[p] = x, px.y[p] = y;
            px.s_major[p] = float(f.s_major), px.s_minor[p] = float(f.s_minor);
            px.ex[p] = float(f.ex), px.ey[p] = float(f.ey);
        }
    });
    return px;
}

}  // namespace

void CameraPipeline::add_source(const LayerSource& source, double t, double t_layer,
                                render::Frame& out) {
    prepare(t);
    if (m_footprints.width == 0) m_footprints = pixel_footprints(*m_view, m_coords, m_aa);
    source.add_perspective(m_footprints, 0.0, 0.0, t_layer, out);
}

render::AntiAlias CameraPipeline::aa_at(double footprint_scale) const {
    render::AntiAlias aa = m_aa;
    aa.footprint_scale *= footprint_scale;
    return aa;
}

bool CameraPipeline::perspective() const {
    return m_scene->camera.type == CameraConfig::Type::Perspective;
}

const kernels::Kernel& CameraPipeline::filtered_kernel(size_t layer, const render::View& view) const {
    const kernels::KernelPyramid& pyr = *m_pyramids.at(layer);
    if (!m_aa.enabled) return pyr.base();
    return pyr.level(pyr.select(m_aa.filter_px * m_aa.footprint_scale * view.scale, m_aa.blend).lo);
}

numeric::Region CameraPipeline::region(size_t layer, const render::View& view, double t,
                                       double footprint_scale) {
    if (!m_active) return view.box();
    const render::AntiAlias aa = aa_at(footprint_scale);
    const kernels::KernelPyramid& pyr = reach_pyramid(layer);
    if (m_scene->camera.type == CameraConfig::Type::Perspective) {
        prepare(t);
        numeric::Region r = render::perspective_region(pyr, *m_view, m_aa);
        if (!r.empty()) return r;
        const auto& c = m_view->camera();
        return numeric::Box{c.x, c.y, c.x, c.y};  // nothing to draw: a point (a few impulses, no work)
    }
    if (!(render::filtered_fade(pyr, view, aa) > 0.0)) {
        // The layer is its mean: ask for next to nothing (a point, never an inverted box).
        const numeric::Box v = view.box();
        const double cx = 0.5 * (v.x0 + v.x1), cy = 0.5 * (v.y0 + v.y1);
        return numeric::Box{cx, cy, cx, cy};
    }
    // The simulator adds the kernel's own radius; the blended levels reach further.
    return view.box().expanded(
        std::max(0.0, render::filtered_support(pyr, view, aa) - kernel_reach(layer)));
}

void CameraPipeline::accumulate(size_t layer, const sim::Impulses& impulses,
                                const render::View& view, double t, render::Frame& out,
                                const render::EvalOptions& options, double footprint_scale) {
    if (!m_active) return render::accumulate(m_kernels->at(layer), impulses, view, out, options);
    if (impulses.scale.empty())
        return accumulate_with(layer, *m_pyramids.at(layer), impulses, view, t, out, options,
                               footprint_scale);
    // A scale field: each class with its own pyramid, in ascending scale (a fixed order).
    for (const render::ScaleClass& c :
         render::split_scale_classes(m_kernels->at(layer), impulses, "layer scale"))
        accumulate_with(layer, class_pyramid(layer, c.scale), c.impulses, view, t, out, options,
                        footprint_scale);
}

void CameraPipeline::accumulate_with(size_t layer, const kernels::KernelPyramid& pyr,
                                     const sim::Impulses& impulses, const render::View& view,
                                     double t, render::Frame& out,
                                     const render::EvalOptions& options, double footprint_scale) {
    if (m_scene->camera.type == CameraConfig::Type::Perspective) {
        prepare(t);
        render::EvalOptions o = options;
        o.max_pixel_evaluations = m_scene->limits.max_pixel_evaluations;
        try {
            render::accumulate_perspective(pyr, impulses, *m_view, m_coords, out, m_aa, o,
                                           &m_stats.at(layer), m_workspaces.at(layer).get());
        } catch (const render::PixelBudgetError& e) {
            std::ostringstream s;
            s << m_scene->path << ": layer[" << layer << "] at t = " << t << " s needs "
              << e.needed << " pixel evaluations, over the budget of " << e.budget
              << " (limits.max_pixel_evaluations; raise camera.cutoff, set camera.anisotropic "
                 "= true, or raise the limit)";
            throw BudgetError(s.str());
        }
        return;
    }
    render::accumulate_filtered(pyr, impulses, view, out, aa_at(footprint_scale), options);
}

numeric::Region CameraPipeline::estimate_region(size_t layer, const render::View& view0) const {
    if (!m_active) return view0.box();
    const kernels::KernelPyramid& pyr = reach_pyramid(layer);
    const CameraConfig& c = m_scene->camera;
    if (c.type == CameraConfig::Type::Orthographic)
        return view0.box().expanded(
            std::max(0.0, render::filtered_support(pyr, view0, m_aa) - kernel_reach(layer)));
    std::set<double> times = {0.0};
    for (const auto* k : {&c.position_x, &c.position_y, &c.altitude, &c.pitch, &c.heading, &c.fov})
        for (const auto& key : k->keys) times.insert(key.first);
    const auto& o = m_scene->output;
    numeric::Region best = numeric::Box{0, 0, 0, 0};
    for (double t : times) {
        const render::PerspectiveView v(c.perspective(o.width, o.height, t));
        numeric::Region r = render::perspective_region(pyr, v, m_aa);
        if (r.area() > best.area()) best = std::move(r);
    }
    return best;
}

}  // namespace impulse::scenes::detail
