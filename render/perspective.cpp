// SPDX-License-Identifier: Apache-2.0
// Anti-aliased evaluation through cameras: orthographic zoom-out with blended pyramid levels,
// and the perspective camera (geometry, region of the plane to populate, per-impulse filters,
// tiled evaluation). Lewis 1986 §3.1: band-limited kernels selected by depth. The derivation:
// docs/perspective.md.

#include "render/perspective.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "numeric/cpu.h"
#include "render/detail/persp.h"
#include "render/detail/persp_far.h"
#include "numeric/errors.h"

namespace impulse::render {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr float kFar = 1e18f;     // texture coordinate of pixels that miss the plane
constexpr int kMaxProbeHalf = 8;  // at most 2 * 8 + 1 probes per impulse
// Radial levels whose Chebyshev series has at most this many terms are evaluated by it rather
// than by their table (the cosine kernel itself: 7 terms, its blurred levels 15-41). Measured on
// impulse_bench_perspective, whose near field is nearly all level 0: 24 was no faster.
constexpr size_t kMaxPolyTerms = 12;
// The line form is used once the blur along the major axis reaches this fraction of the level's
// support radius (empirical: against supersampled references of a cosine kernel the line form
// is within 1-3 % of a single impulse's filtered kernel from there on, better than probes,
// whose texture-space Gaussian ignores the perspective bend of the footprint).
constexpr double kLineFrom = 0.25;

void require(bool ok, const std::string& what) {
    if (!ok) throw ValueError(what);
}

/// Variance of the Gaussian blur level l actually carries (level 0, the kernel itself, none).
double blur2(const kernels::KernelPyramid& pyr, int l) {
    return l == 0 ? 0.0 : pyr.sigma(l) * pyr.sigma(l);
}

/// Half-extent along the axis of level l's axial table for an extra variance `var`: that of the
/// slice above it, the wider of the two the loops blend.
double axial_along(const kernels::KernelPyramid& pyr, int l, double var) {
    const auto& t = pyr.tables(l);
    const int last = static_cast<int>(t.axial_extent.size()) - 1;
    const int s = std::min(last, static_cast<int>(std::ceil(var / t.axial_var_max * last)));
    return t.axial_extent[size_t(s)];
}

/// Probe offsets (units of the axis) and weights for a plan: Gaussian weights at (j - m) step,
/// positions rescaled so the discrete variance is exactly sigma_e^2.
void probe_weights(const detail::Plan& p, std::array<double, 2 * kMaxProbeHalf + 1>& t,
                   std::array<double, 2 * kMaxProbeHalf + 1>& w) {
    const int n = 2 * p.m + 1;
    double sw = 0.0;
    for (int j = 0; j < n; ++j) {
        t[size_t(j)] = (j - p.m) * p.step;
        w[size_t(j)] = std::exp(-0.5 * t[size_t(j)] * t[size_t(j)] / (p.sigma_e * p.sigma_e));
        sw += w[size_t(j)];
    }
    double var = 0.0;
    for (int j = 0; j < n; ++j) {
        w[size_t(j)] /= sw;
        var += w[size_t(j)] * t[size_t(j)] * t[size_t(j)];
    }
    const double scale = var > 0.0 ? p.sigma_e / std::sqrt(var) : 1.0;
    for (int j = 0; j < n; ++j) t[size_t(j)] *= scale;
}

/// Pixel box (inclusive, clipped to the image) of continuous image rectangle [xa, xb] x [ya, yb]
/// with one pixel of margin.
void pixel_box(double xa, double xb, double ya, double yb, int W, int H, int& x0, int& y0, int& x1,
               int& y1) {
    auto cl = [](double v, int lo, int hi) {
        return static_cast<int>(std::clamp(v, static_cast<double>(lo), static_cast<double>(hi)));
    };
    x0 = cl(std::floor(xa) - 1.0, -1, W), x1 = cl(std::floor(xb) + 1.0, -1, W);
    y0 = cl(std::floor(ya) - 1.0, -1, H), y1 = cl(std::floor(yb) + 1.0, -1, H);
    x0 = std::max(x0, 0), y0 = std::max(y0, 0), x1 = std::min(x1, W - 1), y1 = std::min(y1, H - 1);
}

}  // namespace

namespace detail {

double filter_sigma_px(const AntiAlias& aa) { return aa.filter_px * aa.footprint_scale; }

namespace {

/// Single form (docs/perspective.md §3.1): the isotropic blend for `sigma`, its support both ways.
Plan single_plan(Plan& p, const kernels::KernelPyramid& pyr, const AntiAlias& aa, double sigma) {
    p.mode = detail::kPerspSingle;
    p.blend = pyr.select(sigma, aa.blend);
    p.along = p.across = pyr.radius(std::max(p.blend.lo, p.blend.hi));
    return p;
}

/// Axial form (docs/perspective.md §3.2), for radial kernels where the levels' axial tables
/// cover the blur each needs: one evaluation per pixel (the variance along adds: h_l * g_(var_l)
/// has sM^2 more than h along). False, `p` untouched, where they do not.
bool axial_plan(Plan& p, const kernels::KernelPyramid& pyr, double sM) {
    const int lo = p.blend.lo, hi = p.blend.hi;
    if (!pyr.radial()) return false;
    const double vlo = std::max(0.0, sM * sM - blur2(pyr, lo)),
                 vhi = std::max(0.0, sM * sM - blur2(pyr, hi));
    if (!(vlo <= pyr.tables(lo).axial_var_max && vhi <= pyr.tables(hi).axial_var_max))
        return false;
    p.mode = detail::kPerspAxial;
    p.var_lo = vlo, p.var_hi = vhi;
    p.across = pyr.radius(std::max(lo, hi));
    p.along = std::max(axial_along(pyr, lo, vlo), axial_along(pyr, hi, vhi));
    return true;
}

/// Line form (docs/perspective.md §4): the variances the levels lack along the axis, the support
/// across and 4 sd of the widest chord Gaussian along.
Plan line_plan(Plan& p, const kernels::KernelPyramid& pyr, double sM) {
    p.mode = detail::kPerspLine;
    p.var_lo = std::max(0.0, sM * sM - blur2(pyr, p.blend.lo));
    p.var_hi = std::max(0.0, sM * sM - blur2(pyr, p.blend.hi));
    const double R = pyr.radius(std::max(p.blend.lo, p.blend.hi));
    p.across = R;
    p.along = 4.0 * std::sqrt(sM * sM + R * R / 3.0) + R;
    return p;
}

/// Too anisotropic for the probe budget (grid kernels): the isotropic part widened until
/// 3 sqrt(sM^2 - si^2) <= 2 m sqrt(s0^2 + si^2) with m = kMaxProbeHalf (docs/perspective.md
/// eq. 3.3).
double widened_sigma(double sM, double si, double s0) {
    const double mm = kMaxProbeHalf;
    const double s2 = (9.0 * sM * sM - 4.0 * mm * mm * s0 * s0) / (9.0 + 4.0 * mm * mm);
    return std::max(si, std::sqrt(std::max(0.0, s2)));
}

/// Probe form (docs/perspective.md §3.3): probes add what the blended levels do not carry
/// along the axis.
Plan probe_plan(Plan& p, const kernels::KernelPyramid& pyr, double sM, double spacing) {
    const double carried =
        (1.0 - p.blend.weight) * blur2(pyr, p.blend.lo) + p.blend.weight * blur2(pyr, p.blend.hi);
    const double se = std::sqrt(std::max(0.0, sM * sM - carried));
    const int m = std::clamp(static_cast<int>(std::ceil(3.0 * se / spacing)), 1, kMaxProbeHalf);
    p.mode = detail::kPerspProbes;
    p.m = m;
    p.sigma_e = se;
    p.step = 3.0 * se / m;
    const double R = pyr.radius(std::max(p.blend.lo, p.blend.hi));
    p.across = R;
    p.along = R + 3.1 * se;
    return p;
}

}  // namespace

// docs/perspective.md §2 (the split (2.1) and the order of the choices), §3-4 (the forms).
Plan plan_for(const kernels::KernelPyramid& pyr, const AntiAlias& aa, double s_major,
              double s_minor) {
    Plan p;
    const double c = filter_sigma_px(aa);
    const double sM = c * s_major, sm = c * s_minor;
    // The cut-off holds for unfiltered renders too (enabled = false): it bounds the work.
    p.fade = aa.fade ? fade_weight(pyr.sd_fraction(sM), aa.cutoff) : 1.0;
    if (!(p.fade > 0.0)) return p;
    p.keep = true;
    if (!aa.enabled) return single_plan(p, pyr, aa, 0.0);
    const double s0 = pyr.sigma(0);
    if (!aa.anisotropic || sM <= s0) return single_plan(p, pyr, aa, sM);
    // Isotropic part from the minor axis (level 0 stands for sigma_0), the rest along the major.
    double si = std::max(sm, s0);
    p.blend = pyr.select(si, aa.blend);
    double spacing = pyr.probe_spacing(p.blend.lo);
    double se = std::sqrt(std::max(0.0, sM * sM - si * si));
    if (3.0 * se < spacing) return single_plan(p, pyr, aa, sM);  // sM <= 1.2 si: below notice
    const bool line_ok =
        pyr.radial() && pyr.tables(p.blend.lo).nonnegative && pyr.tables(p.blend.hi).nonnegative;
    const int m = static_cast<int>(std::ceil(3.0 * se / spacing));
    if (line_ok && (se >= kLineFrom * pyr.radius(p.blend.lo) || m > kMaxProbeHalf))
        return line_plan(p, pyr, sM);
    if (axial_plan(p, pyr, sM)) return p;
    if (m > kMaxProbeHalf) {
        si = widened_sigma(sM, si, s0);
        p.blend = pyr.select(si, aa.blend);
        spacing = pyr.probe_spacing(p.blend.lo);
        se = std::sqrt(std::max(0.0, sM * sM - si * si));
        if (3.0 * se < spacing) return single_plan(p, pyr, aa, sM);
        if (axial_plan(p, pyr, sM)) return p;
    }
    return probe_plan(p, pyr, sM, spacing);
}

}  // namespace detail

double fade_weight(double sd, double cutoff) {
    if (!(sd > cutoff)) return 0.0;
    if (sd >= 2.0 * cutoff) return 1.0;
    const double s = std::log2(sd / cutoff);  // in (0, 1)
    return s * s * (3.0 - 2.0 * s);
}

// ---------------------------------------------------------------------------------------------
// Orthographic

double filtered_fade(const kernels::KernelPyramid& pyr, const View& view, const AntiAlias& aa) {
    if (!aa.enabled || !aa.fade) return 1.0;
    return fade_weight(pyr.sd_fraction(detail::filter_sigma_px(aa) * view.scale), aa.cutoff);
}

double filtered_support(const kernels::KernelPyramid& pyr, const View& view, const AntiAlias& aa) {
    if (!aa.enabled) return pyr.radius(0);
    const auto b = pyr.select(detail::filter_sigma_px(aa) * view.scale, aa.blend);
    return pyr.radius(std::max(b.lo, b.hi));
}

void accumulate_filtered(const kernels::KernelPyramid& pyr, const sim::Impulses& impulses,
                         const View& view, Frame& out, const AntiAlias& aa,
                         const EvalOptions& options) {
    if (out.width != view.width || out.height != view.height) out.resize(view.width, view.height);
    if (!aa.enabled) return accumulate(pyr.base(), impulses, view, out, options);
    if (!impulses.scale.empty())
        throw ValueError(
            "render::accumulate_filtered: impulses with scales: draw each class of "
            "render::split_scale_classes with the pyramid of its scaled kernel");
    const double fade = filtered_fade(pyr, view, aa);
    if (!(fade > 0.0)) return;
    const auto b = pyr.select(detail::filter_sigma_px(aa) * view.scale, aa.blend);
    const bool two = b.lo != b.hi && b.weight > 0.0;
    if (!two && fade == 1.0) return accumulate(pyr.level(b.lo), impulses, view, out, options);
    // Two passes in a fixed order (every pixel: all of level lo, then all of level hi).
    sim::Impulses scaled = impulses;
    auto pass = [&](int level, double factor) {
        for (size_t i = 0; i < scaled.weight.size(); ++i)
            scaled.weight[i] = static_cast<float>(static_cast<double>(impulses.weight[i]) * factor);
        accumulate(pyr.level(level), scaled, view, out, options);
    };
    pass(b.lo, fade * (1.0 - b.weight));
    if (two) pass(b.hi, fade * b.weight);
}

// ---------------------------------------------------------------------------------------------
// Perspective camera

PerspectiveCamera PerspectiveCamera::window(int x0, int y0, int w, int h, int samples) const {
    PerspectiveCamera c = *this;
    const PerspectiveView v(*this);  // validates and resolves focal length and centre
    const double f = focal_px > 0.0 ? focal_px : 0.5 * height / std::tan(0.5 * fov_deg * kDeg);
    const double cx = std::isnan(principal_x) ? 0.5 * width : principal_x;
    const double cy = std::isnan(principal_y) ? 0.5 * height : principal_y;
    c.width = w * samples, c.height = h * samples;
    c.focal_px = f * samples;
    c.principal_x = (cx - x0) * samples;
    c.principal_y = (cy - y0) * samples;
    return c;
}

PixelBudgetError::PixelBudgetError(double n, double b)
    : BudgetError([&] {
          std::ostringstream s;
          s << "the frame needs " << n << " pixel evaluations, over the budget of " << b;
          return s.str();
      }()),
      needed(n),
      budget(b) {}

bool PerspectiveCamera::same_rays(const PerspectiveCamera& o) const {
    auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    return width == o.width && height == o.height && x == o.x && y == o.y &&
           altitude == o.altitude && pitch_deg == o.pitch_deg && heading_deg == o.heading_deg &&
           fov_deg == o.fov_deg && plane == o.plane && focal_px == o.focal_px &&
           same(principal_x, o.principal_x) && same(principal_y, o.principal_y);
}

PerspectiveView::PerspectiveView(const PerspectiveCamera& cam) : m_cam(cam) {
    auto num = [](double v) {
        std::ostringstream s;
        s << v;
        return s.str();
    };
    require(cam.width >= 1 && cam.height >= 1, "perspective camera: image size must be >= 1x1");
    require(std::isfinite(cam.altitude) && cam.altitude > 0.0,
            "height = " + num(cam.altitude) +
                ": expected a height > 0 above the plane (texture units)");
    require(
        std::isfinite(cam.fov_deg) && cam.fov_deg > 0.0 && cam.fov_deg < 180.0,
        "fov = " + num(cam.fov_deg) + ": expected a vertical field of view in (0, 180) degrees");
    require(std::isfinite(cam.pitch_deg) && cam.pitch_deg >= -90.0 && cam.pitch_deg <= 90.0,
            "pitch = " + num(cam.pitch_deg) + ": expected an angle in [-90, 90] degrees");
    require(std::isfinite(cam.heading_deg) && std::isfinite(cam.x) && std::isfinite(cam.y),
            "perspective camera: position and heading must be finite");
    m_f = cam.focal_px > 0.0 ? cam.focal_px : 0.5 * cam.height / std::tan(0.5 * cam.fov_deg * kDeg);
    m_cx = std::isnan(cam.principal_x) ? 0.5 * cam.width : cam.principal_x;
    m_cy = std::isnan(cam.principal_y) ? 0.5 * cam.height : cam.principal_y;
    const double s = cam.plane == Plane::Ground ? 1.0 : -1.0;  // sky: the mirror image
    const double h = cam.heading_deg * kDeg, p = cam.pitch_deg * kDeg;
    const double dx = std::sin(h), dy = -std::cos(h);  // heading direction on the plane
    const double cp = std::cos(p), sp = std::sin(p);
    m_F[0] = cp * dx, m_F[1] = cp * dy, m_F[2] = -s * sp;
    m_U[0] = s * sp * dx, m_U[1] = s * sp * dy, m_U[2] = cp;
    m_R[0] = std::cos(h), m_R[1] = std::sin(h), m_R[2] = 0.0;
    m_z = -s * cam.altitude;  // the plane's z relative to the eye
    // Some pixel must see the plane: the ray through the image edge nearest the plane.
    const double edge = cam.plane == Plane::Ground ? cam.height - 0.5 - m_cy : 0.5 - m_cy;
    const double dz = m_f * m_F[2] - edge * m_U[2];
    if (!(s * dz < 0.0)) {
        std::ostringstream m;
        m << "pitch = " << cam.pitch_deg << ": the camera sees no part of the "
          << (cam.plane == Plane::Ground ? "ground" : "sky")
          << " plane (expected pitch > -fov/2 = " << -0.5 * cam.fov_deg
          << " degrees, so the plane enters the frame)";
        throw ValueError(m.str());
    }
}

bool PerspectiveView::texture_point(double px, double py, double& x, double& y) const {
    const double a = px - m_cx, b = py - m_cy;
    const double d0 = m_f * m_F[0] + a * m_R[0] - b * m_U[0];
    const double d1 = m_f * m_F[1] + a * m_R[1] - b * m_U[1];
    const double d2 = m_f * m_F[2] + a * m_R[2] - b * m_U[2];
    const double t = m_z / d2;  // plane at z = m_z relative to the eye
    if (!(t > 0.0) || !std::isfinite(t)) return false;
    x = m_cam.x + t * d0;
    y = m_cam.y + t * d1;
    return std::isfinite(x) && std::isfinite(y);
}

double PerspectiveView::depth(double x, double y) const {
    return m_F[0] * (x - m_cam.x) + m_F[1] * (y - m_cam.y) + m_F[2] * m_z;
}

bool PerspectiveView::image_point(double x, double y, double& px, double& py) const {
    const double vx = x - m_cam.x, vy = y - m_cam.y, vz = m_z;
    const double q = m_F[0] * vx + m_F[1] * vy + m_F[2] * vz;
    if (!(q > 0.0)) return false;
    const double a = m_R[0] * vx + m_R[1] * vy + m_R[2] * vz;
    const double b = m_U[0] * vx + m_U[1] * vy + m_U[2] * vz;
    px = m_cx + m_f * a / q;
    py = m_cy - m_f * b / q;
    return true;
}

PerspectiveView::Footprint PerspectiveView::footprint(double x, double y) const {
    const double vx = x - m_cam.x, vy = y - m_cam.y, vz = m_z;
    const double q = m_F[0] * vx + m_F[1] * vy + m_F[2] * vz;
    const double a = m_R[0] * vx + m_R[1] * vy + m_R[2] * vz;
    const double b = m_U[0] * vx + m_U[1] * vy + m_U[2] * vz;
    const double k = m_f / (q * q);
    // Jacobian of (x, y) -> (px, py).
    const double A = k * (m_R[0] * q - a * m_F[0]), B = k * (m_R[1] * q - a * m_F[1]);
    const double C = -k * (m_U[0] * q - b * m_F[0]), D = -k * (m_U[1] * q - b * m_F[1]);
    // Eigen-decomposition of J^T J: the smaller eigenvalue's vector is the footprint's major axis.
    const double a11 = A * A + C * C, a22 = B * B + D * D, a12 = A * B + C * D;
    const double mid = 0.5 * (a11 + a22),
                 half = std::sqrt(0.25 * (a11 - a22) * (a11 - a22) + a12 * a12);
    const double l1 = mid + half, l2 = std::max(mid - half, 1e-300);
    Footprint f;
    f.s_minor = 1.0 / std::sqrt(l1);
    f.s_major = 1.0 / std::sqrt(l2);
    double ex, ey;
    if (std::abs(a11 - l2) > std::abs(a22 - l2))
        ex = -a12, ey = a11 - l2;
    else
        ex = a22 - l2, ey = -a12;
    double n = std::sqrt(ex * ex + ey * ey);
    if (!(n > 0.0)) ex = 1.0, ey = 0.0, n = 1.0;
    f.ex = ex / n, f.ey = ey / n;
    const double ix = A * f.ex + B * f.ey, iy = C * f.ex + D * f.ey;
    const double in = std::sqrt(ix * ix + iy * iy);
    f.ix = in > 0.0 ? ix / in : 0.0;
    f.iy = in > 0.0 ? iy / in : 1.0;
    return f;
}

double PerspectiveView::horizon_row() const {
    const double s = m_cam.plane == Plane::Ground ? 1.0 : -1.0;
    const double p = m_cam.pitch_deg * kDeg;
    if (std::abs(std::cos(p)) < 1e-12) return -s * 1e300;
    return m_cy - s * m_f * std::tan(p);
}

void PerspectiveView::homography(double P[9]) const {
    // image_point: q = F . v, a = R . v, b = U . v with v = (rx, ry, m_z);
    // px = (cx q + f a) / q, py = (cy q - f b) / q.
    for (int k = 0; k < 3; ++k) {
        const double z = k == 2 ? m_z : 1.0;
        const int i = k == 2 ? 2 : k;
        P[k] = (m_cx * m_F[i] + m_f * m_R[i]) * z;
        P[3 + k] = (m_cy * m_F[i] - m_f * m_U[i]) * z;
        P[6 + k] = m_F[i] * z;
    }
}

void PerspectiveView::range_row(double& a, double& b, double& c, double& d) const {
    // image_point of (x, y) = foot + rho (sin h, -cos h): q = F . v, b = U . v, py = cy - f b / q.
    const double h = m_cam.heading_deg * kDeg;
    const double dx = std::sin(h), dy = -std::cos(h);
    const double qf = m_F[0] * dx + m_F[1] * dy, q0 = m_F[2] * m_z;
    const double uf = m_U[0] * dx + m_U[1] * dy, u0 = m_U[2] * m_z;
    a = m_cy * qf - m_f * uf, b = m_cy * q0 - m_f * u0, c = qf, d = q0;
}

void PerspectiveView::texture_row(double py, int n, double ox, double oy, float* x, float* y,
                                  uint8_t* hit) const {
    // The same arithmetic as texture_point: the ray's z component does not depend on the column
    // (the right vector is horizontal, m_R[2] = 0), so neither does the ray parameter t.
    const double b = py - m_cy;
    const double d2 = m_f * m_F[2] + 0.0 * m_R[2] - b * m_U[2];
    const double t = m_z / d2;
    const bool any = t > 0.0 && std::isfinite(t);
    for (int i = 0; i < n; ++i) {
        const double a = (i + 0.5) - m_cx;
        const double d0 = m_f * m_F[0] + a * m_R[0] - b * m_U[0];
        const double d1 = m_f * m_F[1] + a * m_R[1] - b * m_U[1];
        const double rx = (m_cam.x + t * d0) - ox, ry = (m_cam.y + t * d1) - oy;
        const bool ok = any && std::abs(rx) < 1e15 && std::abs(ry) < 1e15;
        x[i] = ok ? static_cast<float>(rx) : kFar;
        y[i] = ok ? static_cast<float>(ry) : kFar;
        hit[i] = ok ? 1 : 0;
    }
}

bool PerspectiveView::row_line(double py, double ox, double oy, double line[4]) const {
    const double b = py - m_cy;
    const double d2 = m_f * m_F[2] + 0.0 * m_R[2] - b * m_U[2];
    const double t = m_z / d2;
    if (!(t > 0.0) || !std::isfinite(t)) {
        line[0] = line[1] = line[2] = line[3] = std::numeric_limits<double>::quiet_NaN();
        return false;
    }
    const double a = 0.5 - m_cx;
    line[0] = (m_cam.x + t * (m_f * m_F[0] + a * m_R[0] - b * m_U[0])) - ox;
    line[1] = (m_cam.y + t * (m_f * m_F[1] + a * m_R[1] - b * m_U[1])) - oy;
    line[2] = t * m_R[0], line[3] = t * m_R[1];
    return true;
}

PixelCoords pixel_coords(const PerspectiveView& view) {
    const auto& cam = view.camera();
    PixelCoords pc;
    pc.width = cam.width, pc.height = cam.height;
    pc.origin_x = cam.x, pc.origin_y = cam.y;
    const size_t n = size_t(cam.width) * cam.height;
    pc.x.resize(n), pc.y.resize(n), pc.hit.resize(n), pc.rows.resize(4 * size_t(cam.height));
    tbb::parallel_for(0, cam.height, [&](int j) {
        const size_t p = size_t(j) * cam.width;
        view.texture_row(j + 0.5, cam.width, pc.origin_x, pc.origin_y, pc.x.data() + p,
                         pc.y.data() + p, pc.hit.data() + p);
        view.row_line(j + 0.5, pc.origin_x, pc.origin_y, pc.rows.data() + 4 * size_t(j));
    });
    return pc;
}

namespace {

/// Image bounding box of a convex texture-space polygon, clipped against the plane of points
/// slightly in front of the camera (a support reaching behind the camera projects to the
/// image edge). Returns false when the polygon lies entirely behind.
template <size_t N>
bool project_box(const PerspectiveView& view, const std::array<std::array<double, 2>, N>& poly,
                 double& xa, double& xb, double& ya, double& yb) {
    const double qmin = 1e-6 * view.camera().altitude;
    std::array<std::array<double, 2>, 2 * N> clipped;  // at most N + 1 for a convex polygon
    size_t m = 0;
    for (size_t i = 0; i < N; ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % N];
        const double qa = view.depth(a[0], a[1]) - qmin, qb = view.depth(b[0], b[1]) - qmin;
        if (qa >= 0.0) clipped[m++] = a;
        if ((qa >= 0.0) != (qb >= 0.0)) {
            const double t = qa / (qa - qb);
            clipped[m++] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])};
        }
        if (m >= clipped.size()) break;
    }
    if (m == 0) return false;
    xa = ya = std::numeric_limits<double>::infinity();
    xb = yb = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < m; ++i) {
        double px, py;
        if (!view.image_point(clipped[i][0], clipped[i][1], px, py)) {
            // on the clip plane itself: far off the image
            px = py = 0.0;
            xa = ya = -1e12, xb = yb = 1e12;
        }
        xa = std::min(xa, px), xb = std::max(xb, px), ya = std::min(ya, py), yb = std::max(yb, py);
    }
    xa = std::max(xa, -1e12), ya = std::max(ya, -1e12), xb = std::min(xb, 1e12),
    yb = std::min(yb, 1e12);
    return true;
}

/// Image box of the square [cx - r, cx + r] x [cy - r, cy + r].
bool square_box(const PerspectiveView& view, double cx, double cy, double r, int W, int H, int& x0,
                int& y0, int& x1, int& y1) {
    const std::array<std::array<double, 2>, 4> sq = {
        {{cx - r, cy - r}, {cx + r, cy - r}, {cx + r, cy + r}, {cx - r, cy + r}}};
    double xa, xb, ya, yb;
    if (!project_box(view, sq, xa, xb, ya, yb)) return false;
    pixel_box(xa, xb, ya, yb, W, H, x0, y0, x1, y1);
    return x0 <= x1 && y0 <= y1;
}

std::vector<detail::PerspLevel> loop_levels(const kernels::KernelPyramid& pyr) {
    std::vector<detail::PerspLevel> lv(size_t(pyr.levels()));
    for (int l = 0; l < pyr.levels(); ++l) {
        auto& L = lv[size_t(l)];
        L.radius = static_cast<float>(pyr.radius(l));
        L.inv_r2 = static_cast<float>(1.0 / (pyr.radius(l) * pyr.radius(l)));
        if (pyr.radial()) {
            const auto& t = pyr.tables(l);
            L.table = t.table.data(), L.table_n = static_cast<int>(t.table.size());
            L.line_p = t.line_mass.data(), L.line_q = t.line_var.data(),
            L.line_k4 = t.line_k4.data();
            L.line_n = static_cast<int>(t.line_mass.size());
            L.axial = t.axial.data(), L.axial_extent = t.axial_extent.data();
            L.axial_nu = t.axial_nu, L.axial_nv = t.axial_nv;
            L.axial_slices = static_cast<int>(t.axial_extent.size());
            L.axial_inv_dvar = static_cast<float>((L.axial_slices - 1) / t.axial_var_max);
            // A table lookup is two reads at computed indices per pixel, which the vectorised
            // loop does element by element; a short Chebyshev series is a few vector multiplies
            // and adds. Its error (at most 1e-6 of h_l(0)) is of the order of the table's.
            const auto& poly = pyr.level(l).polynomial();
            const double e0 = std::abs(pyr.level(l).envelope(0.0));
            if (poly.coefficients.size() >= 3 && poly.coefficients.size() <= kMaxPolyTerms &&
                poly.max_error < 1e-6 * e0) {
                L.poly = poly.coefficients.data();
                L.poly_n = static_cast<int>(poly.coefficients.size());
            }
        } else {
            L.grid = pyr.grid(l).data(), L.grid_n = pyr.grid_n(l);
        }
    }
    return lv;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The region of the plane to populate (docs/perspective.md §6, "The cut-off and the region")

namespace {

/// A sample of the image for perspective_region: the texture point it sees, whether impulses
/// there are drawn (or a neighbour's along the row are: `near`), and the support they reach.
struct RegionSample {
    double x = 0, y = 0, ext = 0;
    bool hit = false, kept = false, near = false;
};

/// The grid of samples of perspective_region: kSamples + 1 points along every image row. A row
/// of pixels maps to a straight segment of the plane, so samples along each row bound it; the
/// fade varies smoothly along the row, so a sample next to a kept one is kept too.
class RegionSampler {
public:
    static constexpr int kSamples = 16;  // segments per row

    RegionSampler(const kernels::KernelPyramid& pyr, const PerspectiveView& view,
                  const AntiAlias& aa)
        : m_pyr(pyr), m_view(view), m_aa(aa), m_W(view.camera().width),
          m_H(view.camera().height) {}

    /// Samples every row (parallel by rows).
    void sample() {
        m_grid.assign(size_t(m_H) * (kSamples + 1), RegionSample{});
        tbb::parallel_for(0, m_H, [&](int j) { sample_row(j); });
    }
    /// The texture box of cell (j, k) of the sample grid (rows j, j + 1 and samples k, k + 1):
    /// the box of the corners that see the plane (a corner past the cut-off moved back to it),
    /// expanded by the largest extent among the kept ones; false when nothing there is drawn.
    bool cell_box(int j, int k, numeric::Box& b) const;

private:
    const kernels::KernelPyramid& m_pyr;
    const PerspectiveView& m_view;
    const AntiAlias& m_aa;
    int m_W, m_H;
    std::vector<RegionSample> m_grid;

    double sample_px(int k) const {
        return k == 0 ? 0.5 : k == kSamples ? m_W - 0.5 : m_W * double(k) / kSamples;
    }
    const RegionSample& at(int j, int k) const {
        return m_grid[size_t(j) * (kSamples + 1) + size_t(k)];
    }
    void probe(double px, double py, RegionSample& s) const;
    void sample_row(int j);
    void boundary(int k, int jk, int ju, double& x, double& y) const;
};

/// Whether the impulses at image point (px, py) are drawn, and their extent.
void RegionSampler::probe(double px, double py, RegionSample& s) const {
    const auto& cam = m_view.camera();
    s.hit = m_view.texture_point(px, py, s.x, s.y);
    s.kept = false;
    if (!s.hit) return;
    if (m_aa.max_distance > 0.0 && std::hypot(s.x - cam.x, s.y - cam.y) > m_aa.max_distance)
        return;
    const auto f = m_view.footprint(s.x, s.y);
    const detail::Plan p = detail::plan_for(m_pyr, m_aa, f.s_major, f.s_minor);
    s.kept = p.keep;
    // The line form's long axis points along the depth, where the neighbouring rows are
    // (the region spans the rows between samples): only its across extent widens it.
    s.ext = 1.25 * (p.mode == detail::kPerspLine ? p.across : std::max(p.along, p.across));
}

void RegionSampler::sample_row(int j) {
    RegionSample* row = m_grid.data() + size_t(j) * (kSamples + 1);
    for (int k = 0; k <= kSamples; ++k) probe(sample_px(k), j + 0.5, row[k]);
    // A sample next to a kept one along the row counts as kept, with its neighbour's extent.
    std::array<double, kSamples + 1> ext{};
    for (int k = 0; k <= kSamples; ++k) {
        const bool left = k > 0 && row[k - 1].kept, right = k < kSamples && row[k + 1].kept;
        row[k].near = row[k].hit && (row[k].kept || left || right);
        double e = row[k].kept ? row[k].ext : 0.0;
        if (left) e = std::max(e, row[k - 1].ext);
        if (right) e = std::max(e, row[k + 1].ext);
        ext[size_t(k)] = e;
    }
    for (int k = 0; k <= kSamples; ++k) row[k].ext = ext[size_t(k)];
}

/// Where column k of samples passes from kept (row jk) to not kept (row ju), the texture point
/// just past the cut-off (bisection in the image row): rows near the horizon lie far apart on
/// the plane, and the region should end at the cut-off, not at the next row.
void RegionSampler::boundary(int k, int jk, int ju, double& x, double& y) const {
    double a = jk + 0.5, b = ju + 0.5;  // kept, not kept
    for (int it = 0; it < 16; ++it) {
        RegionSample s;
        probe(sample_px(k), 0.5 * (a + b), s);
        (s.kept ? a : b) = 0.5 * (a + b);
    }
    if (m_view.texture_point(sample_px(k), b, x, y)) return;
    x = at(jk, k).x, y = at(jk, k).y;
}

bool RegionSampler::cell_box(int j, int k, numeric::Box& b) const {
    b = {1e300, 1e300, -1e300, -1e300};
    double e = -1.0;
    const int rows = m_H > 1 ? 2 : 1;
    for (int dj = 0; dj < rows; ++dj)
        for (int dk = 0; dk <= 1; ++dk) {
            const RegionSample& s = at(j + dj, k + dk);
            if (s.near) e = std::max(e, s.ext);
            double x = s.x, y = s.y;
            const int other = j + (rows - 1 - dj);
            if (!s.kept && other != j + dj && at(other, k + dk).kept)
                boundary(k + dk, other, j + dj, x, y);
            else if (!s.hit)
                continue;
            b.x0 = std::min(b.x0, x), b.x1 = std::max(b.x1, x);
            b.y0 = std::min(b.y0, y), b.y1 = std::max(b.y1, y);
        }
    if (!(e >= 0.0) || !(b.x1 >= b.x0)) return false;
    b = b.expanded(e);
    return true;
}

/// Boxes are merged while a merged box wastes at most kWaste of its area: the covered area of
/// a merged box is tracked as the sum of its parts less their overlaps with the part merged
/// before them (the union of a wedge's row boxes is the wedge; its bounding box would be about
/// twice as large).
constexpr double kWaste = 0.1;
struct MergedBox {
    numeric::Box box, last;
    double covered = 0.0;
};

double overlap_area(const numeric::Box& a, const numeric::Box& b) {
    const double w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
    const double h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
    return w > 0.0 && h > 0.0 ? w * h : 0.0;
}

bool try_merge(MergedBox& m, const numeric::Box& b) {
    const numeric::Box u{std::min(m.box.x0, b.x0), std::min(m.box.y0, b.y0),
                         std::max(m.box.x1, b.x1), std::max(m.box.y1, b.y1)};
    const double covered = m.covered + b.area() - overlap_area(m.last, b);
    if (u.area() > (1.0 + kWaste) * covered) return false;
    m.box = u, m.last = b, m.covered = covered;
    return true;
}

/// Merges the cells' boxes: first along each row of cells (parallel by rows), then down the
/// rows, from the bottom row of cells up.
numeric::Region merge_cells(const RegionSampler& sampler, int H) {
    const int cell_rows = std::max(1, H - 1);
    std::vector<std::vector<MergedBox>> rows(static_cast<size_t>(cell_rows));
    tbb::parallel_for(0, cell_rows, [&](int j) {
        auto& out = rows[size_t(j)];
        for (int k = 0; k < RegionSampler::kSamples; ++k) {
            numeric::Box b;
            if (!sampler.cell_box(j, k, b)) continue;
            if (out.empty() || !try_merge(out.back(), b)) out.push_back({b, b, b.area()});
        }
    });
    std::vector<MergedBox> all;
    for (int j = cell_rows - 1; j >= 0; --j) {
        auto& r = rows[size_t(j)];
        if (r.size() == 1 && !all.empty() && try_merge(all.back(), r.front().box)) continue;
        all.insert(all.end(), r.begin(), r.end());
    }
    numeric::Region region;
    region.boxes.reserve(all.size());
    for (const MergedBox& m : all) region.boxes.push_back(m.box);
    return region;
}

}  // namespace

numeric::Region perspective_region(const kernels::KernelPyramid& pyr, const PerspectiveView& view,
                                   const AntiAlias& aa) {
    RegionSampler sampler(pyr, view, aa);
    sampler.sample();
    return merge_cells(sampler, view.camera().height);
}

// ---------------------------------------------------------------------------------------------
// Perspective evaluation (docs/perspective.md §2-4: the filter forms; §5: the far field)

namespace detail {
/// The per-frame arrays of accumulate_perspective that a PerspectiveWorkspace keeps.
struct PerspScratch {
    std::vector<std::vector<PerspItem>> chunk_items;
    std::vector<std::vector<PerspProbe>> chunk_probes;
    std::vector<PerspItem> items;
    std::vector<PerspProbe> probes;
    std::vector<double> far_q;
    std::vector<uint32_t> far_counts;
    FarField far_field;
    FarScratch far;
    /// What far_field was set up for (a camera that does not move keeps it: a few ms a frame).
    /// The pixel coordinates are the camera's (pixel_coords), so the camera stands for them.
    struct FarKey {
        uint64_t pyramid = 0;  ///< KernelPyramid::serial(), 0: not set up
        PerspectiveCamera camera;
        AntiAlias aa;
    } far_key;
};
}  // namespace detail

PerspectiveWorkspace::PerspectiveWorkspace()
    : m_scratch(std::make_unique<detail::PerspScratch>()) {}
PerspectiveWorkspace::~PerspectiveWorkspace() = default;

detail::PerspScratch* PerspectiveWorkspace::acquire() {
    return m_busy.exchange(true, std::memory_order_acquire) ? nullptr : m_scratch.get();
}

void PerspectiveWorkspace::release() { m_busy.store(false, std::memory_order_release); }

namespace {

/// Impulses prepared per chunk (each chunk writes its own items; probes go to per-chunk lists
/// joined in chunk order, so the layout does not depend on scheduling).
constexpr size_t kChunk = 1024;

/// Counts of one chunk's preparation (PerspectiveStats).
struct ChunkCounts {
    size_t single = 0, probes = 0, line = 0, axial = 0;
    size_t probe_count = 0;  ///< probes made
    size_t pixels = 0;       ///< pixel boxes of the items and probes
};

/// Scratch memory of one call: the workspace's when one is lent and free, else its own.
class ScratchLease {
public:
    explicit ScratchLease(PerspectiveWorkspace* workspace) {
        m_scratch = workspace ? workspace->acquire() : nullptr;
        if (m_scratch)
            m_workspace = workspace;
        else
            m_own = std::make_unique<detail::PerspScratch>(), m_scratch = m_own.get();
    }
    ~ScratchLease() {
        if (m_workspace) m_workspace->release();
    }
    ScratchLease(const ScratchLease&) = delete;
    ScratchLease& operator=(const ScratchLease&) = delete;
    detail::PerspScratch& get() { return *m_scratch; }

private:
    std::unique_ptr<detail::PerspScratch> m_own;
    detail::PerspScratch* m_scratch = nullptr;
    PerspectiveWorkspace* m_workspace = nullptr;
};

/// Sets the far field up unless the scratch holds the set-up of the same pyramid, rays and
/// options (the set-up is a function of these alone).
void ensure_far_setup(detail::PerspScratch& s, const kernels::KernelPyramid& pyr,
                      const PerspectiveView& view, const PixelCoords& coords, const AntiAlias& aa) {
    auto& key = s.far_key;
    if (key.pyramid == pyr.serial() && key.camera.same_rays(view.camera()) && key.aa == aa) return;
    key.pyramid = 0;  // not valid while set up (an exception leaves it so)
    s.far_field.setup(pyr, view, coords, aa);
    key = {pyr.serial(), view.camera(), aa};
}

size_t box_area(int x0, int y0, int x1, int y1) {
    return x1 >= x0 && y1 >= y0 ? size_t(x1 - x0 + 1) * size_t(y1 - y0 + 1) : size_t(0);
}

/// Line form (docs/perspective.md §4): the bend of the footprint's image along its major axis,
/// its second difference (step 1 % of the depth: the map varies on the scale of the depth), and
/// the keystone, the log-derivative of the across scale per image pixel along it.
void line_bend(const PerspectiveView& view, double x, double y,
               const PerspectiveView::Footprint& f, double sx, double sy, detail::PerspItem& it) {
    const double h = 0.01 * view.depth(x, y);
    double ax, ay, bx, by;
    if (!view.image_point(x + h * f.ex, y + h * f.ey, ax, ay) ||
        !view.image_point(x - h * f.ex, y - h * f.ey, bx, by))
        return;
    const double d2 = (ax - 2.0 * sx + bx) * f.ix + (ay - 2.0 * sy + by) * f.iy;
    it.curv = static_cast<float>(0.5 * d2 / (h * h));
    // across scale at +-h along: its log-derivative per image pixel
    const double sp = view.footprint(x + h * f.ex, y + h * f.ey).s_minor;
    const double sn = view.footprint(x - h * f.ex, y - h * f.ey).s_minor;
    const double du = (ax - bx) * f.ix + (ay - by) * f.iy;
    if (du != 0.0) it.keystone = static_cast<float>(std::log(sp / sn) / du);
}

/// Line form (docs/perspective.md §4): the item's image-space filter and pixel box.
bool prepare_line(const PerspectiveView& view, double x, double y,
                  const PerspectiveView::Footprint& f, const detail::Plan& p, double sx, double sy,
                  int W, int H, detail::PerspItem& it) {
    it.ix = static_cast<float>(f.ix), it.iy = static_cast<float>(f.iy);
    it.inv_smaj = static_cast<float>(1.0 / f.s_major);
    it.smin = static_cast<float>(f.s_minor);
    line_bend(view, x, y, f, sx, sy, it);
    const double ism2 = 1.0 / (f.s_major * f.s_major);
    it.var_lo = static_cast<float>(p.var_lo * ism2);
    it.var_hi = static_cast<float>(p.var_hi * ism2);
    // Along the major axis: the Gaussian in image space (4 sd of the widest level,
    // chord variance at most R^2/3); across: the projected support.
    const double R = p.across;
    const double sd = std::sqrt((std::max(p.var_lo, p.var_hi) + R * R / 3.0) * ism2);
    const double ax = 4.0 * sd * std::abs(f.ix) + 1.0, ay = 4.0 * sd * std::abs(f.iy) + 1.0;
    double xa = sx, xb = sx, ya = sy, yb = sy;
    for (double sgn : {-1.0, 1.0}) {
        double qx, qy;
        if (view.image_point(x - sgn * R * f.ey, y + sgn * R * f.ex, qx, qy)) {
            xa = std::min(xa, qx), xb = std::max(xb, qx);
            ya = std::min(ya, qy), yb = std::max(yb, qy);
        } else {
            xa = ya = -1e12, xb = yb = 1e12;
        }
    }
    pixel_box(xa - ax, xb + ax, ya - ay, yb + ay, W, H, it.x0, it.y0, it.x1, it.y1);
    return it.x0 <= it.x1 && it.y0 <= it.y1;
}

/// Axial form (docs/perspective.md §3): the blurred table's variances and the image box of the
/// rectangle along x across the support.
bool prepare_axial(const PerspectiveView& view, double x, double y,
                   const PerspectiveView::Footprint& f, const detail::Plan& p, int W, int H,
                   detail::PerspItem& it) {
    it.ex = static_cast<float>(f.ex), it.ey = static_cast<float>(f.ey);
    it.var_lo = static_cast<float>(p.var_lo), it.var_hi = static_cast<float>(p.var_hi);
    const double ux = p.along * f.ex, uy = p.along * f.ey;
    const double vx = -p.across * f.ey, vy = p.across * f.ex;
    const std::array<std::array<double, 2>, 4> rect = {{{x - ux - vx, y - uy - vy},
                                                        {x + ux - vx, y + uy - vy},
                                                        {x + ux + vx, y + uy + vy},
                                                        {x - ux + vx, y - uy + vy}}};
    double xa, xb, ya, yb;
    if (project_box(view, rect, xa, xb, ya, yb))
        pixel_box(xa, xb, ya, yb, W, H, it.x0, it.y0, it.x1, it.y1);
    return it.x0 <= it.x1 && it.y0 <= it.y1;
}

/// Probe form (docs/perspective.md §3): 2m + 1 Gaussian-weighted copies along the major axis,
/// appended to `probes`; the item's box is the union of theirs.
bool prepare_probes(const PerspectiveView& view, double x, double y,
                    const PerspectiveView::Footprint& f, const detail::Plan& p, int W, int H,
                    detail::PerspItem& it, std::vector<detail::PerspProbe>& probes,
                    ChunkCounts& counts) {
    std::array<double, 2 * kMaxProbeHalf + 1> t{}, w{};
    probe_weights(p, t, w);
    it.probe0 = static_cast<uint32_t>(probes.size());
    it.x0 = W, it.y0 = H, it.x1 = -1, it.y1 = -1;
    for (int j = 0; j <= 2 * p.m; ++j) {
        detail::PerspProbe pr;
        const double ox = t[size_t(j)] * f.ex, oy = t[size_t(j)] * f.ey;
        pr.dx = static_cast<float>(ox), pr.dy = static_cast<float>(oy);
        pr.w = static_cast<float>(static_cast<double>(it.w) * w[size_t(j)]);
        if (!square_box(view, x + ox, y + oy, p.across, W, H, pr.x0, pr.y0, pr.x1, pr.y1))
            continue;
        it.x0 = std::min(it.x0, pr.x0), it.y0 = std::min(it.y0, pr.y0);
        it.x1 = std::max(it.x1, pr.x1), it.y1 = std::max(it.y1, pr.y1);
        counts.pixels += box_area(pr.x0, pr.y0, pr.x1, pr.y1);
        probes.push_back(pr);
    }
    it.nprobe = static_cast<uint32_t>(probes.size()) - it.probe0;
    ++counts.probes;
    counts.probe_count += it.nprobe;
    return it.nprobe > 0;
}

/// The inputs of the preparation, the same for every impulse of a frame.
struct PrepareInputs {
    const kernels::KernelPyramid& pyr;
    const sim::Impulses& imp;
    const PerspectiveView& view;
    const PixelCoords& coords;
    const AntiAlias& aa;
    const detail::FarField& far;
    double orient = 0;  ///< the kernel's own orientation, radians
};

/// Prepares impulse i of a near place: its plan (docs/perspective.md §2-4), position, weight
/// and pixel box; false when it adds nothing to the image.
bool prepare_item(const PrepareInputs& in, size_t i, detail::PerspItem& it,
                  std::vector<detail::PerspProbe>& probes, ChunkCounts& counts) {
    const auto& view = in.view;
    const int W = view.camera().width, H = view.camera().height;
    const double x = in.imp.x[i], y = in.imp.y[i];
    if (!(view.depth(x, y) > 0.0)) return false;
    const auto f = view.footprint(x, y);
    const detail::Plan p = detail::plan_for(in.pyr, in.aa, f.s_major, f.s_minor);
    if (!p.keep) return false;
    it.px = static_cast<float>(x - in.coords.origin_x);
    it.py = static_cast<float>(y - in.coords.origin_y);
    double sx = 0, sy = 0;
    view.image_point(x, y, sx, sy);
    it.sx = static_cast<float>(sx), it.sy = static_cast<float>(sy);
    it.w = static_cast<float>(static_cast<double>(in.imp.weight[i]) * p.fade);
    if (!in.pyr.radial()) {  // only grid levels are turned (a radial kernel has no angle)
        const double th = in.orient + static_cast<double>(in.imp.theta[i]);
        it.cs = static_cast<float>(std::cos(th)), it.sn = static_cast<float>(std::sin(th));
    }
    it.lo = static_cast<int16_t>(p.blend.lo), it.hi = static_cast<int16_t>(p.blend.hi);
    it.a = static_cast<float>(p.blend.weight);
    it.mode = p.mode;
    bool any = false;
    if (p.mode == detail::kPerspSingle) {
        any = square_box(view, x, y, p.across, W, H, it.x0, it.y0, it.x1, it.y1);
        ++counts.single;
    } else if (p.mode == detail::kPerspLine) {
        any = prepare_line(view, x, y, f, p, sx, sy, W, H, it);
        ++counts.line;
    } else if (p.mode == detail::kPerspAxial) {
        any = prepare_axial(view, x, y, f, p, W, H, it);
        ++counts.axial;
    } else {
        return prepare_probes(view, x, y, f, p, W, H, it, probes, counts);
    }
    if (any) counts.pixels += box_area(it.x0, it.y0, it.x1, it.y1);
    return any;
}

/// Prepares chunk c of the impulses: near ones into the chunk's items (and probes), far ones
/// given their sub-row coordinate in far_q and counted per band in far_counts (the far field
/// makes their items itself: stored, they would be tens of megabytes new to every frame).
ChunkCounts prepare_chunk(const PrepareInputs& in, size_t c, detail::PerspScratch& s) {
    const auto& cam = in.view.camera();
    const detail::FarField& far = in.far;
    auto& probes = s.chunk_probes[c];
    auto& items = s.chunk_items[c];
    probes.clear(), items.clear();
    ChunkCounts counts;
    const size_t bands = size_t(far.bands());
    for (size_t i = c * kChunk; i < std::min(in.imp.size(), (c + 1) * kChunk); ++i) {
        const double x = in.imp.x[i], y = in.imp.y[i];
        if (far.active()) s.far_q[i] = -1.0;
        if (in.aa.max_distance > 0.0 && std::hypot(x - cam.x, y - cam.y) > in.aa.max_distance)
            continue;
        if (far.contains(x - cam.x, y - cam.y)) {
            const double q = far.row_coordinate(x - cam.x, y - cam.y);
            s.far_q[i] = q;
            if (q >= 0.0) ++s.far_counts[c * bands + size_t(detail::FarField::band_of(q))];
            continue;
        }
        detail::PerspItem it;
        if (prepare_item(in, i, it, probes, counts)) items.push_back(it);
    }
    return counts;
}

/// Joins the chunks' items and probes in chunk order (the canonical order of the impulses).
void join_chunks(detail::PerspScratch& s, size_t chunks) {
    s.probes.clear(), s.items.clear();
    size_t np = 0, ni = 0;
    for (size_t c = 0; c < chunks; ++c)
        np += s.chunk_probes[c].size(), ni += s.chunk_items[c].size();
    s.probes.reserve(np), s.items.reserve(ni);
    for (size_t c = 0; c < chunks; ++c) {
        const auto base = static_cast<uint32_t>(s.probes.size());
        s.probes.insert(s.probes.end(), s.chunk_probes[c].begin(), s.chunk_probes[c].end());
        for (detail::PerspItem& it : s.chunk_items[c]) {
            if (it.mode == detail::kPerspProbes) it.probe0 += base;
            s.items.push_back(it);
        }
    }
}

/// Prepares every impulse (parallel by chunks); returns the chunks' counts in chunk order.
std::vector<ChunkCounts> prepare_all(const PrepareInputs& in, detail::PerspScratch& s) {
    const size_t n = in.imp.size();
    const size_t chunks = (n + kChunk - 1) / kChunk;
    if (s.chunk_items.size() < chunks) s.chunk_items.resize(chunks), s.chunk_probes.resize(chunks);
    std::vector<ChunkCounts> counts(chunks);
    if (in.far.active()) s.far_q.resize(n);
    s.far_counts.assign(chunks * size_t(in.far.bands()), 0);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) { counts[c] = prepare_chunk(in, c, s); });
    join_chunks(s, chunks);
    return counts;
}

/// Enforces the pixel budget and fills the preparation's part of the stats.
void check_counts(const std::vector<ChunkCounts>& counts, size_t n, const EvalOptions& options,
                  PerspectiveStats* stats) {
    size_t pixels = 0;  // the impulses' pixel boxes
    for (const auto& c : counts) pixels += c.pixels;
    if (options.max_pixel_evaluations > 0.0 && double(pixels) > options.max_pixel_evaluations)
        throw PixelBudgetError(double(pixels), options.max_pixel_evaluations);
    if (!stats) return;
    *stats = {};
    stats->impulses = n, stats->pixels = pixels;
    for (const auto& c : counts) {
        stats->single += c.single, stats->probes += c.probes, stats->line += c.line,
            stats->probe_count += c.probe_count;
        stats->axial += c.axial;
    }
}

/// Items binned into square tiles of T pixels by image box: tile t holds
/// bins[start[t] .. start[t + 1]), in canonical order (a counting sort).
struct TileBins {
    int T = 8, ntx = 0, nty = 0;
    std::vector<uint32_t> start, bins;
};

TileBins bin_items(const std::vector<detail::PerspItem>& items, int W, int H, int tile_size) {
    TileBins tb;
    const int T = tb.T = std::max(8, tile_size);
    const int ntx = tb.ntx = (W + T - 1) / T;
    tb.nty = (H + T - 1) / T;
    std::vector<uint32_t>& count = tb.start;
    count.assign(size_t(ntx) * tb.nty + 1, 0);
    for (const auto& it : items)
        for (int b = it.y0 / T; b <= it.y1 / T; ++b)
            for (int a = it.x0 / T; a <= it.x1 / T; ++a) ++count[size_t(b) * ntx + a + 1];
    for (size_t t = 1; t < count.size(); ++t) count[t] += count[t - 1];
    tb.bins.resize(count.back());
    std::vector<uint32_t> fill(count.begin(), count.end() - 1);
    for (size_t i = 0; i < items.size(); ++i) {
        const auto& it = items[i];
        for (int b = it.y0 / T; b <= it.y1 / T; ++b)
            for (int a = it.x0 / T; a <= it.x1 / T; ++a)
                tb.bins[fill[size_t(b) * ntx + a]++] = uint32_t(i);
    }
    return tb;
}

/// The near field: every tile sums its items in canonical order into a tile of its own, then
/// adds it to `out` (each pixel written by one task).
void render_tiles(const TileBins& tb, const detail::PerspScratch& s, const detail::PerspKernel& lk,
                  const PixelCoords& coords, const detail::PerspLoops& loops, bool parallel,
                  Frame& out) {
    const int W = out.width, H = out.height, T = tb.T;
    auto do_tile = [&](int t) {
        const int a = t % tb.ntx, b = t / tb.ntx;
        const int x0 = a * T, y0 = b * T;
        const int tw = std::min(T, W - x0), th = std::min(T, H - y0);
        std::vector<float> acc(size_t(tw) * th, 0.0f);
        const uint32_t* idx = tb.bins.data() + tb.start[size_t(t)];
        const size_t m = tb.start[size_t(t) + 1] - tb.start[size_t(t)];
        loops.tile(lk, s.items.data(), s.probes.data(), idx, m, coords.x.data(), coords.y.data(),
                   W, x0, y0, tw, th, acc.data());
        for (int y = 0; y < th; ++y) {
            float* dst = out.data.data() + size_t(y0 + y) * W + x0;
            const float* src = acc.data() + size_t(y) * tw;
            for (int x = 0; x < tw; ++x) dst[x] += src[x];
        }
    };
    const int ntiles = tb.ntx * tb.nty;
    if (parallel)
        tbb::parallel_for(0, ntiles, do_tile);
    else
        for (int t = 0; t < ntiles; ++t) do_tile(t);
}

}  // namespace

void accumulate_perspective(const kernels::KernelPyramid& pyr, const sim::Impulses& imp,
                            const PerspectiveView& view, const PixelCoords& coords, Frame& out,
                            const AntiAlias& aa, const EvalOptions& options,
                            PerspectiveStats* stats, PerspectiveWorkspace* workspace) {
    const auto& cam = view.camera();
    const int W = cam.width, H = cam.height;
    if (out.width != W || out.height != H) out.resize(W, H);
    if (coords.width != W || coords.height != H)
        throw ValueError("accumulate_perspective: pixel coordinates of another view size");
    if (!imp.scale.empty())
        throw ValueError(
            "accumulate_perspective: impulses with scales: draw each class of "
            "render::split_scale_classes with the pyramid of its scaled kernel");
    const std::vector<detail::PerspLevel> levels = loop_levels(pyr);
    const detail::PerspKernel lk{pyr.radial(), levels.data(), coords.rows.data()};
    const double orient = pyr.base().params().orientation;
    using Clock = std::chrono::steady_clock;
    auto ms = [](Clock::time_point a, Clock::time_point b) {
        return std::chrono::duration<double, std::milli>(b - a).count();
    };
    ScratchLease lease(workspace);
    detail::PerspScratch& scratch = lease.get();
    const auto t0 = Clock::now();
    ensure_far_setup(scratch, pyr, view, coords, aa);
    const detail::FarField& far = scratch.far_field;
    const auto t1 = Clock::now();
    const std::vector<ChunkCounts> counts =
        prepare_all({pyr, imp, view, coords, aa, far, orient}, scratch);
    check_counts(counts, imp.size(), options, stats);
    const auto t2 = Clock::now();
    const detail::PerspLoops& loops = options.use_avx2 && numeric::cpu_has_avx2()
                                          ? detail::kPerspLoopsAvx2
                                          : detail::kPerspLoopsBase;
    render_tiles(bin_items(scratch.items, W, H, options.tile_size), scratch, lk, coords, loops,
                 options.parallel, out);
    const auto t3 = Clock::now();
    const size_t far_count =
        far.active() ? far.render({&imp, cam.x, cam.y, orient, scratch.far_q.data(),
                                   scratch.far_counts.data(), kChunk},
                                  out, loops, options.parallel, scratch.far)
                     : 0;
    if (stats) {
        stats->far = far_count;
        stats->culled = imp.size() - scratch.items.size() - far_count;
        const auto t4 = Clock::now();
        stats->setup_ms = ms(t0, t1), stats->prepare_ms = ms(t1, t2), stats->tiles_ms = ms(t2, t3);
        stats->far_ms = ms(t3, t4);
    }
}

}  // namespace impulse::render
