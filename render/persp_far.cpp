// SPDX-License-Identifier: Apache-2.0
// The far field of a perspective view: impulses deposited on sub-rows along the circles around
// the camera's foot, convolved across with the line-form profiles, filtered along per pixel
// (render/detail/persp_far.h, render/perspective.h). The derivation: docs/perspective.md §5.

#include "render/detail/persp_far.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>

namespace impulse::render::detail {
namespace {

/// The far form expands each chord's profile along the major axis (a Gaussian of the chord's
/// mean mu and variance var + q / s_major^2, pixels) to fourth order around the Gaussian of the
/// mean variance sbar of its direction bin. It applies where that converges: the chords'
/// departures, weighted by their mass, have rms((var + q / s_major^2 - sbar) / sbar) <=
/// kFarVariance and rms(mu / sqrt(sbar)) <= kFarMean. kFarVariance is set against the
/// supersampled reference of test (a) (cosine kernels, chord variances from 0 to 0.13 R^2):
/// there the far rows err no more than with the line form up to R / s_major = 1.5 px, where the
/// rms is 0.077 (at 2 px, 0.098, the nearest far rows err twice as much). kFarMean bounds the
/// expansion in the centroid of sheared chords (elliptical kernels); against a supersampled
/// reference of the `clouds` sky the far field errs by 1-2 % of the texture's sd where it
/// begins (probes: 0.6 %) and 0.7 % near the horizon (probes, over their budget: 5-10 %).
constexpr double kFarVariance = 0.077;
constexpr double kFarMean = 0.7;
// The filter is refreshed every 0.05 focal lengths along a sub-row (0.05 rad at the centre of
// the image): with 0.2 against the supersampled reference of test (a) the far rows erred by up to
// twice as much as the line form (whose filter is each impulse's own); with 0.05 they are on a
// par with it.
constexpr double kSegmentRad = 0.05;
constexpr int kAcrossNodes = 16;  // nodes across the narrowest profile of a sub-row
constexpr int kProfiles = kFarProfiles;
constexpr double kAlongReach = 4.75;  // the along Gaussian is summed to 4.75 sd
constexpr int kAlongPiece = 64;       // columns per piece of a row's along reach
constexpr int kRowsPerTask = 32;      // output rows per task of the along filter

double sq(double v) { return v * v; }

/// Linear interpolation in a line table over t in [0, 1].
double table_at(const std::vector<float>& t, double x) {
    const double p = std::clamp(x, 0.0, 1.0) * static_cast<double>(t.size() - 1);
    const size_t i = std::min(static_cast<size_t>(p), t.size() - 2);
    const double f = p - static_cast<double>(i);
    return t[i] + f * (t[i + 1] - t[i]);
}

/// Mean chord variance of a radial level, int P q dv / int P dv = E_h[s^2] = R^2 / 2 E[q] with
/// q = r^2 / R^2 distributed as h(q) dq (the area element of the plane is pi R^2 dq).
double mean_chord_variance(const kernels::KernelPyramid& pyr, int l) {
    const auto& t = pyr.tables(l).table;
    double m0 = 0.0, m1 = 0.0;
    for (size_t i = 0; i < t.size(); ++i) {
        const double q = static_cast<double>(i) / static_cast<double>(t.size() - 1);
        const double w = (i == 0 || i + 1 == t.size()) ? 0.5 : 1.0;
        m0 += w * t[i], m1 += w * q * t[i];
    }
    const double R = pyr.radius(l);
    return m0 != 0.0 ? 0.5 * R * R * m1 / m0 : 0.0;
}

/// The straight line of the plane that an image column sees: base point and direction away
/// from the camera, relative to the foot.
struct ColumnLine {
    double bx = 0, by = 0, dx = 0, dy = 0;
    bool ok = false;
};

/// The footprint filter of one place: what the tables and weights need. The level pair is the
/// line form's: the isotropic level for the minor axis, the rest of the major axis's filter
/// (var, px^2) along it.
struct Place {
    bool ok = false;
    Plan plan;
    kernels::KernelPyramid::Blend blend;
    double var_lo = 0, var_hi = 0;
    double s_major = 1, s_minor = 1;
};

/// Variance of the Gaussian blur level l carries (level 0, the kernel itself, none).
double level_blur2(const kernels::KernelPyramid& pyr, int l) {
    return l == 0 ? 0.0 : pyr.sigma(l) * pyr.sigma(l);
}

/// Mean chord variance of a non-radial level across direction bin b (mass-weighted).
double mean_chord_variance_dir(const kernels::KernelPyramid& pyr, int l, int b) {
    double m0 = 0.0, m1 = 0.0;
    const auto& t = pyr.direction_tables(l, b);
    for (size_t i = 0; i < t.mass.size(); ++i) m0 += t.mass[i], m1 += t.mass[i] * t.var[i];
    return m0 != 0.0 ? m1 / m0 : 0.0;
}

/// Linear interpolation in a table over v in [-R, R]; 0 outside.
double signed_table_at(const std::vector<float>& t, double v, double R) {
    const double p = (v / R + 1.0) * 0.5 * static_cast<double>(t.size() - 1);
    if (!(p >= 0.0 && p <= static_cast<double>(t.size() - 1))) return 0.0;
    const size_t i = std::min(static_cast<size_t>(p), t.size() - 2);
    const double f = p - static_cast<double>(i);
    return t[i] + f * (t[i + 1] - t[i]);
}

}  // namespace

/// The steps of FarField::setup and what they share (docs/perspective.md §5). Each step reads
/// the inputs and the results of the steps before it; `f` is the far field being set up.
struct FarField::Setup {
    FarField& f;
    const kernels::KernelPyramid& pyr;
    const PerspectiveView& view;
    const PixelCoords& coords;
    const AntiAlias& aa;
    const PerspectiveCamera& cam;
    int W = 0, H = 0;
    int G = 1;            ///< segments (column lines)
    int NB = 1;           ///< direction bins
    double c = 0;         ///< the pixel filter's sd, pixels
    double hz = 0;        ///< the horizon's image row
    double toward = 1;    ///< +1: image rows nearer the camera lie down the image (ground)
    std::vector<ColumnLine> lines;
    std::vector<double> qbar;  ///< mean chord variance per level and direction bin
    double rho_far = 0, rho_cut = 0;

    Setup(FarField& far, const kernels::KernelPyramid& p, const PerspectiveView& v,
          const PixelCoords& pc, const AntiAlias& a)
        : f(far), pyr(p), view(v), coords(pc), aa(a), cam(v.camera()) {}

    bool frame();
    void column_lines();
    void mean_chord_variances();
    Place place(int g, double rho) const;
    double sbar_of(const Place& p, int bin) const;
    bool converges(const Place& p) const;
    bool far_at(int g, double rho) const;
    bool kept_at(int g, double rho) const;
    double nearest_rho(int g, bool& abort) const;
    void column_zone(int g, double near_rho);
    bool far_zone();
    void depth_min();
    bool sub_rows();
    void table_orientation();
    void row(int r);
    std::vector<Place> row_places(Row& row, double rho, double& narrow, double& wide,
                                  double& sm_min) const;
    void row_across(Row& row, const std::vector<Place>& places, double narrow, double wide,
                    double sm_min) const;
    void place_tables(Row& row, int g, const Place& p, std::array<double, kProfiles>& peak) const;
    std::array<double, kProfiles> chord_terms(const Place& p, int bin, double sbar,
                                              double v) const;
    bool pixel_rows();
    bool row_in_reach(int j, double smax, double y_lo, double y_hi) const;
    void pixel_filters();
    void along_reach();
    void pixel_filter(int j, int i);
};

/// The view-level quantities: which kernels, the Moebius map Y(rho), the segments and the
/// homography; false when the far field does not apply (docs/perspective.md §5.1).
bool FarField::Setup::frame() {
    if (!(aa.far_field && aa.enabled && aa.anisotropic && aa.fade)) return false;
    if (!pyr.radial() && pyr.direction_bins() == 0) return false;
    f.m_bins = pyr.radial() ? 1 : pyr.direction_bins();
    f.m_period = pyr.radial() ? 1.0 : pyr.direction_period();
    W = cam.width, H = cam.height;
    f.m_width = W, f.m_height = H;
    c = filter_sigma_px(aa);
    hz = view.horizon_row();
    if (!std::isfinite(hz) || std::abs(hz) > 1e7) return false;
    toward = cam.plane == Plane::Ground ? 1.0 : -1.0;  // image rows nearer the camera
    view.range_row(f.m_ya, f.m_yb, f.m_yc, f.m_yd);
    f.m_segments =
        std::max(1, static_cast<int>(std::ceil(W / std::max(4.0, kSegmentRad * view.focal_px()))));
    f.m_segment_px = static_cast<double>(W) / f.m_segments;
    f.m_inv_segment_px = 1.0 / f.m_segment_px;
    view.homography(f.m_P);
    G = f.m_segments;
    NB = f.m_bins;
    return true;
}

/// Column lines of the segment centres: the straight line of the plane each sees.
void FarField::Setup::column_lines() {
    lines.assign(static_cast<size_t>(G), ColumnLine{});
    for (int g = 0; g < G; ++g) {
        const double px = (g + 0.5) * f.m_segment_px;
        double ax, ay, bx, by;
        auto& L = lines[size_t(g)];
        if (!view.texture_point(px, hz + toward * 1.0, ax, ay) ||
            !view.texture_point(px, hz + toward * 2.0, bx, by))
            continue;
        L.bx = bx - cam.x, L.by = by - cam.y, L.dx = ax - bx, L.dy = ay - by;
        L.ok = true;
    }
}

/// Mean chord variance per level and direction bin: each bin has its own along Gaussian.
void FarField::Setup::mean_chord_variances() {
    qbar.assign(size_t(pyr.levels()) * NB, 0.0);
    for (int l = 0; l < pyr.levels(); ++l)
        for (int b = 0; b < NB; ++b)
            qbar[size_t(l) * NB + b] =
                pyr.radial() ? mean_chord_variance(pyr, l) : mean_chord_variance_dir(pyr, l, b);
}

/// The place at distance rho from the foot on column line g: the plan there and the line
/// form's level pair and remaining variances along (docs/perspective.md §4).
Place FarField::Setup::place(int g, double rho) const {
    Place p;
    const ColumnLine& L = lines[size_t(g)];
    if (!L.ok) return p;
    const double dd = L.dx * L.dx + L.dy * L.dy, bd = L.bx * L.dx + L.by * L.dy;
    const double disc = bd * bd - dd * (L.bx * L.bx + L.by * L.by - rho * rho);
    if (!(disc >= 0.0) || !(dd > 0.0)) return p;
    const double t = (-bd + std::sqrt(disc)) / dd;
    const double x = cam.x + L.bx + t * L.dx, y = cam.y + L.by + t * L.dy;
    if (!(view.depth(x, y) > 0.0)) return p;
    const auto fp = view.footprint(x, y);
    p.plan = plan_for(pyr, aa, fp.s_major, fp.s_minor);
    p.s_major = fp.s_major, p.s_minor = fp.s_minor;
    p.blend = pyr.select(std::max(c * fp.s_minor, pyr.sigma(0)), aa.blend);
    const double sM2 = c * c * fp.s_major * fp.s_major;
    p.var_lo = std::max(0.0, sM2 - level_blur2(pyr, p.blend.lo)) / (fp.s_major * fp.s_major);
    p.var_hi = std::max(0.0, sM2 - level_blur2(pyr, p.blend.hi)) / (fp.s_major * fp.s_major);
    p.ok = true;
    return p;
}

/// The variance of the along Gaussian of a place and bin, sbar (docs/perspective.md §5.2).
double FarField::Setup::sbar_of(const Place& p, int bin) const {
    const auto& b = p.blend;
    const double ism2 = 1.0 / (p.s_major * p.s_major);
    const double wl = b.lo == b.hi ? 1.0 : 1.0 - b.weight, wh = b.lo == b.hi ? 0.0 : b.weight;
    return wl * (p.var_lo + qbar[size_t(b.lo) * NB + bin] * ism2) +
           wh * (p.var_hi + qbar[size_t(b.hi) * NB + bin] * ism2);
}

namespace {
/// Mass-weighted mean squares of the chords' departures from a bin's along Gaussian: of
/// d / sbar and of mu^2 / sbar (kFarVariance, kFarMean; docs/perspective.md §5.3).
struct Departures {
    double m0 = 0.0, mvar = 0.0, mmean = 0.0;
    /// Adds a level's chords: tables of mass, variance q and (sheared chords) mean, the level's
    /// remaining variance v along and blend weight w. Radial tables are sampled uniformly in
    /// t = v^2 / R^2, so their weight per sample is P dv ~ P / sqrt(t).
    void scan(const std::vector<float>& mass, const std::vector<float>& q,
              const std::vector<float>* mean, double v, double w, bool radial, double sbar,
              double ism2, double s_major) {
        const size_t n = mass.size();
        for (size_t i = 0; i < n; ++i) {
            const double t = (i + 0.5) / static_cast<double>(n);
            const double pw = w * mass[i] * (radial ? 0.5 / std::sqrt(t) : 1.0);
            const double d = v + q[i] * ism2 - sbar;
            m0 += pw, mvar += pw * d * d / (sbar * sbar);
            if (mean) mmean += pw * sq((*mean)[i] / s_major) / sbar;
        }
    }
};
}  // namespace

/// Whether the expansion converges at a place (see kFarVariance).
bool FarField::Setup::converges(const Place& p) const {
    const auto& b = p.blend;
    const double ism2 = 1.0 / (p.s_major * p.s_major);
    const std::array<int, 2> lv = {b.lo, b.hi};
    const std::array<double, 2> bw = {b.lo == b.hi ? 1.0 : 1.0 - b.weight,
                                      b.lo == b.hi ? 0.0 : b.weight};
    const std::array<double, 2> var = {p.var_lo, p.var_hi};
    Departures dep;
    for (int k = 0; k < 2; ++k) {
        if (bw[size_t(k)] == 0.0) continue;
        const int l = lv[size_t(k)];
        if (pyr.radial())
            dep.scan(pyr.tables(l).line_mass, pyr.tables(l).line_var, nullptr, var[size_t(k)],
                     bw[size_t(k)], true, sbar_of(p, 0), ism2, p.s_major);
        else
            for (int bin = 0; bin < pyr.direction_bins(); ++bin) {
                const auto& t = pyr.direction_tables(l, bin);
                dep.scan(t.mass, t.var, &t.mean, var[size_t(k)], bw[size_t(k)], false,
                         sbar_of(p, bin), ism2, p.s_major);
            }
    }
    if (!(dep.m0 > 0.0)) return false;
    return std::sqrt(dep.mvar / dep.m0) <= kFarVariance &&
           std::sqrt(dep.mmean / dep.m0) <= kFarMean;
}

/// A place is far when it is faded out, or its footprint is elongated (not the single form),
/// the levels are of one sign and the chord is short.
bool FarField::Setup::far_at(int g, double rho) const {
    const Place p = place(g, rho);
    if (!p.ok) return false;
    if (!p.plan.keep) return true;
    if (p.plan.mode == kPerspSingle) return false;
    if (!pyr.nonnegative(p.blend.lo) || !pyr.nonnegative(p.blend.hi)) return false;
    return converges(p);
}

bool FarField::Setup::kept_at(int g, double rho) const {
    const Place p = place(g, rho);
    return p.ok && p.plan.keep;
}

/// The distance from the foot of column g's visible point nearest the camera (-1: none).
/// `abort` is set when the distance does not grow up the column from there: the circles then
/// do not label the far zone (a column line meets a circle twice, on either side of its
/// closest approach to the foot) and the far field stays off.
double FarField::Setup::nearest_rho(int g, bool& abort) const {
    for (double py : {H - 0.5, 0.5}) {  // the image row nearest the camera
        const double row = toward > 0 ? py : H - py;
        double x, y;
        if (!view.texture_point((g + 0.5) * f.m_segment_px, row, x, y)) continue;
        const ColumnLine& L = lines[size_t(g)];
        if (!((x - cam.x) * L.dx + (y - cam.y) * L.dy > 0.0)) abort = true;
        return std::sqrt(sq(x - cam.x) + sq(y - cam.y));
    }
    return -1.0;
}

/// Column g's cut-off and the distance beyond which everything is far (both monotone in rho:
/// footprints only grow with the distance), by bisection in log rho; rho_cut and rho_far take
/// the largest over the columns.
void FarField::Setup::column_zone(int g, double near_rho) {
    double hi = near_rho;
    while (kept_at(g, hi) && hi < 1e15) hi *= 2.0;
    if (!kept_at(g, near_rho)) return;  // nothing drawn in this column
    double a = near_rho, b = hi;        // kept, not kept
    for (int it = 0; it < 40 && b / a > 1.0 + 1e-6; ++it) {
        const double m = std::sqrt(a * b);
        (kept_at(g, m) ? a : b) = m;
    }
    rho_cut = std::max(rho_cut, b);
    if (far_at(g, near_rho)) {
        rho_far = std::max(rho_far, near_rho);
        return;
    }
    double fa = near_rho, fb = b;  // not far, far
    for (int it = 0; it < 40 && fb / fa > 1.0 + 1e-6; ++it) {
        const double m = std::sqrt(fa * fb);
        (far_at(g, m) ? fb : fa) = m;
    }
    rho_far = std::max(rho_far, fb);
}

/// The far zone, rho_far <= rho <= rho_cut (docs/perspective.md §5.3); false when empty.
bool FarField::Setup::far_zone() {
    rho_far = 0.0, rho_cut = 0.0;
    for (int g = 0; g < G; ++g) {
        if (!lines[size_t(g)].ok) continue;
        bool abort = false;
        const double near_rho = nearest_rho(g, abort);
        if (abort) return false;
        if (!(near_rho > 0.0)) continue;
        column_zone(g, near_rho);
    }
    if (!(rho_far > 0.0) || !(rho_far < rho_cut)) return false;
    f.m_rho_far2 = rho_far * rho_far;
    return true;
}

/// An impulse belongs to the far zone only on its far side: at least the smallest depth of the
/// zone's near edge (an impulse as far from the foot but nearer the camera lies below the
/// image, on the other side of the closest approach).
void FarField::Setup::depth_min() {
    f.m_depth_min = 1e300;
    for (int g = 0; g < G; ++g) {
        const ColumnLine& L = lines[size_t(g)];
        if (!L.ok) continue;
        const double dd = L.dx * L.dx + L.dy * L.dy, bd = L.bx * L.dx + L.by * L.dy;
        const double disc = bd * bd - dd * (L.bx * L.bx + L.by * L.by - f.m_rho_far2);
        if (!(disc >= 0.0)) continue;
        const double t = (-bd + std::sqrt(disc)) / dd;
        f.m_depth_min =
            std::min(f.m_depth_min, view.depth(cam.x + L.bx + t * L.dx, cam.y + L.by + t * L.dy));
    }
    f.m_depth_min *= 0.999;
}

/// Sub-rows over the far zone, half the pixel filter apart in y' (plus one each side);
/// false when there are none or too many (docs/perspective.md §5.4).
bool FarField::Setup::sub_rows() {
    f.m_dy = 0.5 * c;
    f.m_inv_dy = 1.0 / f.m_dy;
    const double ya = f.y_of(rho_far), yb = f.y_of(rho_cut);
    if (!std::isfinite(ya) || !std::isfinite(yb)) return false;
    f.m_y0 = std::min(ya, yb) - f.m_dy;
    const double span = std::abs(ya - yb) + 2.0 * f.m_dy;
    const int rows = static_cast<int>(std::ceil(span / f.m_dy)) + 2;
    if (rows > 64 * H + 64) return false;
    f.m_rows.resize(static_cast<size_t>(rows));
    return true;
}

/// Orientation of the tables: v grows with xi (image x) when the image's x axis points left
/// of the outward direction e (turned a quarter counter-clockwise); the chord's centroid
/// (along e) moves the image row by sign(dY/drho) per unit.
void FarField::Setup::table_orientation() {
    double x0, y0, x1, y1;
    const double pc = 0.5 * W, pr = toward > 0 ? H - 0.5 : 0.5;
    if (view.texture_point(pc - 0.5, pr, x0, y0) && view.texture_point(pc + 0.5, pr, x1, y1)) {
        const double ex = 0.5 * (x0 + x1) - cam.x, ey = 0.5 * (y0 + y1) - cam.y;
        f.m_v_sign = (x1 - x0) * -ey + (y1 - y0) * ex >= 0.0 ? 1.0 : -1.0;
    }
    f.m_u_sign = f.m_ya * f.m_yd - f.m_yb * f.m_yc >= 0.0 ? 1.0 : -1.0;
}

/// Sub-row r: its circle, across coordinate, nodes and per-segment filter tables.
void FarField::Setup::row(int r) {
    Row& row = f.m_rows[size_t(r)];
    row.y = f.m_y0 + r * f.m_dy;
    // (a row of an earlier frame: its arrays are assigned below, its scalars reset here)
    row.margin = 0.0, row.xi0 = 0.0, row.dxi = row.inv_dxi = 1.0;
    row.nodes = row.taps = 0, row.used = {};
    // rho of the circle (inverse of the Moebius map), held inside the far zone
    double rho = (f.m_yb - f.m_yd * row.y) / (f.m_yc * row.y - f.m_ya);
    if (!(rho >= rho_far)) rho = rho_far;
    if (!(rho <= rho_cut)) rho = rho_cut;
    double narrow = 1e300, wide = 0.0, sm_min = 1e300;
    const std::vector<Place> places = row_places(row, rho, narrow, wide, sm_min);
    row.weight.assign(size_t(G), 0.0f);
    row.sbar.assign(size_t(G) * NB, static_cast<float>(c * c));
    if (!(wide > 0.0)) return;  // nothing drawn on this circle
    row_across(row, places, narrow, wide, sm_min);
    row.tables.assign(size_t(G) * NB * kProfiles * size_t(2 * row.taps + 1), 0.0f);
    std::array<double, kProfiles> peak{};
    for (int g = 0; g < G; ++g)
        if (places[size_t(g)].ok) place_tables(row, g, places[size_t(g)], peak);
    // Profiles whose term stays below 1e-4 of the main one's peak are left out.
    for (int m = 0; m < kProfiles; ++m)
        row.used[size_t(m)] = m == 0 || peak[size_t(m)] > 1e-4 * peak[0];
}

/// The places of a circle at the segment centres (ok only where an elongated form draws), the
/// narrowest and widest support there, the smallest s_minor, and the row's margin.
std::vector<Place> FarField::Setup::row_places(Row& row, double rho, double& narrow,
                                               double& wide, double& sm_min) const {
    std::vector<Place> places(static_cast<size_t>(G));
    for (int g = 0; g < G; ++g) {
        Place& p = places[size_t(g)] = place(g, rho);
        if (!p.ok || !p.plan.keep || p.plan.mode == kPerspSingle) {
            p.ok = false;
            continue;
        }
        const auto& b = p.blend;
        narrow = std::min(narrow, 2.0 * pyr.radius(b.lo));
        wide = std::max(wide, pyr.radius(std::max(b.lo, b.hi)));
        sm_min = std::min(sm_min, p.s_minor);
        row.margin = std::max(row.margin, pyr.radius(std::max(b.lo, b.hi)) / p.s_minor + 2.0);
    }
    return places;
}

/// The across coordinate: arc length along the circle, d xi / dx = s_minor (linear between
/// segment centres, held beyond). The kernel's profile across is then the same function of xi
/// wherever it lies on the circle; only the blend and the along filter change from segment to
/// segment (docs/perspective.md §5.4). Then the node grid over it and the segments' nodes.
void FarField::Setup::row_across(Row& row, const std::vector<Place>& places, double narrow,
                                 double wide, double sm_min) const {
    std::vector<double> sm(static_cast<size_t>(G), 0.0);
    for (int g = 0; g < G; ++g) {
        int k = g;  // nearest valid place
        for (int d = 1; !places[size_t(k)].ok && d < G; ++d)
            k = g - d >= 0 && places[size_t(g - d)].ok  ? g - d
                : g + d < G && places[size_t(g + d)].ok ? g + d
                                                        : k;
        sm[size_t(g)] = places[size_t(k)].s_minor;
    }
    auto sm_at = [&](double x) {
        const double gf = x / f.m_segment_px - 0.5;
        if (!(gf > 0.0)) return sm.front();
        const int g = static_cast<int>(gf);
        if (g >= G - 1) return sm.back();
        return sm[size_t(g)] + (gf - g) * (sm[size_t(g) + 1] - sm[size_t(g)]);
    };
    row.xi.assign(size_t(W) + 1, 0.0);
    for (int x = 0; x < W; ++x) row.xi[size_t(x) + 1] = row.xi[size_t(x)] + sm_at(x + 0.5);
    row.dxi = std::max(narrow / kAcrossNodes, 0.25 * c * sm_min);
    row.inv_dxi = 1.0 / row.dxi;
    row.taps = static_cast<int>(std::ceil(wide / row.dxi)) + 1;
    row.xi0 = f.xi_at(row, -row.margin) - (row.taps + 1) * row.dxi;
    row.nodes = static_cast<int>(std::ceil((f.xi_at(row, W + row.margin) - row.xi0) / row.dxi)) +
                row.taps + 2;
    row.segment_node.assign(size_t(G) + 1, 0);
    for (int g = 1; g < G; ++g)
        row.segment_node[size_t(g)] = std::clamp(
            static_cast<int>(std::ceil((f.xi_at(row, g * f.m_segment_px) - row.xi0) / row.dxi)),
            0, row.nodes);
    row.segment_node[size_t(G)] = row.nodes;
}

/// The coefficients of the profiles 0 .. 4 at across offset v of a place and bin: the chord
/// convolved with the remaining Gaussian, a Gaussian of mean mu and variance var + q / s_major^2
/// with the Edgeworth term of its kurtosis (the line form), expanded around N(u; sbar):
/// N(u - mu; sbar + d) = sum (-mu)^i / i! (d/2)^j / j! N^(i + 2j)(u) (docs/perspective.md §5.2).
std::array<double, kProfiles> FarField::Setup::chord_terms(const Place& p, int bin, double sbar,
                                                           double v) const {
    const auto& b = p.blend;
    const double ism2 = 1.0 / (p.s_major * p.s_major), ism4 = ism2 * ism2;
    const std::array<int, 2> lv = {b.lo, b.hi};
    const std::array<double, 2> bw = {b.lo == b.hi ? 1.0 : 1.0 - b.weight,
                                      b.lo == b.hi ? 0.0 : b.weight};
    const std::array<double, 2> var = {p.var_lo, p.var_hi};
    std::array<double, kProfiles> a{};
    for (int q = 0; q < 2; ++q) {
        if (bw[size_t(q)] == 0.0) continue;
        const int l = lv[size_t(q)];
        const double R = pyr.radius(l);
        double P = 0.0, mu = 0.0, qv = 0.0, k4 = 0.0;
        if (pyr.radial()) {
            const double tt = v * v / (R * R);
            if (!(tt < 1.0)) continue;
            const auto& tab = pyr.tables(l);
            P = table_at(tab.line_mass, tt), qv = table_at(tab.line_var, tt);
            k4 = table_at(tab.line_k4, tt);
        } else {
            const auto& tab = pyr.direction_tables(l, bin);
            P = signed_table_at(tab.mass, v, R);
            if (P == 0.0) continue;
            mu = f.m_u_sign * signed_table_at(tab.mean, v, R) / p.s_major;
            qv = signed_table_at(tab.var, v, R);
            k4 = signed_table_at(tab.k4, v, R);
        }
        const double d = var[size_t(q)] + qv * ism2 - sbar;
        const double w = bw[size_t(q)] * P;
        a[0] += w;
        a[1] += w * -mu;
        a[2] += w * (0.5 * d + 0.5 * mu * mu);
        a[3] += w * (-0.5 * mu * d - mu * mu * mu / 6.0);
        a[4] += w * (0.125 * d * d + 0.25 * mu * mu * d + mu * mu * mu * mu / 24.0 +
                     k4 * ism4 / 24.0);
    }
    return a;
}

/// The linear deposit and the linear interpolation back to the pixels each blur the profile by
/// a tent of half-width dxi: together about (1 + dxi^2 / 6 d^2/dxi^2); a table of T values is
/// sharpened by the inverse, T - dxi^2 / 6 T'' (docs/perspective.md §5.4).
namespace {
void sharpen(float* t, int T, std::vector<float>& sharp) {
    sharp.resize(static_cast<size_t>(T));
    for (int k = 0; k < T; ++k) {
        const float left = k > 0 ? t[k - 1] : 0.0f, right = k + 1 < T ? t[k + 1] : 0.0f;
        sharp[size_t(k)] = t[k] - (left - 2.0f * t[k] + right) / 6.0f;
    }
    std::copy(sharp.begin(), sharp.end(), t);
}
}  // namespace

/// Segment g's weight, along variances and profile tables on a sub-row; `peak` takes the
/// largest of each profile relative to sbar^(m/2).
void FarField::Setup::place_tables(Row& row, int g, const Place& p,
                                   std::array<double, kProfiles>& peak) const {
    const int T = 2 * row.taps + 1;
    row.weight[size_t(g)] =
        static_cast<float>(p.plan.fade / (std::sqrt(2.0 * std::numbers::pi) * p.s_major));
    std::vector<float> sharp;
    for (int bin = 0; bin < NB; ++bin) {
        const double sbar = sbar_of(p, bin);
        row.sbar[size_t(g) * NB + bin] = static_cast<float>(sbar);
        float* t0 = row.tables.data() + (size_t(g) * NB + size_t(bin)) * kProfiles * T;
        for (int k = -row.taps; k <= row.taps; ++k) {
            const double v = f.m_v_sign * k * row.dxi;
            const std::array<double, kProfiles> a = chord_terms(p, bin, sbar, v);
            for (int m = 0; m < kProfiles; ++m) {
                t0[size_t(m) * T + size_t(k + row.taps)] = static_cast<float>(a[size_t(m)]);
                peak[size_t(m)] =
                    std::max(peak[size_t(m)], std::abs(a[size_t(m)]) / std::pow(sbar, 0.5 * m));
            }
        }
        for (int m = 0; m < kProfiles; ++m) sharpen(t0 + size_t(m) * T, T, sharp);
    }
}

/// Which image row j the far field reaches: y' at 33 columns of both pixel edges of the row
/// (along a row rho is smallest at one column and grows away from it, so the samples bound the
/// row's range), widened by the along filter's reach.
bool FarField::Setup::row_in_reach(int j, double smax, double y_lo, double y_hi) const {
    constexpr int kCols = 33;
    double lo = 1e300, hi = -1e300, kmax = 0.0;
    for (int k = 0; k < kCols; ++k) {
        const double px = W * (k + 0.5) / kCols;
        double x0, y0, x1, y1;
        const bool h0 = view.texture_point(px, j, x0, y0);
        const bool h1 = view.texture_point(px, j + 1.0, x1, y1);
        if (!h0 && !h1) continue;
        const double e0 = h0 ? f.y_of(std::sqrt(sq(x0 - cam.x) + sq(y0 - cam.y)))
                             : f.y_of(std::sqrt(sq(x1 - cam.x) + sq(y1 - cam.y)));
        const double e1 = h1 ? f.y_of(std::sqrt(sq(x1 - cam.x) + sq(y1 - cam.y))) : e0;
        lo = std::min(lo, std::min(e0, e1)), hi = std::max(hi, std::max(e0, e1));
        kmax = std::max(kmax, std::abs(e1 - e0));
    }
    const double reach = kAlongReach * std::sqrt(smax) * std::max(kmax, 1.0) + 2.0 * f.m_dy;
    return hi >= y_lo - reach && lo <= y_hi + reach;
}

/// The image rows [m_j0, m_j1) that receive the far field; false when none.
bool FarField::Setup::pixel_rows() {
    double smax = c * c;
    for (const Row& row : f.m_rows)
        for (float sb : row.sbar) smax = std::max(smax, static_cast<double>(sb));
    const int rows = static_cast<int>(f.m_rows.size());
    const double y_lo = f.m_y0, y_hi = f.m_y0 + (rows - 1) * f.m_dy;
    std::vector<uint8_t> use(static_cast<size_t>(H), 0);
    tbb::parallel_for(0, H, [&](int j) { use[size_t(j)] = row_in_reach(j, smax, y_lo, y_hi); });
    f.m_j0 = H, f.m_j1 = 0;
    for (int j = 0; j < H; ++j)
        if (use[size_t(j)]) f.m_j0 = std::min(f.m_j0, j), f.m_j1 = j + 1;
    return f.m_j0 < f.m_j1;
}

/// Pixel (i, j)'s along filter: its y', scale kappa = dy'/dy (from rho at the pixel's upper
/// and lower edges) and, per direction bin, the along variance s (docs/perspective.md §5.5).
void FarField::Setup::pixel_filter(int j, int i) {
    const int rows = static_cast<int>(f.m_rows.size());
    const size_t np = size_t(f.m_j1 - f.m_j0) * W;
    const size_t p = size_t(j - f.m_j0) * W + i, q = size_t(j) * W + i;
    if (!coords.hit[q]) return;
    const double rho = std::sqrt(sq(double(coords.x[q])) + sq(double(coords.y[q])));
    const double yc = f.y_of(rho);
    const double r0 = f.m_rho_edge[size_t(j - f.m_j0) * W + i];
    const double r1 = f.m_rho_edge[size_t(j + 1 - f.m_j0) * W + i];
    double kappa = r0 >= 0.0 && r1 >= 0.0 ? std::abs(f.y_of(r1) - f.y_of(r0))
                   : r0 >= 0.0            ? 2.0 * std::abs(yc - f.y_of(r0))
                   : r1 >= 0.0            ? 2.0 * std::abs(f.y_of(r1) - yc)
                                          : 0.0;
    if (!(kappa > 0.0)) return;
    const int r = std::clamp(static_cast<int>(std::lround((yc - f.m_y0) / f.m_dy)), 0, rows - 1);
    const int g = std::clamp(static_cast<int>((i + 0.5) / f.m_segment_px), 0, G - 1);
    // The linear deposit spreads an impulse over two sub-rows: variance dy^2 / 6 on
    // average (in y'), taken off the along Gaussian (one per direction bin).
    f.m_yp[p] = static_cast<float>(yc);
    f.m_ik[p] = static_cast<float>(1.0 / kappa);
    for (int b = 0; b < NB; ++b) {
        const double sbar = f.m_rows[size_t(r)].sbar[size_t(g) * NB + b];
        const double s = std::max(0.5 * sbar, sbar - f.m_dy * f.m_dy / (6.0 * kappa * kappa));
        f.m_is[size_t(b) * np + p] = static_cast<float>(1.0 / s);
        f.m_rs[size_t(b) * np + p] = static_cast<float>(1.0 / std::sqrt(s));
    }
}

/// rho at the pixel edges (row boundaries m_j0 .. m_j1) of the rows reached, then every
/// pixel's along filter.
void FarField::Setup::pixel_filters() {
    std::vector<double>& rho_edge = f.m_rho_edge;
    rho_edge.assign(size_t(W) * (f.m_j1 - f.m_j0 + 1), -1.0);
    tbb::parallel_for(f.m_j0, f.m_j1 + 1, [&](int e) {
        std::vector<float> ex(static_cast<size_t>(W)), ey(static_cast<size_t>(W));
        std::vector<uint8_t> hit(static_cast<size_t>(W));
        view.texture_row(e, W, cam.x, cam.y, ex.data(), ey.data(), hit.data());
        for (int i = 0; i < W; ++i)
            rho_edge[size_t(e - f.m_j0) * W + i] =
                hit[size_t(i)] ? std::sqrt(sq(double(ex[size_t(i)])) + sq(double(ey[size_t(i)])))
                               : -1.0;
    });
    const size_t np = size_t(f.m_j1 - f.m_j0) * W;
    f.m_yp.assign(np, 0.0f), f.m_ik.assign(np, 0.0f);
    f.m_is.assign(np * NB, 0.0f), f.m_rs.assign(np * NB, 0.0f);
    tbb::parallel_for(f.m_j0, f.m_j1, [&](int j) {
        for (int i = 0; i < W; ++i) pixel_filter(j, i);
    });
}

/// Each pixel sums the sub-rows within kAlongReach sd of its own y' only. The reach is kept
/// per piece of kAlongPiece columns: sub-rows follow circles, which bend across the image, so
/// the reach of a whole row is several times that of any of its pixels. A function of the
/// set-up alone: made once with it (FarField::m_reach0, m_reach1).
void FarField::Setup::along_reach() {
    const size_t np = f.m_yp.size();
    const int nrow = f.m_j1 - f.m_j0, rows = static_cast<int>(f.m_rows.size());
    const int pieces = (W + kAlongPiece - 1) / kAlongPiece;
    std::vector<int>& reach0 = f.m_reach0;
    std::vector<int>& reach1 = f.m_reach1;
    reach0.assign(size_t(nrow) * pieces, rows), reach1.assign(size_t(nrow) * pieces, 0);
    for (int jj = 0; jj < nrow; ++jj) {
        for (int pc = 0; pc < pieces; ++pc) {
            double lo = 1e300, hi = -1e300;
            for (int i = pc * kAlongPiece; i < std::min(W, (pc + 1) * kAlongPiece); ++i) {
                const size_t p = size_t(jj) * W + i;
                if (f.m_ik[p] == 0.0f) continue;
                double smax = 0.0;
                for (int b = 0; b < NB; ++b)
                    smax = std::max(smax, 1.0 / double(f.m_is[size_t(b) * np + p]));
                const double reach = kAlongReach * std::sqrt(smax) / f.m_ik[p];
                lo = std::min(lo, f.m_yp[p] - reach), hi = std::max(hi, f.m_yp[p] + reach);
            }
            if (!(lo <= hi)) continue;
            const size_t e = size_t(jj) * pieces + pc;
            reach0[e] = std::max(0, static_cast<int>(std::floor((lo - f.m_y0) / f.m_dy)));
            reach1[e] = std::min(rows, static_cast<int>(std::ceil((hi - f.m_y0) / f.m_dy)) + 1);
        }
    }
}

void FarField::setup(const kernels::KernelPyramid& pyr, const PerspectiveView& view,
                     const PixelCoords& coords, const AntiAlias& aa) {
    // Everything below is set afresh but the arrays' memory (m_v_sign, which the frame may not
    // set, included).
    m_active = false;
    m_v_sign = 1.0;
    Setup s(*this, pyr, view, coords, aa);
    if (!s.frame()) return;
    s.column_lines();
    s.mean_chord_variances();
    if (!s.far_zone()) return;
    s.depth_min();
    if (!s.sub_rows()) return;
    s.table_orientation();
    tbb::parallel_for(0, static_cast<int>(m_rows.size()), [&](int r) { s.row(r); });
    if (!s.pixel_rows()) return;
    s.pixel_filters();
    s.along_reach();
    m_active = true;
}

inline double FarField::xi_at(const Row& row, double x) const {
    const int W = m_width;
    if (x <= 0.0) return row.xi[0] + x * (row.xi[1] - row.xi[0]);
    if (x >= W) return row.xi[size_t(W)] + (x - W) * (row.xi[size_t(W)] - row.xi[size_t(W) - 1]);
    const int i = std::min(static_cast<int>(x), W - 1);
    return row.xi[size_t(i)] + (x - i) * (row.xi[size_t(i) + 1] - row.xi[size_t(i)]);
}

inline float FarField::row_weight(const Row& row, double sx) const {
    // Linear between segment centres (held beyond the first and last).
    const double gf = sx * m_inv_segment_px - 0.5;
    if (!(gf > 0.0)) return row.weight.front();
    const int g = static_cast<int>(gf);
    if (g >= m_segments - 1) return row.weight.back();
    const double t = gf - g;
    return static_cast<float>((1.0 - t) * row.weight[size_t(g)] + t * row.weight[size_t(g) + 1]);
}

bool FarField::item(double rx, double ry, double q, double sx, float weight, double theta,
                    FarItem& it) const {
    const int r = static_cast<int>(q);
    const Row& a = m_rows[size_t(r)];
    const Row& b = m_rows[size_t(r) + 1];
    const double margin = std::max(a.nodes ? a.margin : 0.0, b.nodes ? b.margin : 0.0);
    if (!(a.nodes || b.nodes) || !(sx > -margin && sx < m_width + margin)) return false;
    it.row = r;
    it.bin = 0, it.wb[0] = 1.0f, it.wb[1] = 0.0f;
    if (m_bins > 1) {
        // The direction of the footprint's major axis (away from the foot) in the kernel's
        // frame, in bins (linear weights between the two nearest).
        double gamma = std::atan2(ry, rx) - theta;
        gamma -= m_period * std::floor(gamma / m_period);
        const double pb = gamma / m_period * m_bins;
        const int b0 = std::min(static_cast<int>(pb), m_bins - 1);
        it.bin = b0;
        it.wb[1] = static_cast<float>(pb - b0), it.wb[0] = 1.0f - it.wb[1];
    }
    const double fy = q - r;
    bool any = false;
    for (int e = 0; e < 2; ++e) {
        const Row& row = e ? b : a;
        it.node[e] = -1;
        if (!row.nodes) continue;
        const double w = weight * (e ? fy : 1.0 - fy) * row_weight(row, sx);
        const double p = (xi_at(row, sx) - row.xi0) * row.inv_dxi;
        const int nd = static_cast<int>(p);
        if (w == 0.0 || nd < 0 || nd + 1 >= row.nodes) continue;
        const double fx = p - nd;
        it.node[e] = nd;
        it.w[e][0] = static_cast<float>(w * (1.0 - fx));
        it.w[e][1] = static_cast<float>(w * fx);
        any = true;
    }
    return any;
}


/// The steps of FarField::render and what they share (docs/perspective.md §5.6).
struct FarField::Pass {
    const FarField& f;
    const Impulses& in;
    const PerspLoops& loops;
    bool parallel = true;
    FarScratch& scratch;
    int rows = 0, W = 0, B = 1, bands = 0;
    std::vector<size_t> off;         ///< sub-row r's grids start at off[r] in scratch.grids
    std::vector<size_t> band_start;  ///< band b's impulses: order[band_start[b] .. b + 1]
    std::vector<std::vector<float>> halo;  ///< per band: the deposit on the row after it
    std::vector<size_t> drawn_in;          ///< per band: impulses drawn
    /// Which (sub-row, bin) grids received something (each set by the band that owns the row,
    /// or by the band before through its halo: both bands set it, from disjoint tasks' items).
    std::vector<uint8_t> filled, halo_filled;
    int nrow = 0, pieces = 0;
    const std::vector<int>& reach0 = f.m_reach0;  ///< FarField::m_reach0, m_reach1
    const std::vector<int>& reach1 = f.m_reach1;

    Pass(const FarField& far, const Impulses& impulses, const PerspLoops& l, bool par,
         FarScratch& s)
        : f(far), in(impulses), loops(l), parallel(par), scratch(s) {}

    /// Buffers of one task of the across and along filters.
    struct TaskBuffers {
        std::vector<float> acc, x, zeros, frac;
        std::vector<int> node;
        std::array<std::vector<float>, kProfiles> px;
    };

    template <class F>
    void run(int n, F&& fn) const {
        if (parallel)
            tbb::parallel_for(0, n, fn);
        else
            for (int i = 0; i < n; ++i) fn(i);
    }
    size_t stride(const Row& row) const { return size_t(row.nodes + 2 * row.taps); }
    float* grid(int r, int bin) {
        const Row& row = f.m_rows[size_t(r)];
        return scratch.grids.data() + off[size_t(r)] + size_t(bin) * stride(row) +
               size_t(row.taps);
    }
    void layout_grids();
    void sort_by_band();
    void deposit_band(int b);
    void add_halo(int b);
    void filter_task(int task, Frame& out);
    /// Column runs [first, second) of the pieces a sub-row reaches from a task's output rows.
    using Runs = std::vector<std::pair<int, int>>;
    void task_hull(int ja, int jb, std::vector<int>& lo, std::vector<int>& hi) const;
    void reached_runs(int r, const std::vector<int>& lo, const std::vector<int>& hi,
                      Runs& runs) const;
    void pixel_nodes(const Row& row, const Runs& runs, TaskBuffers& buf) const;
    int across(const Row& row, int r, int bin, const Runs& runs, TaskBuffers& buf,
               std::array<const float*, kProfiles>& xp);
    void along(int r, int bin, int ja, int jb, float yr,
               const std::array<const float*, kProfiles>& xp, int terms, TaskBuffers& buf) const;
};

/// Node grids, one per sub-row and direction bin (with `taps` zeros each side for the
/// convolution).
void FarField::Pass::layout_grids() {
    off.assign(static_cast<size_t>(rows) + 1, 0);
    for (int r = 0; r < rows; ++r) {
        const Row& row = f.m_rows[size_t(r)];
        off[size_t(r) + 1] = off[size_t(r)] + (row.nodes ? size_t(B) * stride(row) : 0);
    }
    scratch.grids.assign(off.back(), 0.0f);
}

/// The far impulses sorted by band in canonical order: a counting sort of their indices, 4
/// bytes each (a frame has millions, and memory new to the process costs a page fault per
/// 4 KiB).
void FarField::Pass::sort_by_band() {
    const size_t n = in.imp->size();
    const int chunks = static_cast<int>((n + in.chunk - 1) / in.chunk);
    std::vector<size_t> start(size_t(chunks) * bands + 1, 0);
    band_start.assign(static_cast<size_t>(bands) + 1, 0);
    size_t total = 0;
    for (int b = 0; b < bands; ++b) {
        band_start[size_t(b)] = total;
        for (int c = 0; c < chunks; ++c) {
            start[size_t(c) * bands + b] = total;
            total += in.counts[size_t(c) * bands + b];
        }
    }
    band_start[size_t(bands)] = total;
    std::vector<uint32_t>& order = scratch.order;
    order.resize(band_start.back());
    run(chunks, [&](int c) {
        std::vector<size_t> fill(start.begin() + ptrdiff_t(c) * bands,
                                 start.begin() + ptrdiff_t(c + 1) * bands);
        const size_t i1 = std::min(n, (size_t(c) + 1) * in.chunk);
        for (size_t i = size_t(c) * in.chunk; i < i1; ++i)
            if (in.q[i] >= 0.0) order[fill[size_t(band_of(in.q[i]))]++] = static_cast<uint32_t>(i);
    });
}

/// Band b's deposit: its items made (from the sub-row coordinates the preparation computed)
/// and summed by this one task into its rows, the row after the band into its halo.
void FarField::Pass::deposit_band(int b) {
    const sim::Impulses& imp = *in.imp;
    const std::vector<uint32_t>& order = scratch.order;
    const int last = std::min(rows, (b + 1) * kBand);  // first row after the band
    const size_t hn = last < rows ? size_t(f.m_rows[size_t(last)].nodes) : 0;
    if (hn) halo[size_t(b)].assign(size_t(B) * hn, 0.0f);
    size_t drawn = 0;
    // Items are made kItemBlock at a time: the image column of a block first (a divide per
    // impulse, whose latency dominated, in a loop the compiler vectorises; the same
    // operations in the same order, so the same bits), then the rest per impulse.
    constexpr int kItemBlock = 8;
    std::array<double, kItemBlock> rx{}, ry{}, sx{};
    const size_t k0 = band_start[size_t(b)], k1 = band_start[size_t(b) + 1];
    for (size_t kb = k0; kb < k1; kb += kItemBlock) {
        const int m = static_cast<int>(std::min<size_t>(kItemBlock, k1 - kb));
        for (int j = 0; j < m; ++j) {
            const size_t i = order[kb + size_t(j)];
            rx[size_t(j)] = imp.x[i] - in.cam_x, ry[size_t(j)] = imp.y[i] - in.cam_y;
        }
        for (int j = 0; j < kItemBlock; ++j) sx[size_t(j)] = f.column(rx[size_t(j)], ry[size_t(j)]);
        for (int j = 0; j < m; ++j) {
            const size_t i = order[kb + size_t(j)];
            FarItem it;
            if (!f.item(rx[size_t(j)], ry[size_t(j)], in.q[i], sx[size_t(j)], imp.weight[i],
                        in.orient + static_cast<double>(imp.theta[i]), it))
                continue;
            ++drawn;
            for (int e = 0; e < 2; ++e) {
                const int r = it.row + e, nd = it.node[e];
                if (nd < 0) continue;
                for (int q = 0; q < (B > 1 ? 2 : 1); ++q) {
                    const int bin = (it.bin + q) % B;
                    float* d = r == last ? halo[size_t(b)].data() + size_t(bin) * hn : grid(r, bin);
                    d[nd] += it.wb[q] * it.w[e][0];
                    d[nd + 1] += it.wb[q] * it.w[e][1];
                    (r == last ? halo_filled[size_t(b) * B + bin] : filled[size_t(r) * B + bin]) =
                        1;
                }
            }
        }
    }
    drawn_in[size_t(b)] = drawn;
}

/// Adds band b's halo to the first row of the next band (after all deposits: a fixed order).
void FarField::Pass::add_halo(int b) {
    const int r = (b + 1) * kBand;
    if (r >= rows || halo[size_t(b)].empty()) return;
    const size_t hn = size_t(f.m_rows[size_t(r)].nodes);
    for (int bin = 0; bin < B; ++bin) {
        if (!halo_filled[size_t(b) * B + bin]) continue;
        filled[size_t(r) * B + bin] = 1;
        float* d = grid(r, bin);
        const float* h = halo[size_t(b)].data() + size_t(bin) * hn;
        for (size_t k = 0; k < hn; ++k) d[k] += h[k];
    }
}

/// Per piece of columns, the hull [lo, hi) of the sub-rows that output rows [ja, jb) reach
/// (a superset of what along() reads: across() computes the pixels of these pieces only).
void FarField::Pass::task_hull(int ja, int jb, std::vector<int>& lo, std::vector<int>& hi) const {
    lo.assign(size_t(pieces), rows), hi.assign(size_t(pieces), 0);
    for (int jj = ja; jj < jb; ++jj)
        for (int c = 0; c < pieces; ++c) {
            const size_t e = size_t(jj) * pieces + c;
            if (reach0[e] >= reach1[e]) continue;
            lo[size_t(c)] = std::min(lo[size_t(c)], reach0[e]);
            hi[size_t(c)] = std::max(hi[size_t(c)], reach1[e]);
        }
}

/// The runs of consecutive pieces whose hull holds sub-row r, as column ranges.
void FarField::Pass::reached_runs(int r, const std::vector<int>& lo, const std::vector<int>& hi,
                                  Runs& runs) const {
    runs.clear();
    for (int c = 0; c < pieces;) {
        if (r < lo[size_t(c)] || r >= hi[size_t(c)]) {
            ++c;
            continue;
        }
        const int c0 = c;
        while (c < pieces && r >= lo[size_t(c)] && r < hi[size_t(c)]) ++c;
        runs.emplace_back(c0 * kAlongPiece, std::min(W, c * kAlongPiece));
    }
}

/// The node left of each pixel centre of the runs and the fraction to the next (linear
/// interpolation from the nodes to the pixels).
void FarField::Pass::pixel_nodes(const Row& row, const Runs& runs, TaskBuffers& buf) const {
    for (const auto& [i0, i1] : runs)
        for (int i = i0; i < i1; ++i) {
            const double p = (f.xi_at(row, i + 0.5) - row.xi0) / row.dxi;
            buf.node[size_t(i)] = static_cast<int>(p);
            buf.frac[size_t(i)] = static_cast<float>(p - buf.node[size_t(i)]);
        }
}

/// Sub-row r, bin `bin`, convolved across with its segments' profiles and sampled at the pixel
/// centres of the runs (linear between nodes, buf.node and buf.frac): xp[m] points at profile
/// m's samples (zeros when unused); returns the far_along term bits. Only the nodes the runs'
/// pixels read are convolved: each node's sum is the same whichever others are (far_across
/// sums every node's taps in the same order), so the pixels' values do not depend on the runs.
int FarField::Pass::across(const Row& row, int r, int bin, const Runs& runs, TaskBuffers& buf,
                           std::array<const float*, kProfiles>& xp) {
    const int T = 2 * row.taps + 1;
    const float* d = grid(r, bin);
    int terms = 0;
    for (int m = 0; m < kProfiles; ++m) {
        xp[size_t(m)] = buf.zeros.data();
        if (!row.used[size_t(m)]) continue;
        auto& v = buf.px[size_t(m)];
        v.resize(size_t(W));
        for (const auto& [i0, i1] : runs) {
            int na = row.nodes, nb = 0;  // nodes [na, nb) that the run's pixels read
            for (int i = i0; i < i1; ++i)
                na = std::min(na, buf.node[size_t(i)]), nb = std::max(nb, buf.node[size_t(i)] + 2);
            nb = std::min(nb, row.nodes);
            if (na >= nb) continue;
            std::fill(buf.x.begin() + na, buf.x.begin() + nb, 0.0f);
            for (int g = 0; g < f.m_segments; ++g) {
                const int n0 = std::max(na, row.segment_node[size_t(g)]);
                const int n1 = std::min(nb, row.segment_node[size_t(g) + 1]);
                if (n0 >= n1) continue;
                const float* t = row.tables.data() +
                                 ((size_t(g) * B + size_t(bin)) * kProfiles + size_t(m)) * T;
                loops.far_across(d, t + row.taps, row.taps, n0, n1, buf.x.data());  // writes
            }
            for (int i = i0; i < i1; ++i) {
                const size_t nd = size_t(buf.node[size_t(i)]);
                v[size_t(i)] = buf.x[nd] + buf.frac[size_t(i)] * (buf.x[nd + 1] - buf.x[nd]);
            }
        }
        xp[size_t(m)] = v.data();
        if (m) terms |= m == 1 || m == 3 ? 2 : 1;
    }
    return terms;
}

/// Adds sub-row r's profiles (bin `bin`) through the along filter to the task's output rows
/// [ja, jb), over the runs of consecutive pieces that the sub-row reaches.
void FarField::Pass::along(int r, int bin, int ja, int jb, float yr,
                           const std::array<const float*, kProfiles>& xp, int terms,
                           TaskBuffers& buf) const {
    const size_t np = f.m_yp.size();
    for (int jj = ja; jj < jb; ++jj) {
        const int* r0 = reach0.data() + size_t(jj) * pieces;
        const int* r1 = reach1.data() + size_t(jj) * pieces;
        for (int c = 0; c < pieces;) {
            if (r < r0[c] || r >= r1[c]) {
                ++c;
                continue;
            }
            const int c0 = c;
            while (c < pieces && r >= r0[c] && r < r1[c]) ++c;
            const int i0 = c0 * kAlongPiece, i1 = std::min(W, c * kAlongPiece);
            const size_t p = size_t(jj) * W + i0, pb = size_t(bin) * np + p;
            std::array<const float*, kProfiles> xq;
            for (int m = 0; m < kProfiles; ++m) xq[size_t(m)] = xp[size_t(m)] + i0;
            loops.far_along(f.m_yp.data() + p, f.m_ik.data() + p, f.m_is.data() + pb,
                            f.m_rs.data() + pb, i1 - i0, yr, xq.data(), terms,
                            buf.acc.data() + size_t(jj - ja) * W + i0);
        }
    }
}

/// One task of the across and along filters: output rows [ja, jb) of the far field's rows,
/// written by it alone. Sub-rows are visited in order, so every pixel sums them in the same
/// order.
void FarField::Pass::filter_task(int task, Frame& out) {
    const int ja = task * kRowsPerTask, jb = std::min(nrow, ja + kRowsPerTask);
    int ra = rows, rb = 0;
    for (size_t e = size_t(ja) * pieces; e < size_t(jb) * pieces; ++e)
        ra = std::min(ra, reach0[e]), rb = std::max(rb, reach1[e]);
    TaskBuffers buf;
    buf.acc.assign(size_t(jb - ja) * W, 0.0f);
    buf.zeros.assign(static_cast<size_t>(W), 0.0f), buf.frac.resize(static_cast<size_t>(W));
    buf.node.resize(static_cast<size_t>(W));
    std::vector<int> lo, hi;
    task_hull(ja, jb, lo, hi);
    Runs runs;
    for (int r = ra; r < rb; ++r) {
        const Row& row = f.m_rows[size_t(r)];
        if (!row.nodes) continue;
        bool any = false;
        for (int bin = 0; bin < B; ++bin) any = any || filled[size_t(r) * B + bin];
        if (!any) continue;
        reached_runs(r, lo, hi, runs);
        if (runs.empty()) continue;
        buf.x.resize(size_t(row.nodes));
        pixel_nodes(row, runs, buf);
        for (int bin = 0; bin < B; ++bin) {
            if (!filled[size_t(r) * B + bin]) continue;
            std::array<const float*, kProfiles> xp{};
            const int terms = across(row, r, bin, runs, buf, xp);
            along(r, bin, ja, jb, static_cast<float>(row.y), xp, terms, buf);
        }
    }
    for (int jj = ja; jj < jb; ++jj) {
        float* dst = out.data.data() + size_t(f.m_j0 + jj) * W;
        const float* src = buf.acc.data() + size_t(jj - ja) * W;
        for (int i = 0; i < W; ++i) dst[i] += src[i];
    }
}

size_t FarField::render(const Impulses& in, Frame& out, const PerspLoops& loops, bool parallel,
                        FarScratch& scratch) const {
    Pass s(*this, in, loops, parallel, scratch);
    s.rows = static_cast<int>(m_rows.size()), s.W = m_width, s.B = m_bins, s.bands = bands();
    s.layout_grids();
    // Deposit by bands of sub-rows, then the halos between bands.
    s.sort_by_band();
    s.halo.resize(static_cast<size_t>(s.bands));
    s.drawn_in.assign(static_cast<size_t>(s.bands), 0);
    s.filled.assign(size_t(s.rows) * s.B, 0), s.halo_filled.assign(size_t(s.bands) * s.B, 0);
    s.run(s.bands, [&](int b) { s.deposit_band(b); });
    s.run(s.bands, [&](int b) { s.add_halo(b); });
    // Across and along, by bands of output rows: for each sub-row within reach of the band and
    // each direction bin, the sub-row is convolved across with its segments' profiles and
    // sampled at the pixel centres, then added to every pixel of the band it reaches through
    // the along filter of that bin.
    s.nrow = m_j1 - m_j0, s.pieces = (m_width + kAlongPiece - 1) / kAlongPiece;
    const int tasks = (s.nrow + kRowsPerTask - 1) / kRowsPerTask;
    s.run(tasks, [&](int task) { s.filter_task(task, out); });
    size_t drawn = 0;
    for (size_t d : s.drawn_in) drawn += d;
    return drawn;
}

}  // namespace impulse::render::detail
