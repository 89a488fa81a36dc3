// SPDX-License-Identifier: Apache-2.0
#pragma once
// Anti-aliased rendering through cameras (part of impulse::render; included by render/render.h):
// the orthographic view zoomed out, and a perspective camera looking at the texture plane, both
// choosing band-limited kernels from a pyramid (kernels/pyramid.h) by the pixel footprint
// (Lewis 1986 §3.1 "selecting appropriate precomputed bandlimited versions of the kernel as a
// function of depth").
//
// The pixel filter is a Gaussian of standard deviation `filter_px` pixels. Its footprint on the
// texture plane at a point is an ellipse: sd filter_px * s_major along the direction that
// recedes and filter_px * s_minor across it (s = texture units per pixel, the singular values of
// the inverse Jacobian of the texture -> image map). Each impulse gets the filter of the
// footprint at its own position (the map is locally affine over a kernel that is small compared
// with its depth):
//   * single: the isotropic level for s_major blended with its neighbour (orthographic views,
//     near-isotropic footprints, or `anisotropic = false`: the conservative major-axis rule);
//   * axial: for radial kernels (of either sign), the level for s_minor convolved along the
//     major axis with a 1-D Gaussian of the variance it lacks there (sd_major^2 less the level's
//     own blur), read from the level's tables of such blurs (KernelPyramid::tables(l).axial:
//     bilinear in the offset along and across, linear between the two tabulated variances that
//     bracket it): one evaluation per pixel, where the probes below took 2m + 1;
//   * probes: the isotropic level for s_minor, repeated at Gaussian-weighted points along the
//     major axis (footprint assembly) so the blur is sd_major along and sd_minor across: for
//     non-radial kernels (gabor, elliptical, grids, exemplars: their blurred levels would need a
//     table per orientation) and for radial ones blurred beyond the tables' range;
//   * line: for strongly anisotropic footprints of non-negative radial kernels, the level for
//     s_minor projected across (a 1-D table P(v) with its chord variance q(v)) times a Gaussian
//     along the major axis evaluated in image space: exact in the limit, cost independent of the
//     anisotropy.
//   * far field: where the kernel's image is a sliver no taller than the pixel filter (the
//     chords' spread along the axis small against it), impulses are deposited on sub-rows that
//     follow the circles round the camera's foot, convolved across with the line form's profile
//     and filtered along per pixel (render/detail/persp_far.h): a few additions per impulse and a
//     bounded amount of work per pixel, for radial and (through chords tabulated per direction)
//     other non-negative kernels.
// Far away the filtered noise tends to its mean: the remaining standard deviation of the
// major-axis filtered kernel (KernelPyramid::sd_fraction) fades the impulses out between
// 2 * cutoff and cutoff, and none are generated beyond, so the work per frame stays bounded
// however close the horizon is.
//
// docs/perspective.md derives the forms (§3-4), the far field (§5) and the cut-off (§6) with
// these symbols.
//
// Determinism: every pixel sums its impulses in canonical order (and an impulse's probes or
// table slices in order), each pixel is written by one task, and the per-pixel code uses only
// + - * / sqrt and the polynomial exp of the evaluator, compiled for baseline x86-64 and AVX2
// without FMA contraction: the bits do not depend on threads, tiles or the CPU.

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "kernels/kernels.h"
#include "render/evaluate.h"
#include "sim/sim.h"

namespace impulse::render {

/// Anti-aliasing options (scene keys camera.antialias, filter, cutoff, anisotropic).
struct AntiAlias {
    bool enabled = true;      ///< false: the unfiltered kernel everywhere ("off"; the
                              ///< perspective cut-off still applies unless `fade` is false)
    bool blend = true;        ///< false: nearest level instead of blending two ("nearest")
    bool anisotropic = true;  ///< false: isotropic levels from the major axis only
    double filter_px = 0.5;   ///< pixel filter: a Gaussian of this sd in pixels, > 0
    double cutoff = 0.01;     ///< fade out where the remaining sd < cutoff * unfiltered sd, (0, 1)
    bool fade = true;         ///< false: no fade and no cut-off (test references only)
    /// > 0: drop impulses farther than this from the camera's foot on the plane, in texture units
    /// (bounds unfiltered reference renders, which have no cut-off).
    double max_distance = 0.0;
    /// Pixel footprints are multiplied by this (tests): a render at k times the resolution with
    /// footprint_scale k applies the 1x filter, sampled k times finer. >= 1.
    double footprint_scale = 1.0;
    /// false: no far field; the line form draws every impulse it applies to (tests, benchmarks).
    bool far_field = true;

    bool operator==(const AntiAlias&) const = default;
};

/// Fade factor in [0, 1] for a remaining standard deviation fraction `sd` (0 at or below
/// cutoff, 1 at or above 2 cutoff, smoothstep in log sd between).
double fade_weight(double sd, double cutoff);

// ---------------------------------------------------------------------------------------------
// Orthographic views

/// Adds the impulses to `out` like render::accumulate, with the kernel low-passed for the view's
/// footprint (sd filter_px * view.scale texture units): the two bracketing pyramid levels
/// weighted 1 - w and w (two passes of the tiled evaluator), faded by fade_weight. Footprints
/// at or below sigma_0 use the kernel itself (identical bits to render::accumulate). Impulses
/// must cover view.box() expanded by `filtered_support(...)`.
void accumulate_filtered(const kernels::KernelPyramid& pyramid, const sim::Impulses& impulses,
                         const View& view, Frame& out, const AntiAlias& aa,
                         const EvalOptions& options = {});
/// Support radius (texture units) of the kernel used for `view`: the largest blended level's.
double filtered_support(const kernels::KernelPyramid& pyramid, const View& view,
                        const AntiAlias& aa);
/// Fade factor of an orthographic view (0: the layer is its mean; impulses need not be made).
double filtered_fade(const kernels::KernelPyramid& pyramid, const View& view, const AntiAlias& aa);

// ---------------------------------------------------------------------------------------------
// Perspective camera

/// Which plane the camera looks at: the ground (z = 0, camera `height` above it, looking down)
/// or the sky (a plane `height` above the camera, looking up: the mirror image of the ground
/// view, the horizon at the bottom of the sky).
enum class Plane { Ground, Sky };

/// A pinhole camera over the texture plane. Angles in degrees. Heading: direction of view on
/// the plane, 0 towards -y (the top of the orthographic view, +x to the right), 90 towards +x.
/// Pitch: angle of the view axis below the horizon (ground) or above it (sky); 90 looks
/// straight down (up) and shows the plane like the orthographic view.
struct PerspectiveCamera {
    int width = 0, height = 0;  ///< image size in pixels
    double x = 0.0, y = 0.0;    ///< the camera's foot on the plane, texture units
    double altitude = 100.0;    ///< distance from the plane, texture units, > 0
    double pitch_deg = 20.0;    ///< in [-90, 90]
    double heading_deg = 0.0;
    double fov_deg = 60.0;  ///< vertical field of view, in (0, 180)
    Plane plane = Plane::Ground;
    /// Internal: focal length and principal point in pixels (0 / NaN: from fov and the image
    /// centre). Set by `window` for supersampling and strips.
    double focal_px = 0.0;
    double principal_x = std::numeric_limits<double>::quiet_NaN();
    double principal_y = std::numeric_limits<double>::quiet_NaN();

    /// The camera that renders image rectangle [x0, x0 + w) x [y0, y0 + h) of this one with
    /// `samples` x `samples` pixels per pixel (same rays: a supersampled or cropped copy).
    PerspectiveCamera window(int x0, int y0, int w, int h, int samples = 1) const;
    /// Whether the two cameras see the same rays: every field equal, NaN principal points ("from
    /// the image centre") equal to each other.
    bool same_rays(const PerspectiveCamera& other) const;
};

/// Geometry of a perspective camera: rays, projection, pixel footprints. Image coordinates are
/// continuous pixels: pixel (i, j) covers [i, i + 1) x [j, j + 1), row 0 at the top.
class PerspectiveView {
public:
    /// Validates (throws ValueError naming the field: altitude > 0, fov in (0, 180), pitch in
    /// [-90, 90], a visible part of the plane).
    explicit PerspectiveView(const PerspectiveCamera& camera);
    const PerspectiveCamera& camera() const { return m_cam; }
    /// Focal length in pixels.
    double focal_px() const { return m_f; }

    /// The texture point seen at image point (px, py); false when the ray misses the plane.
    bool texture_point(double px, double py, double& x, double& y) const;
    /// The image point of texture point (x, y); false when it is behind the camera.
    bool image_point(double x, double y, double& px, double& py) const;
    /// Distance along the view axis of texture point (x, y) (> 0 in front of the camera).
    double depth(double x, double y) const;

    /// Pixel footprint at a texture point: texture units per pixel along the major and minor
    /// axes, the major axis in texture space (ex, ey) and its image direction (ix, iy).
    struct Footprint {
        double s_major = 0, s_minor = 0;
        double ex = 1, ey = 0, ix = 0, iy = 1;
    };
    Footprint footprint(double x, double y) const;

    /// Image row of the horizon (may lie outside the image); rows beyond it miss the plane.
    double horizon_row() const;

    /// The projection as a homography of the texture point relative to the camera's foot:
    /// with (u, v, w) = P (x - foot_x, y - foot_y, 1), the image point is (u / w, v / w) and
    /// w > 0 in front of the camera (w is the depth). Row-major 3x3.
    void homography(double P[9]) const;

    /// The image row of the point at distance rho straight ahead of the camera's foot (along
    /// the heading): Y(rho) = (a rho + b) / (c rho + d). The far field labels the circles
    /// around the foot by it.
    void range_row(double& a, double& b, double& c, double& d) const;

    /// The texture points of the pixel centres (i + 0.5, py), i in [0, n), minus (ox, oy), as
    /// floats: the arithmetic of texture_point, one division per row. Points that miss the plane
    /// (or lie beyond 1e15) get hit 0 and a far coordinate.
    void texture_row(double py, int n, double ox, double oy, float* x, float* y,
                     uint8_t* hit) const;
    /// The same row as a line: the texture point of pixel centre (i + 0.5, py) is
    /// (x0 + i dx, y0 + i dy) - (ox, oy); false (NaNs) when the row misses the plane.
    bool row_line(double py, double ox, double oy, double line[4]) const;

private:
    PerspectiveCamera m_cam;
    double m_f = 0, m_cx = 0, m_cy = 0;
    double m_z = 0;                 // eye height above the plane along the plane normal sign
    double m_F[3], m_R[3], m_U[3];  // forward, right, up (image up) unit vectors
};

/// Texture coordinates of the pixel centres of a view, relative to an origin (so floats stay
/// small): (x[p], y[p]) for pixel p = j * width + i, `hit` 0 above the horizon.
struct PixelCoords {
    int width = 0, height = 0;
    double origin_x = 0, origin_y = 0;
    std::vector<float> x, y;
    std::vector<uint8_t> hit;
    /// Per row j, (x0, y0, dx, dy): the texture point of pixel (i, j) is (x0 + i dx, y0 + i dy)
    /// relative to the origin, in double (NaN for rows that miss the plane).
    std::vector<double> rows;
};
/// Computes the pixel coordinates (origin: the camera's foot). Deterministic; parallel by rows.
PixelCoords pixel_coords(const PerspectiveView& view);

/// The texture region that must hold the impulses for a frame: every visible point whose
/// impulses are not faded out (nor beyond aa.max_distance), expanded by the support they would
/// have there, as a union of boxes that follows the visible wedge of the plane (its bounding box
/// is about twice its area). Pass it to sim::LayerSimulator::impulses_at. Empty when nothing is
/// visible.
numeric::Region perspective_region(const kernels::KernelPyramid& pyramid, const PerspectiveView& view,
                               const AntiAlias& aa);

/// Counts of the last perspective evaluation (for benchmarks and tests).
struct PerspectiveStats {
    size_t impulses = 0;  ///< impulses given
    size_t culled = 0;    ///< faded out, behind the camera, beyond max_distance or off-image
    size_t single = 0, axial = 0, probes = 0, line = 0;  ///< impulses per filter form
    size_t far = 0;                           ///< impulses drawn by the far field
    /// Wall time of the parts (ms): far-field set-up, per-impulse preparation, tiled
    /// evaluation (binning included), far field (deposit, across, along).
    double setup_ms = 0, prepare_ms = 0, tiles_ms = 0, far_ms = 0;
    size_t probe_count = 0;  ///< probes evaluated
    size_t pixels = 0;       ///< pixel evaluations (sum of the impulses' and probes' boxes)
};

namespace detail {
struct PerspScratch;
}

/// Memory that accumulate_perspective keeps from call to call: a frame's per-impulse arrays are
/// tens of megabytes, and memory new to the process costs a page fault per 4 KiB on every frame.
/// It also keeps the far field's set-up (a few ms at 1080p) while the pyramid, the camera's rays
/// and the anti-aliasing options stay the same. Optional; keep one per caller that renders frame
/// after frame (one per layer). Safe to share: a call that finds the workspace in use by another
/// uses memory of its own.
class PerspectiveWorkspace {
public:
    PerspectiveWorkspace();
    ~PerspectiveWorkspace();
    PerspectiveWorkspace(const PerspectiveWorkspace&) = delete;
    PerspectiveWorkspace& operator=(const PerspectiveWorkspace&) = delete;
    /// (internal) The memory, or null while another call holds it; give it back with release().
    detail::PerspScratch* acquire();
    void release();

private:
    std::unique_ptr<detail::PerspScratch> m_scratch;
    std::atomic<bool> m_busy{false};
};

/// Adds sum_k w_k h_k(X(p) - x_k) to `out` (resized to the view, not cleared) for every pixel p
/// that sees the plane, h_k the kernel filtered for the footprint at x_k (see the header
/// comment). Deterministic (tile and thread independent); AVX2 where available, same bits.
/// `workspace` (optional) lends memory reused across calls; it does not change the result.
void accumulate_perspective(const kernels::KernelPyramid& pyramid, const sim::Impulses& impulses,
                            const PerspectiveView& view, const PixelCoords& coords, Frame& out,
                            const AntiAlias& aa, const EvalOptions& options = {},
                            PerspectiveStats* stats = nullptr,
                            PerspectiveWorkspace* workspace = nullptr);

}  // namespace impulse::render
