// SPDX-License-Identifier: Apache-2.0
#pragma once
// Composition of layers (docs/scenes.md "Composition"): reading the keys that refer to other
// layers (scenes/language/compose_config.cpp) and the per-pixel operations of the renderer
// (scenes/frame/compose_render.cpp). Internal to impulse::scenes.

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes::detail {

// ---------------------------------------------------------------------------------------------
// Scene files

/// Reads a layer's composition keys and the keys that name other layers, which can only be
/// checked once every layer is read: call read_layer for each [[layer]] (and read_orientation /
/// read_flow from the readers of those keys), then resolve.
class CompositionReader {
public:
    CompositionReader();
    ~CompositionReader();
    /// name, visible, blend, opacity, alpha, warp of layer `index`.
    void read_layer(Reader& layer, size_t index, LayerConfig& config);
    /// orientation = { type = "layer", source = ..., along = "gradient" | "level" }.
    void read_orientation(Reader& table, size_t index);
    /// [[layer.flow]] type = "layer": a placeholder term of `sum`, completed by resolve.
    void read_flow(Reader& flow, size_t index, sim::FlowSum& sum);
    /// Resolves names and indices, refuses self references, cycles and sources unfit for their
    /// use, and builds the stream-function flows. Throws SceneError at the offending key.
    void resolve(Scene& scene);

private:
    struct Ref;
    struct PendingFlow;
    std::vector<Ref> m_refs;
    std::vector<std::unique_ptr<PendingFlow>> m_flows;
    std::vector<std::optional<Reader>> m_layers;  ///< each layer's reader, for messages

    // The steps of resolve, in order.
    /// Layer names -> indices (appended to `names` in file order); a repeated name fails.
    std::map<std::string, size_t> unique_names(const std::vector<LayerConfig>& layers,
                                               std::vector<std::string>& names);
    /// Sets ref.target from a name or an index of `n` layers; refuses a self reference.
    void resolve_target(Ref& ref, const std::map<std::string, size_t>& by_name,
                        const std::vector<std::string>& names, size_t n);
    /// A domain warp's source: an orthographic camera and a source with variance.
    void connect_warp(const Ref& ref, Scene& scene);
    /// A flow along a still impulse layer's level lines: completes the pending term.
    void connect_flow(const Ref& ref, std::vector<LayerConfig>& layers);
    /// No layer may need its own field through a chain of warps and orientations.
    void refuse_cycles(size_t n);
    /// Something to show; a first visible layer that adds or lies over; unused hidden layers.
    void check_visibility(const std::vector<LayerConfig>& layers);
};

/// The semivariogram (1/2) int (h(x) - h(x + tau))^2 d^2x = C(0) - C(tau) of a kernel at
/// tau = (tx, ty), C its autocorrelation, by the midpoint rule on a 96 x 96 grid over the
/// support grown by |tau|: within 1e-6 of itself for the cosine kernel and 2e-4 for a truncated
/// Gaussian (measured against Kernel::autocorrelation, which takes 100 times as long). Averaged
/// over 36 rotations of the kernel when `random_orientation` and the kernel is not isotropic.
/// Computed as a difference's own integral it keeps its relative accuracy at small lags, where
/// C(0) - C is a small part of C(0).
double sampled_semivariogram(const kernels::Kernel& kernel, bool random_orientation, double tx,
                             double ty);

// ---------------------------------------------------------------------------------------------
// Rendering

/// Blends `layer` (its own field) onto `running` in place, pixel by pixel, with weight
/// `opacity`: add r + o l; multiply r ((1 - o) + o l); max r + o (max(r, l) - r); min alike;
/// over r (1 - a) + l a with a = o smoothstep(lo, hi, l) or a = o without an alpha range.
/// Deterministic (each pixel on its own).
void blend(Blend mode, double opacity, const std::optional<std::array<double, 2>>& alpha,
           const render::Frame& layer, render::Frame& running);

/// smoothstep from lo to hi (lo > hi: falling), the alpha ramp of `over`.
double alpha_ramp(double lo, double hi, double v);

/// out(i, j) = src at pixel position (i + margin + dx(i, j), j + margin + dy(i, j)), bicubic
/// (Catmull-Rom); src is out's view grown by `margin` pixels on every side, dx and dy are in
/// pixels (out-sized). Positions are held inside src (the caller's margin covers them).
void warp_resample(const render::Frame& src, int margin, const std::vector<float>& dx,
                   const std::vector<float>& dy, render::Frame& out);

/// Theta from a field sampled on a lattice (the renderer fills it for the frame and the region
/// of the impulses it is about to ask for): the direction of the Catmull-Rom interpolant's
/// gradient, or of its level lines (gradient + pi/2). 0 where the gradient vanishes.
class LatticeOrientation final : public sim::OrientationField {
public:
    explicit LatticeOrientation(bool level_lines) : m_level_lines(level_lines) {}
    /// Node (a, b) of `values` (values.width x values.height) sits at texture point
    /// ((i0 + a) h, (j0 + b) h).
    void set(render::Frame values, int64_t i0, int64_t j0, double spacing);
    void angles(double t_s, size_t n, const double* x, const double* y,
                float* theta) const override;

private:
    bool m_level_lines;
    render::Frame m_values;
    int64_t m_i0 = 0, m_j0 = 0;
    double m_h = 1.0;
};

/// Mean and variance of the running result after blending a layer with mean/variance `layer`
/// (independent of the running result) in `mode` with weight `opacity` (see scene_theory).
Theory blend_theory(const Theory& running, const LayerConfig& layer, const Theory& layer_theory,
                    double opacity);

}  // namespace impulse::scenes::detail
