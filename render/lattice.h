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
/// The recommended tolerance (render.tolerance = 0.005): 0.5 % of a layer's sd, under an 8-bit
/// frame's quantisation noise (1/sqrt(12) of a code in +-3 sd over 255 codes: 0.57 %). Not yet
/// the default: per-annulus spectral tests still see the lattice's signature near its Nyquist
/// frequency (docs/multirate.md §5).
inline constexpr double kRecommendedLatticeTolerance = 0.005;
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
};

/// The parts of the predicted rms error (each / the field's sd) of sampling a layer of
/// `kernel` every h pixels and reconstructing with the interpolating cubic B-spline, averaged
/// over the h x h phases of the pixels between the nodes and over the field's randomness:
/// sqrt( int |H(k)|^2 e(k) dk / int |H(k)|^2 dk ), with e(k) = 1 - 2 Re(G(kx) G(ky)) +
/// A(kx) A(ky) the per-frequency error of the separable interpolator (G the phase-averaged
/// response, A the phase-averaged squared response; docs/multirate.md §2), by a midpoint rule
/// fine enough to be exact for the kernel's support (§3), the energy beyond the quadrature's
/// reach bounded, the prefilter's cut at `margin` nodes bounded by 3 |z|^margin.
struct LatticeError {
    double interpolation = 0.0;  ///< aliasing and interpolation, quadrature
    double beyond = 0.0;         ///< bound on the energy the quadrature does not reach
    double boundary = 0.0;       ///< the recursive prefilter cut at the margin
    double total() const;        ///< the three added in quadrature
};
/// `units_per_pixel` is the view's scale (texture units per pixel). Anisotropic, Gabor and grid
/// kernels take the largest error over eight turns of the kernel in [0, pi/2) (orientation
/// fields and per-impulse angles turn them). Deterministic.
LatticeError lattice_error(const kernels::Kernel& kernel, double units_per_pixel, int h, int margin);

/// The lattice nodes beyond the view the prefilter needs for `tolerance` (|z|^m <= tolerance / 20,
/// z = sqrt(3) - 2, and 2 more for the interpolation's stencil).
int lattice_margin(double tolerance);

/// The coarsest spacing (1, 2, 3, ... up to kMaxLatticeSpacing) whose predicted error is within
/// `tolerance` (rms / sd, in [0, kMaxLatticeTolerance]); spacing 1 for tolerance 0 or when
/// even spacing 2 misses it. Throws ValueError for a tolerance outside that range.
LatticeRule choose_lattice(const kernels::Kernel& kernel, double units_per_pixel, double tolerance);

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
