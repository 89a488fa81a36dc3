// SPDX-License-Identifier: Apache-2.0
// The far field of a perspective view: impulses deposited on sub-rows along the circles around
// the camera's foot, convolved across with the line-form profiles, filtered along per pixel
// (render/persp_far.h, render/perspective.h).

#include "render/persp_far.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

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

void FarField::setup(const kernels::KernelPyramid& pyr, const PerspectiveView& view,
                     const PixelCoords& coords, const AntiAlias& aa) {
    // Everything below is set afresh but the arrays' memory (m_v_sign, which the frame may not
    // set, included).
    m_active = false;
    m_v_sign = 1.0;
    if (!(aa.far_field && aa.enabled && aa.anisotropic && aa.fade)) return;
    if (!pyr.radial() && pyr.direction_bins() == 0) return;
    m_bins = pyr.radial() ? 1 : pyr.direction_bins();
    m_period = pyr.radial() ? 1.0 : pyr.direction_period();
    const auto& cam = view.camera();
    const int W = cam.width, H = cam.height;
    m_width = W, m_height = H;
    const double c = filter_sigma_px(aa);
    const double hz = view.horizon_row();
    if (!std::isfinite(hz) || std::abs(hz) > 1e7) return;
    const double toward = cam.plane == Plane::Ground ? 1.0 : -1.0;  // image rows nearer the camera
    view.range_row(m_ya, m_yb, m_yc, m_yd);
    m_segments =
        std::max(1, static_cast<int>(std::ceil(W / std::max(4.0, kSegmentRad * view.focal_px()))));
    m_segment_px = static_cast<double>(W) / m_segments;
    m_inv_segment_px = 1.0 / m_segment_px;
    view.homography(m_P);
    const int G = m_segments;

    // Column lines of the segment centres.
    std::vector<ColumnLine> lines(static_cast<size_t>(G));
    for (int g = 0; g < G; ++g) {
        const double px = (g + 0.5) * m_segment_px;
        double ax, ay, bx, by;
        auto& L = lines[size_t(g)];
        if (!view.texture_point(px, hz + toward * 1.0, ax, ay) ||
            !view.texture_point(px, hz + toward * 2.0, bx, by))
            continue;
        L.bx = bx - cam.x, L.by = by - cam.y, L.dx = ax - bx, L.dy = ay - by;
        L.ok = true;
    }
    // The place at distance rho from the foot on column line g.
    auto place = [&](int g, double rho) {
        Place p;
        const ColumnLine& L = lines[size_t(g)];
        if (!L.ok) return p;
        const double dd = L.dx * L.dx + L.dy * L.dy, bd = L.bx * L.dx + L.by * L.dy;
        const double disc = bd * bd - dd * (L.bx * L.bx + L.by * L.by - rho * rho);
        if (!(disc >= 0.0) || !(dd > 0.0)) return p;
        const double t = (-bd + std::sqrt(disc)) / dd;
        const double x = cam.x + L.bx + t * L.dx, y = cam.y + L.by + t * L.dy;
        if (!(view.depth(x, y) > 0.0)) return p;
        const auto f = view.footprint(x, y);
        p.plan = plan_for(pyr, aa, f.s_major, f.s_minor);
        p.s_major = f.s_major, p.s_minor = f.s_minor;
        p.blend = pyr.select(std::max(c * f.s_minor, pyr.sigma(0)), aa.blend);
        const double sM2 = c * c * f.s_major * f.s_major;
        p.var_lo = std::max(0.0, sM2 - level_blur2(pyr, p.blend.lo)) / (f.s_major * f.s_major);
        p.var_hi = std::max(0.0, sM2 - level_blur2(pyr, p.blend.hi)) / (f.s_major * f.s_major);
        p.ok = true;
        return p;
    };
    // Whether the expansion converges at a place (see kFarVariance).
    // Mean chord variance per level and direction bin: each bin has its own along Gaussian.
    const int NB = m_bins;
    std::vector<double> qbar(size_t(pyr.levels()) * NB);
    for (int l = 0; l < pyr.levels(); ++l)
        for (int b = 0; b < NB; ++b)
            qbar[size_t(l) * NB + b] =
                pyr.radial() ? mean_chord_variance(pyr, l) : mean_chord_variance_dir(pyr, l, b);
    // The variance of the along Gaussian of a place and bin.
    auto sbar_of = [&](const Place& p, int bin) {
        const auto& b = p.blend;
        const double ism2 = 1.0 / (p.s_major * p.s_major);
        const double wl = b.lo == b.hi ? 1.0 : 1.0 - b.weight, wh = b.lo == b.hi ? 0.0 : b.weight;
        return wl * (p.var_lo + qbar[size_t(b.lo) * NB + bin] * ism2) +
               wh * (p.var_hi + qbar[size_t(b.hi) * NB + bin] * ism2);
    };
    auto converges = [&](const Place& p) {
        const auto& b = p.blend;
        const double ism2 = 1.0 / (p.s_major * p.s_major);
        const std::array<int, 2> lv = {b.lo, b.hi};
        const std::array<double, 2> bw = {b.lo == b.hi ? 1.0 : 1.0 - b.weight,
                                          b.lo == b.hi ? 0.0 : b.weight};
        const std::array<double, 2> var = {p.var_lo, p.var_hi};
        // Mass-weighted mean squares of the chords' departures (radial tables are sampled
        // uniformly in t = v^2 / R^2, so their weight per sample is P dv ~ P / sqrt(t)).
        // (relative to the bin's own sbar: the mean squares of d / sbar and mu^2 / sbar)
        double m0 = 0.0, mvar = 0.0, mmean = 0.0;
        auto scan = [&](const std::vector<float>& mass, const std::vector<float>& q,
                        const std::vector<float>* mean, double v, double w, bool radial,
                        double sbar) {
            const size_t n = mass.size();
            for (size_t i = 0; i < n; ++i) {
                const double t = (i + 0.5) / static_cast<double>(n);
                const double pw = w * mass[i] * (radial ? 0.5 / std::sqrt(t) : 1.0);
                const double d = v + q[i] * ism2 - sbar;
                m0 += pw, mvar += pw * d * d / (sbar * sbar);
                if (mean) mmean += pw * sq((*mean)[i] / p.s_major) / sbar;
            }
        };
        for (int k = 0; k < 2; ++k) {
            if (bw[size_t(k)] == 0.0) continue;
            const int l = lv[size_t(k)];
            if (pyr.radial())
                scan(pyr.tables(l).line_mass, pyr.tables(l).line_var, nullptr, var[size_t(k)],
                     bw[size_t(k)], true, sbar_of(p, 0));
            else
                for (int bin = 0; bin < pyr.direction_bins(); ++bin) {
                    const auto& t = pyr.direction_tables(l, bin);
                    scan(t.mass, t.var, &t.mean, var[size_t(k)], bw[size_t(k)], false,
                         sbar_of(p, bin));
                }
        }
        if (!(m0 > 0.0)) return false;
        return std::sqrt(mvar / m0) <= kFarVariance && std::sqrt(mmean / m0) <= kFarMean;
    };
    // A place is far when it is faded out, or its footprint is elongated (not the single form),
    // the levels are of one sign and the chord is short.
    auto far_at = [&](int g, double rho) {
        const Place p = place(g, rho);
        if (!p.ok) return false;
        if (!p.plan.keep) return true;
        if (p.plan.mode == kPerspSingle) return false;
        if (!pyr.nonnegative(p.blend.lo) || !pyr.nonnegative(p.blend.hi)) return false;
        return converges(p);
    };
    auto kept_at = [&](int g, double rho) {
        const Place p = place(g, rho);
        return p.ok && p.plan.keep;
    };
    // Per column: the distance beyond which everything is far, and the cut-off (both
    // monotone in rho: footprints only grow with the distance). Bisection in log rho.
    double rho_far = 0.0, rho_cut = 0.0;
    for (int g = 0; g < G; ++g) {
        if (!lines[size_t(g)].ok) continue;
        double near_rho = -1.0;
        for (double py : {H - 0.5, 0.5}) {  // the image row nearest the camera
            const double row = toward > 0 ? py : H - py;
            double x, y;
            if (view.texture_point((g + 0.5) * m_segment_px, row, x, y)) {
                near_rho = std::sqrt(sq(x - cam.x) + sq(y - cam.y));
                // The circles label the far zone only where the distance from the foot grows
                // up the column from its nearest visible point on (a column line meets a
                // circle twice, on either side of its closest approach to the foot).
                const ColumnLine& L = lines[size_t(g)];
                if (!((x - cam.x) * L.dx + (y - cam.y) * L.dy > 0.0)) return;
                break;
            }
        }
        if (!(near_rho > 0.0)) continue;
        double hi = near_rho;
        while (kept_at(g, hi) && hi < 1e15) hi *= 2.0;
        if (!kept_at(g, near_rho)) continue;  // nothing drawn in this column
        double a = near_rho, b = hi;          // kept, not kept
        for (int it = 0; it < 40 && b / a > 1.0 + 1e-6; ++it) {
            const double m = std::sqrt(a * b);
            (kept_at(g, m) ? a : b) = m;
        }
        rho_cut = std::max(rho_cut, b);
        if (far_at(g, near_rho)) {
            rho_far = std::max(rho_far, near_rho);
            continue;
        }
        double fa = near_rho, fb = b;  // not far, far
        for (int it = 0; it < 40 && fb / fa > 1.0 + 1e-6; ++it) {
            const double m = std::sqrt(fa * fb);
            (far_at(g, m) ? fb : fa) = m;
        }
        rho_far = std::max(rho_far, fb);
    }
    if (!(rho_far > 0.0) || !(rho_far < rho_cut)) return;
    m_rho_far2 = rho_far * rho_far;
    // ... and an impulse belongs to it only on that side: at least the smallest depth of the
    // far zone's near edge (an impulse as far from the foot but nearer the camera lies below
    // the image, on the other side of the closest approach).
    m_depth_min = 1e300;
    for (int g = 0; g < G; ++g) {
        const ColumnLine& L = lines[size_t(g)];
        if (!L.ok) continue;
        const double dd = L.dx * L.dx + L.dy * L.dy, bd = L.bx * L.dx + L.by * L.dy;
        const double disc = bd * bd - dd * (L.bx * L.bx + L.by * L.by - m_rho_far2);
        if (!(disc >= 0.0)) continue;
        const double t = (-bd + std::sqrt(disc)) / dd;
        m_depth_min =
            std::min(m_depth_min, view.depth(cam.x + L.bx + t * L.dx, cam.y + L.by + t * L.dy));
    }
    m_depth_min *= 0.999;

    // Sub-rows over the far zone, a quarter of ... half the pixel filter apart (plus one each
    // side).
    m_dy = 0.5 * c;
    m_inv_dy = 1.0 / m_dy;
    const double ya = y_of(rho_far), yb = y_of(rho_cut);
    if (!std::isfinite(ya) || !std::isfinite(yb)) return;
    m_y0 = std::min(ya, yb) - m_dy;
    const double span = std::abs(ya - yb) + 2.0 * m_dy;
    const int rows = static_cast<int>(std::ceil(span / m_dy)) + 2;
    if (rows > 64 * H + 64) return;
    m_rows.resize(static_cast<size_t>(rows));
    // Orientation of the tables: v grows with xi (image x) when the image's x axis points left
    // of the outward direction e (turned a quarter counter-clockwise); the chord's centroid
    // (along e) moves the image row by sign(dY/drho) per unit.
    {
        double x0, y0, x1, y1;
        const double pc = 0.5 * W, pr = toward > 0 ? H - 0.5 : 0.5;
        if (view.texture_point(pc - 0.5, pr, x0, y0) && view.texture_point(pc + 0.5, pr, x1, y1)) {
            const double ex = 0.5 * (x0 + x1) - cam.x, ey = 0.5 * (y0 + y1) - cam.y;
            m_v_sign = (x1 - x0) * -ey + (y1 - y0) * ex >= 0.0 ? 1.0 : -1.0;
        }
        m_u_sign = m_ya * m_yd - m_yb * m_yc >= 0.0 ? 1.0 : -1.0;
    }

    tbb::parallel_for(0, rows, [&](int r) {
        Row& row = m_rows[size_t(r)];
        row.y = m_y0 + r * m_dy;
        // (a row of an earlier frame: its arrays are assigned below, its scalars reset here)
        row.margin = 0.0, row.xi0 = 0.0, row.dxi = row.inv_dxi = 1.0;
        row.nodes = row.taps = 0, row.used = {};
        // rho of the circle (inverse of the Moebius map), held inside the far zone
        double rho = (m_yb - m_yd * row.y) / (m_yc * row.y - m_ya);
        if (!(rho >= rho_far)) rho = rho_far;
        if (!(rho <= rho_cut)) rho = rho_cut;
        std::vector<Place> places(static_cast<size_t>(G));
        double narrow = 1e300, wide = 0.0, sm_min = 1e300;
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
        row.weight.assign(size_t(G), 0.0f);
        row.sbar.assign(size_t(G) * m_bins, static_cast<float>(c * c));
        if (!(wide > 0.0)) return;  // nothing drawn on this circle
        // The across coordinate: arc length along the circle, d xi / dx = s_minor (linear
        // between segment centres, held beyond). The kernel's profile across is then the same
        // function of xi wherever it lies on the circle; only the blend and the along filter
        // change from segment to segment.
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
            const double gf = x / m_segment_px - 0.5;
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
        row.xi0 = xi_at(row, -row.margin) - (row.taps + 1) * row.dxi;
        row.nodes = static_cast<int>(std::ceil((xi_at(row, W + row.margin) - row.xi0) / row.dxi)) +
                    row.taps + 2;
        row.segment_node.assign(size_t(G) + 1, 0);
        for (int g = 1; g < G; ++g)
            row.segment_node[size_t(g)] = std::clamp(
                static_cast<int>(std::ceil((xi_at(row, g * m_segment_px) - row.xi0) / row.dxi)), 0,
                row.nodes);
        row.segment_node[size_t(G)] = row.nodes;
        const int T = 2 * row.taps + 1;
        const int B = m_bins;
        row.tables.assign(size_t(G) * B * kProfiles * T, 0.0f);
        std::array<double, kProfiles> peak{};
        for (int g = 0; g < G; ++g) {
            const Place& p = places[size_t(g)];
            if (!p.ok) continue;
            const auto& b = p.blend;
            const double ism2 = 1.0 / (p.s_major * p.s_major), ism4 = ism2 * ism2;
            const std::array<int, 2> lv = {b.lo, b.hi};
            const std::array<double, 2> bw = {b.lo == b.hi ? 1.0 : 1.0 - b.weight,
                                              b.lo == b.hi ? 0.0 : b.weight};
            const std::array<double, 2> var = {p.var_lo, p.var_hi};
            row.weight[size_t(g)] =
                static_cast<float>(p.plan.fade / (std::sqrt(2.0 * std::numbers::pi) * p.s_major));
            for (int bin = 0; bin < B; ++bin) {
                const double sbar = sbar_of(p, bin);
                row.sbar[size_t(g) * B + bin] = static_cast<float>(sbar);
                float* t0 = row.tables.data() + (size_t(g) * B + size_t(bin)) * kProfiles * T;
                for (int k = -row.taps; k <= row.taps; ++k) {
                    const double v = m_v_sign * k * row.dxi;
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
                            mu = m_u_sign * signed_table_at(tab.mean, v, R) / p.s_major;
                            qv = signed_table_at(tab.var, v, R);
                            k4 = signed_table_at(tab.k4, v, R);
                        }
                        // The chord convolved with the remaining Gaussian: a Gaussian of mean
                        // mu and variance var + q / s_major^2 with the Edgeworth term of its
                        // kurtosis (the line form), expanded around N(u; sbar):
                        // N(u - mu; sbar + d) = sum (-mu)^i / i! (d/2)^j / j! N^(i + 2j)(u).
                        const double d = var[size_t(q)] + qv * ism2 - sbar;
                        const double w = bw[size_t(q)] * P;
                        a[0] += w;
                        a[1] += w * -mu;
                        a[2] += w * (0.5 * d + 0.5 * mu * mu);
                        a[3] += w * (-0.5 * mu * d - mu * mu * mu / 6.0);
                        a[4] += w * (0.125 * d * d + 0.25 * mu * mu * d + mu * mu * mu * mu / 24.0 +
                                     k4 * ism4 / 24.0);
                    }
                    for (int m = 0; m < kProfiles; ++m) {
                        t0[size_t(m) * T + size_t(k + row.taps)] = static_cast<float>(a[size_t(m)]);
                        peak[size_t(m)] = std::max(
                            peak[size_t(m)], std::abs(a[size_t(m)]) / std::pow(sbar, 0.5 * m));
                    }
                }
                // The linear deposit and the linear interpolation back to the pixels each blur
                // the profile by a tent of half-width dxi: together about (1 + dxi^2 / 6
                // d^2/dxi^2); the tables are sharpened by the inverse, T - dxi^2 / 6 T''.
                std::vector<float> sharp(static_cast<size_t>(T));
                for (int m = 0; m < kProfiles; ++m) {
                    float* t = t0 + size_t(m) * T;
                    for (int k = 0; k < T; ++k) {
                        const float left = k > 0 ? t[k - 1] : 0.0f,
                                    right = k + 1 < T ? t[k + 1] : 0.0f;
                        sharp[size_t(k)] = t[k] - (left - 2.0f * t[k] + right) / 6.0f;
                    }
                    std::copy(sharp.begin(), sharp.end(), t);
                }
            }
        }
        // Profiles whose term stays below 1e-4 of the main one's peak are left out.
        for (int m = 0; m < kProfiles; ++m)
            row.used[size_t(m)] = m == 0 || peak[size_t(m)] > 1e-4 * peak[0];
    });

    // The pixels the far field reaches: rows whose y' range meets the sub-rows' (plus the
    // along filter's reach), per pixel y', its scale kappa = dy'/dy and the along variance.
    double smax = c * c;
    for (const Row& row : m_rows)
        for (float sb : row.sbar) smax = std::max(smax, static_cast<double>(sb));
    const double y_lo = m_y0, y_hi = m_y0 + (rows - 1) * m_dy;
    // Which rows: y' at 33 columns of both pixel edges of each row (along a row rho is
    // smallest at one column and grows away from it, so the samples bound the row's range).
    std::vector<uint8_t> use(static_cast<size_t>(H), 0);
    tbb::parallel_for(0, H, [&](int j) {
        constexpr int kCols = 33;
        double lo = 1e300, hi = -1e300, kmax = 0.0;
        for (int k = 0; k < kCols; ++k) {
            const double px = W * (k + 0.5) / kCols;
            double x0, y0, x1, y1;
            const bool h0 = view.texture_point(px, j, x0, y0);
            const bool h1 = view.texture_point(px, j + 1.0, x1, y1);
            if (!h0 && !h1) continue;
            const double e0 = h0 ? y_of(std::sqrt(sq(x0 - cam.x) + sq(y0 - cam.y)))
                                 : y_of(std::sqrt(sq(x1 - cam.x) + sq(y1 - cam.y)));
            const double e1 = h1 ? y_of(std::sqrt(sq(x1 - cam.x) + sq(y1 - cam.y))) : e0;
            lo = std::min(lo, std::min(e0, e1)), hi = std::max(hi, std::max(e0, e1));
            kmax = std::max(kmax, std::abs(e1 - e0));
        }
        const double reach = kAlongReach * std::sqrt(smax) * std::max(kmax, 1.0) + 2.0 * m_dy;
        use[size_t(j)] = hi >= y_lo - reach && lo <= y_hi + reach;
    });
    m_j0 = H, m_j1 = 0;
    for (int j = 0; j < H; ++j)
        if (use[size_t(j)]) m_j0 = std::min(m_j0, j), m_j1 = j + 1;
    if (m_j0 >= m_j1) return;
    // rho at the pixel edges (row boundaries e = m_j0 .. m_j1) of those rows.
    std::vector<double>& rho_edge = m_rho_edge;
    rho_edge.assign(size_t(W) * (m_j1 - m_j0 + 1), -1.0);
    tbb::parallel_for(m_j0, m_j1 + 1, [&](int e) {
        std::vector<float> ex(static_cast<size_t>(W)), ey(static_cast<size_t>(W));
        std::vector<uint8_t> hit(static_cast<size_t>(W));
        view.texture_row(e, W, cam.x, cam.y, ex.data(), ey.data(), hit.data());
        for (int i = 0; i < W; ++i)
            rho_edge[size_t(e - m_j0) * W + i] =
                hit[size_t(i)] ? std::sqrt(sq(double(ex[size_t(i)])) + sq(double(ey[size_t(i)])))
                               : -1.0;
    });
    const size_t np = size_t(m_j1 - m_j0) * W;
    m_yp.assign(np, 0.0f), m_ik.assign(np, 0.0f);
    m_is.assign(np * m_bins, 0.0f), m_rs.assign(np * m_bins, 0.0f);
    tbb::parallel_for(m_j0, m_j1, [&](int j) {
        for (int i = 0; i < W; ++i) {
            const size_t p = size_t(j - m_j0) * W + i, q = size_t(j) * W + i;
            if (!coords.hit[q]) continue;
            const double rho = std::sqrt(sq(double(coords.x[q])) + sq(double(coords.y[q])));
            const double yc = y_of(rho);
            const double r0 = rho_edge[size_t(j - m_j0) * W + i];
            const double r1 = rho_edge[size_t(j + 1 - m_j0) * W + i];
            double kappa = r0 >= 0.0 && r1 >= 0.0 ? std::abs(y_of(r1) - y_of(r0))
                           : r0 >= 0.0            ? 2.0 * std::abs(yc - y_of(r0))
                           : r1 >= 0.0            ? 2.0 * std::abs(y_of(r1) - yc)
                                                  : 0.0;
            if (!(kappa > 0.0)) continue;
            const int r =
                std::clamp(static_cast<int>(std::lround((yc - m_y0) / m_dy)), 0, rows - 1);
            const int g = std::clamp(static_cast<int>((i + 0.5) / m_segment_px), 0, G - 1);
            // The linear deposit spreads an impulse over two sub-rows: variance dy^2 / 6 on
            // average (in y'), taken off the along Gaussian (one per direction bin).
            m_yp[p] = static_cast<float>(yc);
            m_ik[p] = static_cast<float>(1.0 / kappa);
            for (int b = 0; b < m_bins; ++b) {
                const double sbar = m_rows[size_t(r)].sbar[size_t(g) * m_bins + b];
                const double s = std::max(0.5 * sbar, sbar - m_dy * m_dy / (6.0 * kappa * kappa));
                m_is[size_t(b) * np + p] = static_cast<float>(1.0 / s);
                m_rs[size_t(b) * np + p] = static_cast<float>(1.0 / std::sqrt(s));
            }
        }
    });
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

size_t FarField::render(const Impulses& in, Frame& out, const PerspLoops& loops, bool parallel,
                        FarScratch& scratch) const {
    const int rows = static_cast<int>(m_rows.size());
    const int W = m_width;
    auto run = [&](int n, auto&& f) {
        if (parallel)
            tbb::parallel_for(0, n, f);
        else
            for (int i = 0; i < n; ++i) f(i);
    };
    // Node grids, one per direction bin (with `taps` zeros each side for the convolution).
    const int B = m_bins;
    std::vector<size_t> off(static_cast<size_t>(rows) + 1, 0);
    auto stride = [&](const Row& row) { return size_t(row.nodes + 2 * row.taps); };
    for (int r = 0; r < rows; ++r) {
        const Row& row = m_rows[size_t(r)];
        off[size_t(r) + 1] = off[size_t(r)] + (row.nodes ? size_t(B) * stride(row) : 0);
    }
    std::vector<float>& D = scratch.grids;
    D.assign(off.back(), 0.0f);
    auto grid = [&](int r, int bin) {
        const Row& row = m_rows[size_t(r)];
        return D.data() + off[size_t(r)] + size_t(bin) * stride(row) + size_t(row.taps);
    };

    // Deposit by bands of sub-rows: impulses sorted by band in canonical order (a counting sort
    // of their indices, 4 bytes each: a frame has millions, and memory new to the process costs
    // a page fault per 4 KiB), each band's items made (from the sub-row coordinates the
    // preparation computed) and summed by one task into its rows, the row after the band into a
    // halo added afterwards.
    const sim::Impulses& imp = *in.imp;
    const size_t n = imp.size();
    const int bands = this->bands();
    const int chunks = static_cast<int>((n + in.chunk - 1) / in.chunk);
    std::vector<size_t> start(size_t(chunks) * bands + 1, 0);
    std::vector<size_t> band_start(static_cast<size_t>(bands) + 1, 0);
    {
        size_t total = 0;
        for (int b = 0; b < bands; ++b) {
            band_start[size_t(b)] = total;
            for (int c = 0; c < chunks; ++c) {
                start[size_t(c) * bands + b] = total;
                total += in.counts[size_t(c) * bands + b];
            }
        }
        band_start[size_t(bands)] = total;
    }
    std::vector<uint32_t>& order = scratch.order;
    order.resize(band_start.back());
    run(chunks, [&](int c) {
        std::vector<size_t> fill(start.begin() + ptrdiff_t(c) * bands,
                                 start.begin() + ptrdiff_t(c + 1) * bands);
        const size_t i1 = std::min(n, (size_t(c) + 1) * in.chunk);
        for (size_t i = size_t(c) * in.chunk; i < i1; ++i)
            if (in.q[i] >= 0.0) order[fill[size_t(band_of(in.q[i]))]++] = static_cast<uint32_t>(i);
    });
    std::vector<std::vector<float>> halo(static_cast<size_t>(bands));
    std::vector<size_t> drawn_in(static_cast<size_t>(bands), 0);
    // Which (sub-row, bin) grids received something (each set by the band that owns the row,
    // or by the band before through its halo: both bands set it, from disjoint tasks' items).
    std::vector<uint8_t> filled(size_t(rows) * B, 0), halo_filled(size_t(bands) * B, 0);
    run(bands, [&](int b) {
        const int last = std::min(rows, (b + 1) * kBand);  // first row after the band
        const size_t hn = last < rows ? size_t(m_rows[size_t(last)].nodes) : 0;
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
            for (int j = 0; j < kItemBlock; ++j)
                sx[size_t(j)] = column(rx[size_t(j)], ry[size_t(j)]);
            for (int j = 0; j < m; ++j) {
                const size_t i = order[kb + size_t(j)];
                FarItem it;
                if (!item(rx[size_t(j)], ry[size_t(j)], in.q[i], sx[size_t(j)], imp.weight[i],
                          in.orient + static_cast<double>(imp.theta[i]), it))
                    continue;
                ++drawn;
                for (int e = 0; e < 2; ++e) {
                    const int r = it.row + e, nd = it.node[e];
                    if (nd < 0) continue;
                    for (int q = 0; q < (B > 1 ? 2 : 1); ++q) {
                        const int bin = (it.bin + q) % B;
                        float* d =
                            r == last ? halo[size_t(b)].data() + size_t(bin) * hn : grid(r, bin);
                        d[nd] += it.wb[q] * it.w[e][0];
                        d[nd + 1] += it.wb[q] * it.w[e][1];
                        (r == last ? halo_filled[size_t(b) * B + bin]
                                   : filled[size_t(r) * B + bin]) = 1;
                    }
                }
            }
        }
        drawn_in[size_t(b)] = drawn;
    });
    run(bands, [&](int b) {
        const int r = (b + 1) * kBand;
        if (r >= rows || halo[size_t(b)].empty()) return;
        const size_t hn = size_t(m_rows[size_t(r)].nodes);
        for (int bin = 0; bin < B; ++bin) {
            if (!halo_filled[size_t(b) * B + bin]) continue;
            filled[size_t(r) * B + bin] = 1;
            float* d = grid(r, bin);
            const float* h = halo[size_t(b)].data() + size_t(bin) * hn;
            for (size_t k = 0; k < hn; ++k) d[k] += h[k];
        }
    });

    // Across and along, by bands of output rows (one task each, its rows written by it alone):
    // for each sub-row within reach of the band and each direction bin, the sub-row is
    // convolved across with its segments' profiles and sampled at the pixel centres (linear
    // between nodes), then added to every pixel of the band it reaches through the along filter
    // of that bin. Sub-rows are visited in order, so every pixel sums them in the same order.
    // Each pixel sums the sub-rows within kAlongReach sd of its own y' only. The reach is kept
    // per piece of kAlongPiece columns: sub-rows follow circles, which bend across the image, so
    // the reach of a whole row is several times that of any of its pixels.
    const size_t np = m_yp.size();
    const int nrow = m_j1 - m_j0;
    const int pieces = (W + kAlongPiece - 1) / kAlongPiece;
    std::vector<int> reach0(size_t(nrow) * pieces, rows), reach1(size_t(nrow) * pieces, 0);
    for (int jj = 0; jj < nrow; ++jj) {
        for (int c = 0; c < pieces; ++c) {
            double lo = 1e300, hi = -1e300;
            for (int i = c * kAlongPiece; i < std::min(W, (c + 1) * kAlongPiece); ++i) {
                const size_t p = size_t(jj) * W + i;
                if (m_ik[p] == 0.0f) continue;
                double smax = 0.0;
                for (int b = 0; b < B; ++b)
                    smax = std::max(smax, 1.0 / double(m_is[size_t(b) * np + p]));
                const double reach = kAlongReach * std::sqrt(smax) / m_ik[p];
                lo = std::min(lo, m_yp[p] - reach), hi = std::max(hi, m_yp[p] + reach);
            }
            if (!(lo <= hi)) continue;
            const size_t e = size_t(jj) * pieces + c;
            reach0[e] = std::max(0, static_cast<int>(std::floor((lo - m_y0) / m_dy)));
            reach1[e] = std::min(rows, static_cast<int>(std::ceil((hi - m_y0) / m_dy)) + 1);
        }
    }
    constexpr int kRowsPerTask = 32;
    const int tasks = (nrow + kRowsPerTask - 1) / kRowsPerTask;
    run(tasks, [&](int task) {
        const int ja = task * kRowsPerTask, jb = std::min(nrow, ja + kRowsPerTask);
        int ra = rows, rb = 0;
        for (size_t e = size_t(ja) * pieces; e < size_t(jb) * pieces; ++e)
            ra = std::min(ra, reach0[e]), rb = std::max(rb, reach1[e]);
        std::vector<float> acc(size_t(jb - ja) * W, 0.0f), x;
        std::vector<float> zeros(static_cast<size_t>(W), 0.0f), frac(static_cast<size_t>(W));
        std::vector<int> node(static_cast<size_t>(W));
        std::array<std::vector<float>, kProfiles> px;
        for (int r = ra; r < rb; ++r) {
            const Row& row = m_rows[size_t(r)];
            if (!row.nodes) continue;
            const int T = 2 * row.taps + 1;
            x.resize(size_t(row.nodes));
            const float yr = static_cast<float>(row.y);
            for (int i = 0; i < W; ++i) {
                const double p = (xi_at(row, i + 0.5) - row.xi0) / row.dxi;
                node[size_t(i)] = static_cast<int>(p);
                frac[size_t(i)] = static_cast<float>(p - node[size_t(i)]);
            }
            for (int bin = 0; bin < B; ++bin) {
                if (!filled[size_t(r) * B + bin]) continue;
                const float* d = grid(r, bin);
                int terms = 0;
                std::array<const float*, kProfiles> xp{};
                for (int m = 0; m < kProfiles; ++m) {
                    xp[size_t(m)] = zeros.data();
                    if (!row.used[size_t(m)]) continue;
                    std::fill(x.begin(), x.end(), 0.0f);
                    for (int g = 0; g < m_segments; ++g) {
                        const int n0 = row.segment_node[size_t(g)];
                        const int n1 = row.segment_node[size_t(g) + 1];
                        if (n0 >= n1) continue;
                        const float* t =
                            row.tables.data() +
                            ((size_t(g) * B + size_t(bin)) * kProfiles + size_t(m)) * T;
                        loops.far_across(d, t + row.taps, row.taps, n0, n1, x.data());  // writes
                    }
                    auto& v = px[size_t(m)];
                    v.resize(size_t(W));
                    for (int i = 0; i < W; ++i) {
                        const size_t nd = size_t(node[size_t(i)]);
                        v[size_t(i)] = x[nd] + frac[size_t(i)] * (x[nd + 1] - x[nd]);
                    }
                    xp[size_t(m)] = v.data();
                    if (m) terms |= m == 1 || m == 3 ? 2 : 1;
                }
                for (int jj = ja; jj < jb; ++jj) {
                    // Runs of consecutive pieces that the sub-row reaches.
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
                        for (int m = 0; m < kProfiles; ++m)
                            xq[size_t(m)] = xp[size_t(m)] + i0;
                        loops.far_along(m_yp.data() + p, m_ik.data() + p, m_is.data() + pb,
                                        m_rs.data() + pb, i1 - i0, yr, xq.data(), terms,
                                        acc.data() + size_t(jj - ja) * W + i0);
                    }
                }
            }
        }
        for (int jj = ja; jj < jb; ++jj) {
            float* dst = out.data.data() + size_t(m_j0 + jj) * W;
            const float* src = acc.data() + size_t(jj - ja) * W;
            for (int i = 0; i < W; ++i) dst[i] += src[i];
        }
    });
    size_t drawn = 0;
    for (size_t d : drawn_in) drawn += d;
    return drawn;
}

}  // namespace impulse::render::detail
