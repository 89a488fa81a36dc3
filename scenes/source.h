// SPDX-License-Identifier: Apache-2.0
#pragma once
// The layer-source seam (design.md §2; part of impulse::scenes, included by scenes/scenes.h):
// a layer draws either the impulse process (the point process of sim/ and render/, configured
// by the layer's kernel, density and flow) or a LayerSource, a field of texture space and time
// from another synthesizer (subdivision, fBm, solid noise). Composition, shading, marginal
// shaping, warps, orientation and analysis take a source's layer as they take any other.

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "numeric/frame.h"
#include "render/render.h"

namespace impulse::scenes {

/// Closed-form statistics of a layer or a source (Campbell's theorem for impulses, design.md
/// §1; the synthesizer's own theory for a source).
struct Theory {
    double mean = 0.0;
    double variance = 0.0;
};

/// The pixels of a perspective frame as the texture plane sees them (pixel p = j * width + i):
/// the texture point of each pixel centre and its footprint, texture units per pixel along the
/// major axis (ex, ey) and across (docs/perspective.md §1); s_major = 0 where the ray misses the
/// plane (the pixel shows the mean).
struct PixelFootprints {
    int width = 0, height = 0;
    std::vector<double> x, y;
    std::vector<float> s_major, s_minor, ex, ey;
    double filter_sd_px = 0.5;  ///< the pixel filter's sd in pixels (camera.filter)
    double cutoff = 0.01;       ///< fade to the mean below this fraction of the sd (0: none)
    /// The camera, its pixel coordinates and anti-aliasing options these footprints come from
    /// (kept alive by the caller): for sources drawn as impulses through
    /// render::accumulate_perspective (solid noise, docs/perspective.md §10).
    const render::PerspectiveView* view = nullptr;
    const render::PixelCoords* coords = nullptr;
    render::AntiAlias aa;
};

/// The pixel lattice of an orthographic view, where the closed form of a scene samples a source
/// (scenes/theory/closed_form.cpp).
struct PixelLattice {
    double scale = 1.0;       ///< texture units per pixel (1 / zoom)
    double x = 0.5, y = 0.5;  ///< the texture point of pixel (0, 0)'s centre
};

/// A field f(x, t) of texture space x and time t, stated by a synthesizer. Implementations are
/// immutable once built and thread-safe.
class LayerSource {
public:
    virtual ~LayerSource() = default;
    /// The source's name in scene files and messages ("fbm", "subdivision", "solid").
    virtual std::string_view kind() const = 0;
    /// Adds f(x, t_s) at the pixel centres x of `view` to `out` (sized to the view), band-limited
    /// by the source to the view's pixel spacing where it can be. A pure function of (source,
    /// view, t_s): the same pixels in any view, tile or frame order give the same bits.
    virtual void add(const numeric::View& view, double t_s, numeric::Frame& out) const = 0;
    /// Whether add_perspective draws this source (a perspective camera refuses it otherwise).
    virtual bool perspective() const { return false; }
    /// Why a perspective camera refuses this source, one line ("" where it draws it).
    virtual std::string no_perspective_reason() const {
        return "a " + std::string(kind()) + " layer is seen through an orthographic camera only";
    }
    /// Adds f(x - (dx, dy), t_s) filtered by each pixel's footprint (a Gaussian of sd
    /// filter_sd_px pixels) to `out` (sized to the pixels), faded to the mean where the footprint
    /// leaves less than `cutoff` of the sd, as impulse layers are. Pure, like `add`.
    virtual void add_perspective(const PixelFootprints& pixels, double dx, double dy, double t_s,
                                 numeric::Frame& out) const {
        (void)pixels, (void)dx, (void)dy, (void)t_s, (void)out;
    }
    /// Bytes the source holds to draw frames of `pixels` pixels: its realised tile, the
    /// pyramid a perspective camera builds on first use (`perspective`) and its buffers per
    /// frame; what limits.max_memory_mib counts for it (Renderer::estimated_memory_mib).
    virtual double memory_bytes(double pixels, bool perspective) const {
        (void)pixels, (void)perspective;
        return 0.0;
    }
    /// Closed-form mean and variance of f at t_s (before the layer's gain and mean).
    virtual Theory theory(double t_s) const = 0;
    /// A length over which f is correlated (texture units, > 0): the spacing of the lattices on
    /// which other layers sample this one (orientation from its gradient), taken as 1/8 of it.
    virtual double correlation_length() const = 0;
    /// The radially averaged power spectrum S(k), k in cycles per texture unit, where the
    /// source states it; nullopt otherwise (analysis then compares moments only).
    virtual std::optional<double> power_spectrum(double k_cycles) const {
        (void)k_cycles;
        return std::nullopt;
    }
    /// S(kx, ky) (cycles per texture unit) where the source states it; the radial one by
    /// default. Analysis evaluates it where annuli hold too few DFT bins for the radial mean to
    /// stand for an anisotropic spectrum (an fbm tile's square lattice of frequencies).
    virtual std::optional<double> power_spectrum_2d(double kx, double ky) const {
        return power_spectrum(std::hypot(kx, ky));
    }
    /// The expected periodogram density of f(., t_s) sampled at the pixel centres of `lattice`
    /// (value^2 px^2 at (fx, fy) cycles per pixel, every alias of the pixel lattice included),
    /// where the source states it; nullopt otherwise, and the closed form adds the nearest
    /// images of power_spectrum_2d as power. A field on a lattice of its own (an fbm tile's
    /// samples) states it: where the two lattices are commensurate its images add coherently.
    virtual std::optional<double> sampled_spectrum(double fx, double fy, const PixelLattice& lattice,
                                                   double t_s) const {
        (void)fx, (void)fy, (void)lattice, (void)t_s;
        return std::nullopt;
    }
    /// Whether the spectrum depends on direction (then power_spectrum_2d is used at low k).
    virtual bool anisotropic_spectrum() const { return false; }
    /// Why power_spectrum states nothing, for analysis notes ("" where it states a spectrum).
    virtual std::string no_spectrum_reason() const { return "the source states no spectrum"; }
};

}  // namespace impulse::scenes
