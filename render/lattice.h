// SPDX-License-Identifier: Apache-2.0
#pragma once
// Multi-rate evaluation (part of impulse::render; docs/multirate.md). A layer's field is the sum
// of its kernels, so its spectrum is the kernel's (Lewis 1986 eq. 2: S = lambda E[a^2] |H|^2):
// a kernel many pixels wide has almost no energy near the pixels' Nyquist frequency, and
// evaluating every impulse at every pixel oversamples it. Here the impulses are evaluated on a
// lattice of spacing h pixels, chosen from |H|^2 so that the predicted rms error stays under a
// tolerance, and the field is reconstructed at the pixels by the interpolating cubic B-spline
// (a recursive prefilter, then 4 x 4 separable taps). Spacing 1 is direct evaluation, bit for
// bit.

#include "kernels/kernels.h"
#include "render/evaluate.h"

namespace impulse::render {

/// The largest tolerance a scene may ask for (rms error / the layer's sd): beyond it a frame's
/// reconstruction error would be plain to see.
inline constexpr double kMaxLatticeTolerance = 0.1;
/// The default tolerance (render.tolerance = 0.005): 0.5 % of a layer's sd, under an 8-bit
/// frame's quantisation noise (1/sqrt(12) of a code in +-3 sd over 255 codes: 0.57 %). With it
/// the rule also keeps the spectrum (kSpectralFidelity; docs/multirate.md §5).
inline constexpr double kRecommendedLatticeTolerance = 0.005;
/// The spectral density of that quantisation noise, white over the pixels' band: (6/255)^2 / 12
/// of the field's variance per (cycle/px)^2. Below it a frequency's power is not seen in an
/// 8-bit frame.
inline constexpr double kQuantisationDensity = (6.0 / 255.0) * (6.0 / 255.0) / 12.0;
/// The largest mean-square error the lattice may add at any one frequency, as a fraction of
/// that frequency's power; where that is below kQuantisationDensity, up to the latter (the
/// error is then under the noise every 8-bit frame carries at that frequency). The frame's
/// power spectrum is within ~2 sqrt(1e-3) = 6 % of the kernel's wherever the power is 1000x
/// the quantisation density, within the density itself below.
inline constexpr double kSpectralFidelity = 1e-3;
/// The coarsest lattice tried, pixels.
inline constexpr int kMaxLatticeSpacing = 64;

/// How one layer is evaluated: the lattice spacing and its predicted error.
struct LatticeRule {
    int spacing = 1;               ///< h, pixels between lattice nodes; 1 = direct evaluation
    int margin = 0;                ///< lattice nodes evaluated beyond the view on each side
    double predicted_error = 0.0;  ///< predicted rms error at the pixels / the field's sd
    /// The error the next coarser spacing would have (why it was not taken); 0 when none was
    /// tried.
    double next_error = 0.0;
    /// The chosen spacing's and the next one's worst per-frequency error (LatticeError::spectral;
    /// 0 when the spectrum was not asked to be kept or none was tried).
    double spectral_error = 0.0, next_spectral = 0.0;
    /// The rule's quadrature would have needed more working memory than it was given: direct.
    bool over_memory = false;
};

/// The parts of the predicted rms error (each / the field's sd) of sampling a layer of
/// `kernel` every h pixels and reconstructing with the interpolating cubic B-spline, averaged
/// over the h x h phases of the pixels between the nodes and over the field's randomness:
/// sqrt( int |H(k)|^2 e(k) dk / int |H(k)|^2 dk ), with e(k) = 1 - 2 Re(G(kx) G(ky)) +
/// A(kx) A(ky) the per-frequency error of the separable interpolator (G the phase-averaged
/// response, A the phase-averaged squared response; docs/multirate.md §2), by a midpoint rule
/// fine enough to be exact for the kernel's support (§3), the energy beyond the quadrature's
/// reach bounded, the prefilter's cut at `margin` nodes bounded by 3 |z|^margin.
/// `spectral` is the worst over the quadrature's frequencies of |H|^2 e(k) / max(|H|^2, floor /
/// kSpectralFidelity), the floor kQuantisationDensity of the variance in the kernel's units:
/// the error a frequency adds against its own power, or against the 8-bit noise where the power
/// is low (the energy beyond the quadrature's reach is bounded in `beyond`, not per frequency).
struct LatticeError {
    double interpolation = 0.0;  ///< aliasing and interpolation, quadrature
    double beyond = 0.0;         ///< bound on the energy the quadrature does not reach
    double boundary = 0.0;       ///< the recursive prefilter cut at the margin
    double spectral = 0.0;       ///< worst per-frequency error (above)
    double total() const;        ///< the first three added in quadrature
};
/// `units_per_pixel` is the view's scale (texture units per pixel). Anisotropic, Gabor and grid
/// kernels take the largest error over eight turns of the kernel in [0, pi/2) (orientation
/// fields and per-impulse angles turn them). Deterministic.
LatticeError lattice_error(const kernels::Kernel& kernel, double units_per_pixel, int h, int margin);

/// The lattice nodes beyond the view the prefilter needs for `tolerance` (|z|^m <= tolerance / 20,
/// z = sqrt(3) - 2, and 2 more for the interpolation's stencil).
int lattice_margin(double tolerance);

/// The coarsest spacing (1, 2, 3, ... up to kMaxLatticeSpacing and a third of the kernel's radius)
/// whose predicted error is within
/// `tolerance` (rms / sd, in [0, kMaxLatticeTolerance]) and, with `keep_spectrum`, whose
/// spectral error is within kSpectralFidelity; spacing 1 for tolerance 0 or when even spacing 2
/// misses them. Throws ValueError for a tolerance outside that range. The renderer always keeps
/// the spectrum: the rms criterion alone is for measuring it (tests, benches).
/// `max_bytes` bounds the quadrature's working grids (|H|^2 on n^2 points per turn of the
/// kernel, 8 bytes a point): a kernel whose rule would need more is drawn directly
/// (over_memory), so a scene's memory limit bounds the rule's time too.
LatticeRule choose_lattice(const kernels::Kernel& kernel, double units_per_pixel, double tolerance,
                           bool keep_spectrum = true, double max_bytes = 1e300);

/// The lattice of `rule` over `view`: node n (n = -margin ..) sits on the centre of pixel n h,
/// its view's pixels are the nodes. Spacing 1 with margin 0: the view itself.
View lattice_view(const View& view, const LatticeRule& rule);

/// Adds to `out` (sized to `view`) the field reconstructed from `nodes`, samples of the field at
/// lattice_view(view, rule) (a frame of that view's size): the cubic B-spline prefilter along
/// rows and columns, then 4 x 4 taps per pixel (separable). Deterministic (fixed order, no FMA
/// contraction), the same bits for any thread count.
void add_reconstruction(Frame& nodes, const LatticeRule& rule, const View& view, Frame& out);

/// Adds the field of `impulses` to `out` (sized to the view) through the lattice of `rule`: the
/// impulses evaluated at the nodes by render::accumulate, then add_reconstruction. The impulses
/// must cover lattice_view(view, rule)'s box (within the kernel's radius). With spacing 1 it is
/// render::accumulate, bit for bit.
void accumulate_lattice(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                        const View& view, const LatticeRule& rule, Frame& out,
                        const EvalOptions& options = {});

}  // namespace impulse::render
