// SPDX-License-Identifier: Apache-2.0
#pragma once
// The inner loops of the perspective evaluator (internal to impulse::render). Like
// eval_detail.h: one source (persp_loops.inc) compiled for baseline x86-64 and for AVX2 with FMA
// contraction off, so both round identically. Everything here is in texture units relative to
// the frame origin, except image positions (continuous pixels, pixel i spans [i, i + 1)).
// docs/perspective.md derives each mode (§3-4) and the plan (§2).

#include <cstddef>
#include <cstdint>

#include "kernels/kernels.h"
#include "render/render.h"

namespace impulse::render::detail {

/// One pyramid level as the loops see it.
struct PerspLevel {
    float radius = 1, inv_r2 = 1;  ///< support R_l and 1 / R_l^2
    const float* table = nullptr;  ///< radial: h_l at q = r^2 / R_l^2, linear
    int table_n = 0;
    /// radial, when a short series fits h_l to 1e-6 of h_l(0): its Chebyshev coefficients in q
    /// (kernels::EnvelopePolynomial), evaluated instead of `table` (arithmetic, no gathers)
    const float* poly = nullptr;
    int poly_n = 0;
    const float* line_p = nullptr;   ///< radial: line mass P and chord variance q at
    const float* line_q = nullptr;   ///< t = v^2 / R_l^2, linear; and the chord's
    const float* line_k4 = nullptr;  ///< fourth cumulant (Edgeworth correction)
    int line_n = 0;
    const float* grid = nullptr;  ///< grid levels: n x n over [-R_l, R_l]^2, bilinear
    int grid_n = 0;
    /// radial: h_l blurred along the major axis (kernels::RadialLevelTables::axial): `slices`
    /// tables of nv x nu samples, slice k for the extra variance k / axial_inv_dvar, over
    /// [0, axial_extent[k]] along and [0, R_l] across
    const float* axial = nullptr;
    const float* axial_extent = nullptr;
    int axial_nu = 0, axial_nv = 0, axial_slices = 0;
    float axial_inv_dvar = 0;
};

struct PerspKernel {
    bool radial = true;
    const PerspLevel* levels = nullptr;
    /// Per image row j: rows[4 j .. 4 j + 3] = (x0, y0, dx, dy), the texture point of pixel
    /// (i, j) being (x0 + i dx, y0 + i dy) relative to the origin (NaN: the row misses the plane).
    const double* rows = nullptr;
};

enum PerspMode : uint8_t { kPerspSingle = 0, kPerspProbes = 1, kPerspLine = 2, kPerspAxial = 3 };

/// How one impulse is filtered: the plan for a footprint (texture units per pixel).
struct Plan {
    bool keep = false;
    double fade = 1.0;
    uint8_t mode = kPerspSingle;
    kernels::KernelPyramid::Blend blend;
    double var_lo = 0, var_hi = 0;  ///< line, axial: extra variance along the major axis, texture
                                    ///< units^2, per level
    int m = 0;                      ///< probes: 2m + 1
    double sigma_e = 0, step = 0;   ///< probes: Gaussian sd along the axis, spacing
    double along = 0, across = 0;   ///< texture half-extents of the support (region, boxes)
};
/// The pixel filter's standard deviation in (possibly supersampled) pixels.
double filter_sigma_px(const AntiAlias& aa);
/// The plan for an impulse whose footprint is s_major x s_minor texture units per pixel
/// (render/perspective.h: single, axial, probes or line, and the fade).
Plan plan_for(const kernels::KernelPyramid& pyr, const AntiAlias& aa, double s_major,
              double s_minor);

/// One probe of an impulse: its offset from the impulse, weight and clipped image box.
struct PerspProbe {
    float dx = 0, dy = 0;                  ///< offset along the major axis, texture units
    float w = 0;                           ///< impulse weight * fade * Gaussian probe weight
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  ///< pixels touched (inclusive), clipped to the image
};

/// An impulse prepared for the loops.
struct PerspItem {
    float px = 0, py = 0;    ///< texture position relative to the origin
    float sx = 0, sy = 0;    ///< image position
    float w = 0;             ///< weight * fade (single, line)
    float cs = 1, sn = 0;    ///< cos, sin of the total orientation (grid kernels)
    float a = 0;             ///< weight of level hi in the blend
    int16_t lo = 0, hi = 0;  ///< levels
    uint8_t mode = kPerspSingle;
    float ix = 0, iy = 1;  ///< line: image direction of the footprint's major axis
    float inv_smaj = 1;    ///< line: 1 / s_major (pixels per texture unit along the major axis)
    float smin = 1;        ///< line: s_minor (texture units per pixel across)
    /// line: half the second derivative of the image position along the axis per texture unit
    /// moved along it (pixels / unit^2): the chord's image centroid sits at curv * q(v).
    float curv = 0;
    /// line: d ln(s_minor) / d(image offset along the axis): the keystone (nearer is wider).
    float keystone = 0;
    /// extra blur along the major axis per level: line: pixels^2; axial: texture units^2
    float var_lo = 0, var_hi = 0;
    float ex = 1, ey = 0;  ///< axial: texture direction of the footprint's major axis
    uint32_t probe0 = 0, nprobe = 0;       ///< probes: range in the probe array
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  ///< pixels touched (inclusive), clipped to the image
};

/// The inner loops, compiled for baseline x86-64 and for AVX2 (same bits).
struct PerspLoops {
    /// Adds items idx[0..n) to the tile covering pixels [tx0, tx0+tw) x [ty0, ty0+th); `acc` is
    /// tw*th floats. X, Y: texture coordinates of all pixel centres (row stride `stride`).
    void (*tile)(const PerspKernel& k, const PerspItem* items, const PerspProbe* probes,
                 const uint32_t* idx, size_t n, const float* X, const float* Y, int stride, int tx0,
                 int ty0, int tw, int th, float* acc);
    /// Far field, across: X[n] = sum_{k = -m..m} D[n - k] T[k] for n in [n0, n1) (D readable
    /// on [n0 - m, n1 + m), T on [-m, m]), summed from 0 in order of k.
    void (*far_across)(const float* D, const float* T, int m, int n0, int n1, float* X);
    /// Far field, along: for pixels i in [0, n) of a row, from the sub-row at y' = yr,
    /// acc[i] += sum_q g_q(u) x[q][i], g_q the q-th derivative (q = 0 .. 4) of
    /// g(u) = exp(-u^2 / (2 s)) / sqrt(s), u = (yp[i] - yr) * inv_kappa[i], s = 1 / inv_s[i],
    /// rsqrt_s[i] = 1 / sqrt(s). terms: bit 0: x[2], x[4] are used; bit 1: x[1], x[3].
    void (*far_along)(const float* yp, const float* inv_kappa, const float* inv_s,
                      const float* rsqrt_s, int n, float yr, const float* const* x, int terms,
                      float* acc);
};
extern const PerspLoops kPerspLoopsBase, kPerspLoopsAvx2;

}  // namespace impulse::render::detail
