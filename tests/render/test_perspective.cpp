// SPDX-License-Identifier: Apache-2.0
// Perspective and zoom anti-aliasing (issue "Non-stationary and perspective", item 5):
//  (a) a perspective frame against a supersampled reference, per depth band, with and without
//      depth selection;
//  (b) a zoom-out of a still texture: frame-to-frame change against the reference's, with
//      blending, nearest level and no filtering;
//  (d) spectral energy above the pixel Nyquist rate per depth band;
// plus the camera geometry, the pyramid's statistics, determinism and error paths.

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"
#include "numeric/errors.h"

namespace {

using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelPyramid;
using impulse::kernels::KernelType;
using impulse::render::AntiAlias;
using impulse::render::Frame;
using impulse::render::PerspectiveCamera;
using impulse::render::PerspectiveView;
namespace numeric = impulse::numeric;
namespace sim = impulse::sim;
namespace render = impulse::render;

constexpr double kPi = std::numbers::pi;

/// The scene of tests (a) and (d): cosine kernels of radius 16, 16 impulses per kernel area, a
/// ground camera 16 units up, pitch 20 degrees, fov 60: the near edge at ~0.15 texture units
/// per pixel, the horizon 35.5 rows from the top.
struct PerspectiveCase {
    Kernel kernel{[] {
        KernelParams p;
        p.type = KernelType::Cosine;
        p.radius = 16.0;
        return p;
    }()};
    KernelPyramid pyramid{kernel, [] {
                              impulse::kernels::PyramidParams pp;
                              pp.min_sd_fraction = 2.5e-3;
                              return pp;
                          }()};
    sim::ProcessConfig process = [this] {
        sim::ProcessConfig c;
        c.seed = 99;
        c.cell_size = 16.0;
        c.intensity = 16.0 / kernel.support_area();
        return c;
    }();
    PerspectiveCamera camera = [] {
        PerspectiveCamera c;
        c.width = 256, c.height = 192;
        c.altitude = 16.0, c.pitch_deg = 20.0, c.fov_deg = 60.0;
        return c;
    }();
    /// Standard deviation of the unfiltered texture (Campbell: lambda E[a^2] int h^2).
    double sd0() const { return std::sqrt(process.intensity * kernel.integral_sq()); }
};

/// Whether two frames hold the same bits.
bool same_bits(const Frame& a, const Frame& b) {
    return a.data.size() == b.data.size() &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

Frame render_frame(const KernelPyramid& pyr, sim::LayerSimulator& s, const PerspectiveCamera& cam,
                   const AntiAlias& aa, render::PerspectiveStats* stats = nullptr,
                   const render::EvalOptions& eo = {},
                   render::PerspectiveWorkspace* workspace = nullptr) {
    const PerspectiveView v(cam);
    const numeric::Region box = render::perspective_region(pyr, v, aa);
    sim::Impulses imp;
    s.impulses_at(0, box, imp);
    const auto pc = render::pixel_coords(v);
    Frame f;
    f.resize(cam.width, cam.height);
    render::accumulate_perspective(pyr, imp, v, pc, f, aa, eo, stats, workspace);
    return f;
}

/// Distance along the centre column beyond which the supersampled reference is taken as the
/// mean: where the remaining standard deviation of the texture filtered by the pixel footprint
/// (anisotropic: sqrt(sd(sigma_major) sd(sigma_minor))) falls below `fraction`.
double reference_distance(const KernelPyramid& pyr, const PerspectiveView& view, double fraction) {
    const auto& c = view.camera();
    const double h = c.heading_deg * kPi / 180.0;
    for (double d = 4.0 * c.altitude; d < 1e8; d *= 1.01) {
        const auto f = view.footprint(c.x + d * std::sin(h), c.y - d * std::cos(h));
        if (std::sqrt(pyr.sd_fraction(0.5 * f.s_major) * pyr.sd_fraction(0.5 * f.s_minor)) <
            fraction)
            return d;
    }
    return 1e8;
}

/// Unfiltered texture at arbitrary points, in double: impulses binned into cells of the kernel
/// radius (a reference independent of the renderer's loops).
class PointField {
public:
    PointField(const Kernel& k, const sim::Impulses& imp, double max_distance, double cx, double cy)
        : m_k(k), m_imp(imp) {
        const double R = k.radius();
        m_c = R;
        m_inv_r2 = 1.0 / (R * R);
        double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
        for (size_t i = 0; i < imp.size(); ++i) {
            x0 = std::min(x0, imp.x[i]), x1 = std::max(x1, imp.x[i]);
            y0 = std::min(y0, imp.y[i]), y1 = std::max(y1, imp.y[i]);
        }
        m_x0 = x0 - 1.0, m_y0 = y0 - 1.0;
        m_w = static_cast<int>((x1 - m_x0) / m_c) + 2,
        m_h = static_cast<int>((y1 - m_y0) / m_c) + 2;
        m_start.assign(size_t(m_w) * m_h + 1, 0);
        std::vector<int> cell(imp.size(), -1);
        for (size_t i = 0; i < imp.size(); ++i) {
            if (std::hypot(imp.x[i] - cx, imp.y[i] - cy) > max_distance) continue;
            cell[i] = static_cast<int>((imp.y[i] - m_y0) / m_c) * m_w +
                      static_cast<int>((imp.x[i] - m_x0) / m_c);
            ++m_start[size_t(cell[i]) + 1];
        }
        for (size_t i = 1; i < m_start.size(); ++i) m_start[i] += m_start[i - 1];
        m_index.resize(m_start.back());
        std::vector<uint32_t> fill(m_start.begin(), m_start.end() - 1);
        for (size_t i = 0; i < imp.size(); ++i)
            if (cell[i] >= 0) m_index[fill[size_t(cell[i])]++] = static_cast<uint32_t>(i);
    }
    double operator()(double x, double y) const {
        const int gx = static_cast<int>(std::floor((x - m_x0) / m_c));
        const int gy = static_cast<int>(std::floor((y - m_y0) / m_c));
        double s = 0.0;
        for (int b = std::max(0, gy - 1); b <= std::min(m_h - 1, gy + 1); ++b)
            for (int a = std::max(0, gx - 1); a <= std::min(m_w - 1, gx + 1); ++a) {
                const size_t c = size_t(b) * m_w + a;
                for (uint32_t k = m_start[c]; k < m_start[c + 1]; ++k) {
                    const uint32_t i = m_index[k];
                    const double dx = x - m_imp.x[i], dy = y - m_imp.y[i];
                    const double q = (dx * dx + dy * dy) * m_inv_r2;  // radial kernels only
                    if (q < 1.0) s += m_imp.weight[i] * m_k.envelope(q);
                }
            }
        return s;
    }

private:
    const Kernel& m_k;
    const sim::Impulses& m_imp;
    double m_c, m_inv_r2, m_x0, m_y0;
    int m_w, m_h;
    std::vector<uint32_t> m_start, m_index;
};

/// The supersampled reference of the unfiltered texture (mean 0) for the whole frame. Rows whose
/// footprint is at most 4 units deep per pixel: 16 x 16 samples per pixel, rendered in strips by
/// the perspective evaluator with filtering off. Rows nearer the horizon: 4 x ny samples with ny
/// (a power of two) raised until the samples are R/4 apart along the depth (up to 1024),
/// evaluated point by point in double (otherwise the reference itself aliases there). The pixel
/// filter: a Gaussian of sd 0.5 px truncated at 3 sd (radius 1.5 px), weights normalised. Beyond
/// `max_distance` the reference is the mean (its remaining filtered sd is below 1 % of the
/// texture's there).
std::vector<float> reference_frame(const PerspectiveCase& pc, sim::LayerSimulator& s,
                                   double max_distance) {
    const auto& cam = pc.camera;
    const int W = cam.width, H = cam.height;
    const PerspectiveView view(cam);
    const double R = pc.kernel.radius();
    AntiAlias raw;
    raw.enabled = false, raw.fade = false, raw.max_distance = max_distance;
    std::vector<float> ref(size_t(W) * H, 0.0f);
    // vertical samples per pixel needed by row j: the deepest footprint within its filter
    const double hz = view.horizon_row();
    auto rows_needed = [&](int j) {
        double worst = 0.0;
        for (double py : {j - 1.0, j + 0.5}) {
            double x, y;
            const double pyc = std::max(py, hz + 1e-3);
            if (!view.texture_point(0.5 * W, pyc, x, y)) continue;
            if (std::hypot(x - cam.x, y - cam.y) > max_distance) {
                // only the part of the filter nearer than max_distance matters
                for (double t = pyc; t < j + 2.0; t += 0.01)
                    if (view.texture_point(0.5 * W, t, x, y) &&
                        std::hypot(x - cam.x, y - cam.y) <= max_distance)
                        break;
            }
            worst = std::max(worst, view.footprint(x, y).s_major);
        }
        return std::clamp(static_cast<int>(std::ceil(4.0 * worst / R)), 16, 1024);
    };
    int first_near = H;
    for (int j = H - 1; j >= 0 && j + 2 > hz; --j) {
        if (rows_needed(j) > 16) break;
        first_near = j;
    }
    // Near rows: strips through the evaluator.
    const int n = 16, m = 2, S = 8;
    for (int r0 = first_near; r0 < H; r0 += S) {
        const int rows = std::min(S, H - r0);
        const PerspectiveCamera wc = cam.window(-m, r0 - m, W + 2 * m, rows + 2 * m, n);
        const PerspectiveView wv(wc);
        const numeric::Region box = render::perspective_region(pc.pyramid, wv, raw);
        sim::Impulses imp;
        s.impulses_at(0, box, imp);
        const auto coords = render::pixel_coords(wv);
        Frame f;
        f.resize(wc.width, wc.height);
        render::accumulate_perspective(pc.pyramid, imp, wv, coords, f, raw);
        for (int j = r0; j < r0 + rows; ++j)
            for (int i = 0; i < W; ++i) {
                const double cx = (i + m + 0.5) * n, cy = (j - r0 + m + 0.5) * n;
                double sum = 0.0, ws = 0.0;
                for (int b = static_cast<int>(cy - 1.5 * n); b <= static_cast<int>(cy + 1.5 * n);
                     ++b)
                    for (int a = static_cast<int>(cx - 1.5 * n);
                         a <= static_cast<int>(cx + 1.5 * n); ++a) {
                        const double dx = (a + 0.5 - cx) / n, dy = (b + 0.5 - cy) / n;
                        const double d2 = dx * dx + dy * dy;
                        if (d2 > 2.25 || a < 0 || b < 0 || a >= wc.width || b >= wc.height)
                            continue;
                        const double w = std::exp(-2.0 * d2);
                        sum += w * f.at(a, b);
                        ws += w;
                    }
                ref[size_t(j) * W + i] = static_cast<float>(sum / ws);
            }
    }
    // Far rows: point sampling on a grid shared by the rows of a group (rows needing the same
    // power-of-two ny), 4 samples per pixel across.
    const int far0 = std::max(0, static_cast<int>(std::floor(hz)) - 1);
    if (far0 < first_near) {
        const PerspectiveCamera wc =
            cam.window(-m, far0 - m, W + 2 * m, first_near - far0 + 2 * m, 1);
        const PerspectiveView wv(wc);
        const numeric::Region box = render::perspective_region(pc.pyramid, wv, raw);
        sim::Impulses imp;
        s.impulses_at(0, box, imp);
        const PointField field(pc.kernel, imp, max_distance, cam.x, cam.y);
        constexpr int nx = 4;
        auto pow2 = [](int v) {
            int p = 16;
            while (p < v) p *= 2;
            return p;
        };
        for (int g0 = far0; g0 < first_near;) {
            const int ny = pow2(rows_needed(g0));
            int g1 = g0 + 1;
            while (g1 < first_near && pow2(rows_needed(g1)) == ny) ++g1;
            // samples at x = -1 + (a + 0.5) / nx, y = g0 - 1 + (b + 0.5) / ny
            const int sw = (W + 2) * nx, sh = (g1 - g0 + 3) * ny;
            std::vector<float> smp(size_t(sw) * sh);
            tbb::parallel_for(0, sh, [&](int b) {
                const double py = g0 - 1.0 + (b + 0.5) / ny;
                for (int a = 0; a < sw; ++a) {
                    const double px = -1.0 + (a + 0.5) / nx;
                    double x, y, v = 0.0;
                    if (view.texture_point(px, py, x, y) &&
                        std::hypot(x - cam.x, y - cam.y) <= max_distance)
                        v = field(x, y);
                    smp[size_t(b) * sw + a] = static_cast<float>(v);
                }
            });
            tbb::parallel_for(g0 * W, g1 * W, [&](int p) {
                const int j = p / W, i = p % W;
                double sum = 0.0, ws = 0.0;
                for (int b = (j - g0) * ny; b < (j - g0 + 3) * ny; ++b) {
                    const double dy = (g0 - 1.0 + (b + 0.5) / ny) - (j + 0.5);
                    for (int a = i * nx; a < (i + 3) * nx; ++a) {
                        const double dx = (-1.0 + (a + 0.5) / nx) - (i + 0.5);
                        const double d2 = dx * dx + dy * dy;
                        if (d2 > 2.25) continue;
                        const double w = std::exp(-2.0 * d2);  // sd 0.5 px
                        sum += w * smp[size_t(b) * sw + a];
                        ws += w;
                    }
                }
                ref[size_t(p)] = static_cast<float>(sum / ws);
            });
            g0 = g1;
        }
    }
    return ref;
}

/// Depth bands: `count` bands of equal rows from the near edge up to the first row whose centre
/// lies below the horizon. Returns [row0, row1) per band, nearest first.
std::vector<std::pair<int, int>> depth_bands(const PerspectiveView& view, int count) {
    const int H = view.camera().height;
    const int top = std::max(0, static_cast<int>(std::ceil(view.horizon_row() - 0.5)));
    std::vector<std::pair<int, int>> b;
    for (int k = 0; k < count; ++k)
        b.emplace_back(H - (k + 1) * (H - top) / count, H - k * (H - top) / count);
    return b;
}

double band_rmse(const std::vector<float>& a, const std::vector<float>& b, int W,
                 std::pair<int, int> rows) {
    double e = 0.0;
    for (int j = rows.first; j < rows.second; ++j)
        for (int i = 0; i < W; ++i) {
            const double d = double(a[size_t(j) * W + i]) - b[size_t(j) * W + i];
            e += d * d;
        }
    return std::sqrt(e / (double(W) * (rows.second - rows.first)));
}

double band_sd(const std::vector<float>& a, int W, std::pair<int, int> rows) {
    double s = 0.0, s2 = 0.0;
    const double n = double(W) * (rows.second - rows.first);
    for (int j = rows.first; j < rows.second; ++j)
        for (int i = 0; i < W; ++i) {
            const double v = a[size_t(j) * W + i];
            s += v, s2 += v * v;
        }
    return std::sqrt(std::max(0.0, s2 / n - (s / n) * (s / n)));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Geometry

TEST_CASE("perspective camera: rays and projection are inverse and footprints match the Jacobian",
          "[render][perspective]") {
    for (auto plane : {render::Plane::Ground, render::Plane::Sky}) {
        PerspectiveCamera c;
        c.width = 320, c.height = 200, c.x = 13.0, c.y = -7.0, c.altitude = 50.0;
        c.pitch_deg = 25.0, c.heading_deg = 37.0, c.fov_deg = 55.0, c.plane = plane;
        const PerspectiveView v(c);
        for (double py : {0.5, 60.3, 150.0, 199.5})
            for (double px : {0.5, 100.2, 319.5}) {
                double x, y;
                if (!v.texture_point(px, py, x, y)) continue;
                double qx, qy;
                REQUIRE(v.image_point(x, y, qx, qy));
                CHECK(qx == Approx(px).margin(1e-6));
                CHECK(qy == Approx(py).margin(1e-6));
                // footprint: moving s_major along e moves one pixel along (ix, iy)
                const auto f = v.footprint(x, y);
                const double h = 1e-4 * f.s_major;
                double ax, ay;
                REQUIRE(v.image_point(x + h * f.ex, y + h * f.ey, ax, ay));
                CHECK((ax - qx) / h * f.s_major == Approx(f.ix).margin(1e-4));
                CHECK((ay - qy) / h * f.s_major == Approx(f.iy).margin(1e-4));
                CHECK(f.s_major >= f.s_minor);
            }
        // The horizon: rows on the plane's side of it hit, the others miss.
        const double hz = v.horizon_row();
        double x, y;
        const bool below_hits = plane == render::Plane::Ground;
        CHECK(v.texture_point(160.0, hz + 0.5, x, y) == below_hits);
        CHECK(v.texture_point(160.0, hz - 0.5, x, y) == !below_hits);
    }
    // Straight down, heading 0: the orthographic orientation (+x right, -y up).
    PerspectiveCamera c;
    c.width = 100, c.height = 100, c.altitude = 100.0, c.pitch_deg = 90.0, c.fov_deg = 40.0;
    const PerspectiveView v(c);
    double xl, yl, xr, yr, xt, yt;
    REQUIRE(v.texture_point(10.5, 50.0, xl, yl));
    REQUIRE(v.texture_point(90.5, 50.0, xr, yr));
    REQUIRE(v.texture_point(50.0, 10.5, xt, yt));
    CHECK(xr > xl);
    CHECK(yt < 0.0);
}

TEST_CASE("perspective camera: invalid cameras are refused with the field named",
          "[render][perspective]") {
    using Catch::Matchers::Contains;
    PerspectiveCamera c;
    c.width = 64, c.height = 48;
    auto err = [](PerspectiveCamera cam) {
        try {
            PerspectiveView v(cam);
        } catch (const impulse::ValueError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    PerspectiveCamera a = c;
    a.altitude = 0.0;
    CHECK_THAT(err(a), Contains("height = 0") && Contains("> 0"));
    a = c, a.fov_deg = 180.0;
    CHECK_THAT(err(a), Contains("fov = 180") && Contains("(0, 180)"));
    a = c, a.pitch_deg = -40.0;  // looking up at a ground plane
    CHECK_THAT(err(a), Contains("sees no part of the ground plane"));
    a = c, a.pitch_deg = -40.0, a.plane = render::Plane::Sky;  // looking down at a sky plane
    CHECK_THAT(err(a), Contains("sees no part of the sky plane"));
    a = c, a.pitch_deg = 40.0, a.plane = render::Plane::Sky;
    CHECK(err(a).empty());
}

TEST_CASE("pyramid: levels low-pass the kernel by the stated Gaussian",
          "[render][perspective][kernels]") {
    // Parseval: int h_l^2 = int |H|^2 exp(-4 pi^2 sigma_l^2 k^2) d^2k, by Hankel quadrature of
    // the kernel's power spectrum; the level's own integral comes from its samples.
    PerspectiveCase pc;
    const KernelPyramid& pyr = pc.pyramid;
    REQUIRE(pyr.levels() >= 10);
    for (int l : {1, 4, 8, 12}) {
        const double s = pyr.sigma(l);
        const int n = 400;
        const double kmax = 0.6 / s;  // exp(-4 pi^2 s^2 k^2) < 1e-6 beyond
        double v = 0.0;
        for (int i = 0; i < n; ++i) {
            const double k = (i + 0.5) * kmax / n;
            v += pc.kernel.power_spectrum(k, 0.0) * std::exp(-4.0 * kPi * kPi * s * s * k * k) *
                 2.0 * kPi * k;
        }
        v *= kmax / n;
        INFO("level " << l << " sigma " << s);
        CHECK(pyr.variance(l) == Approx(v).epsilon(2e-3));
        CHECK(pyr.sigma(l) == Approx(pyr.sigma(0) * std::exp2(0.5 * l)));
        CHECK(pyr.radius(l) == Approx(16.0 + 4.0 * s));
    }
    // far levels: variance ~ (int h)^2 / (4 pi sigma^2)
    const int L = pyr.levels() - 1;
    const double s = pyr.sigma(L);
    CHECK(pyr.variance(L) ==
          Approx(pc.kernel.integral() * pc.kernel.integral() / (4.0 * kPi * s * s)).epsilon(0.02));
    // blending weights are linear in log sigma and continuous
    const auto b = pyr.select(pyr.sigma(5) * std::pow(2.0, 0.25 * 0.5));
    CHECK(b.lo == 5);
    CHECK(b.hi == 6);
    CHECK(b.weight == Approx(0.25));
}

TEST_CASE("pyramid: a large kernel and a small fraction stop at the largest kernel support",
          "[render][perspective][kernels]") {
    // clouds' kernel with camera.cutoff = 3e-4 asks for levels down to 7.5e-5 of its sd, which
    // lie beyond a support of 1e6 texture units: the pyramid stops below that (it had thrown
    // "radius = 1.00096e+06: must be at most 1e6"), and sd_fraction extrapolates past the top.
    KernelParams p;
    p.type = KernelType::Gaussian, p.radius = 72.0, p.sigma = 24.0;
    const Kernel k(p);
    impulse::kernels::PyramidParams pp;
    pp.min_sd_fraction = 7.5e-5;
    const KernelPyramid pyr(k, pp);
    const int L = pyr.levels() - 1;
    CHECK(pyr.radius(L) <= impulse::kernels::kMaxKernelRadius);
    CHECK(72.0 + 4.0 * pyr.sigma(L) * std::sqrt(2.0) > impulse::kernels::kMaxKernelRadius);
    CHECK(pyr.sd_fraction(pyr.sigma(L)) > pp.min_sd_fraction);
    // beyond the top: sigma_L / sigma times the top's fraction (the 1 / sigma decay of a kernel
    // with a non-zero integral)
    const double top = pyr.sd_fraction(pyr.sigma(L));
    CHECK(pyr.sd_fraction(4.0 * pyr.sigma(L)) == Approx(0.25 * top).epsilon(1e-9));
}

TEST_CASE("pyramid: axial tables hold the levels blurred along one axis",
          "[render][perspective][kernels]") {
    // Against the convolution done here by a fine trapezoid rule: h_l(sqrt(s^2 + v^2)) times a
    // Gaussian of the slice's variance in u - s, at table nodes; and the mass of each slice (the
    // quarter table, four times), which the blur keeps: int h_l, less the Gaussian's tails
    // beyond 3 sd (0.27 %) and the trapezoid rule's error on the 49 x 33 nodes.
    PerspectiveCase pc;
    const KernelPyramid& pyr = pc.pyramid;
    for (int l : {0, 4, 10}) {
        const auto& t = pyr.tables(l);
        const Kernel& k = pyr.level(l);
        const double R = pyr.radius(l);
        auto h = [&](double r) { return r < R ? k.envelope(r * r / (R * R)) : 0.0; };
        const int nu = t.axial_nu, nv = t.axial_nv, slices = int(t.axial_extent.size());
        REQUIRE(slices >= 2);
        for (int sl : {0, slices / 2, slices - 1}) {
            const double var = t.axial_var_max * sl / (slices - 1), E = t.axial_extent[size_t(sl)];
            const float* T = t.axial.data() + size_t(sl) * nu * nv;
            double mass = 0.0;
            for (int j = 0; j < nv; ++j)
                for (int i = 0; i < nu; ++i)
                    mass += (i == 0 ? 0.5 : 1.0) * (j == 0 ? 0.5 : 1.0) * T[size_t(j) * nu + i];
            mass *= 4.0 * (E / (nu - 1)) * (R / (nv - 1));
            INFO("level " << l << " slice " << sl);
            CHECK(mass == Approx(k.integral()).epsilon(0.01));
            for (int i : {0, nu / 4, nu / 2})
                for (int j : {0, nv / 3, 2 * nv / 3}) {
                    const double u = E * i / (nu - 1), v = R * j / (nv - 1);
                    double ref = 0.0;
                    if (var == 0.0) {
                        ref = h(std::hypot(u, v));
                    } else {
                        const int n = 4096;
                        const double ds = 2.0 * R / n;
                        for (int m = 0; m <= n; ++m) {
                            const double sm = -R + m * ds, d = u - sm;
                            ref += (m == 0 || m == n ? 0.5 : 1.0) * h(std::hypot(sm, v)) *
                                   std::exp(-0.5 * d * d / var);
                        }
                        ref *= ds / std::sqrt(2.0 * kPi * var);
                    }
                    CHECK(T[size_t(j) * nu + i] == Approx(ref).margin(1e-5 * h(0.0)));
                }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (a) accuracy per depth band

TEST_CASE(
    "perspective (a): depth bands match a supersampled reference and without depth "
    "selection the far bands alias",
    "[render][perspective][stats]") {
    PerspectiveCase pc;
    const PerspectiveView view(pc.camera);
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    const double sd0 = pc.sd0();
    const int W = pc.camera.width;

    AntiAlias aa;  // defaults: blend, anisotropic, filter 0.5 px, cut-off 1 %
    render::PerspectiveStats st;
    const Frame ours = render_frame(pc.pyramid, s, pc.camera, aa, &st);
    AntiAlias major = aa;
    major.anisotropic = false;  // the conservative major-axis rule
    const Frame iso = render_frame(pc.pyramid, s, pc.camera, major);
    AntiAlias level0 = aa;
    level0.enabled = false;  // no depth selection: the kernel itself everywhere
    const Frame raw = render_frame(pc.pyramid, s, pc.camera, level0);

    const double dref = reference_distance(pc.pyramid, view, 0.01);
    const std::vector<float> ref = reference_frame(pc, s, dref);

    const auto bands = depth_bands(view, 8);
    WARN("perspective (a): " << st.impulses << " impulses, " << st.culled
                             << " culled, forms single " << st.single << " axial " << st.axial
                             << " probes " << st.probes
                             << " line " << st.line << "; reference to " << dref
                             << " units; sd0 = " << sd0);
    std::ostringstream table;
    for (size_t b = 0; b < bands.size(); ++b) {
        const double e = band_rmse(ours.data, ref, W, bands[b]) / sd0;
        const double ei = band_rmse(iso.data, ref, W, bands[b]) / sd0;
        const double e0 = band_rmse(raw.data, ref, W, bands[b]) / sd0;
        const double rsd = band_sd(ref, W, bands[b]) / sd0;
        table << "band " << b << " rows " << bands[b].first << "-" << bands[b].second << ": ref sd "
              << rsd << ", RMSE/sd0 ours " << e << " major-axis " << ei << " level-0 " << e0
              << " (ours/band sd " << e / std::max(rsd, 1e-12) << ")\n";
        // Every band within 5 % of the texture's standard deviation.
        CHECK(e <= 0.05);
    }
    WARN(table.str());
    // Without depth selection the farthest quarter of the rows aliases.
    CHECK(band_rmse(raw.data, ref, W, bands[7]) / sd0 > 0.05);
    CHECK(band_rmse(raw.data, ref, W, {bands[7].first, bands[6].second}) / sd0 > 0.05);
}

// ---------------------------------------------------------------------------------------------
// (b) zoom-out: frame-to-frame change

namespace {

/// A still cosine texture (radius 8, 16 impulses per kernel area) zoomed out from 1 to 1/8
/// exponentially over `frames` frames (one key per frame), `size`^2 pixels, through the scene
/// loader and Renderer. `scale` multiplies the size and zoom (supersampled references).
std::string zoom_scene(int size, int frames, int scale, const char* antialias) {
    std::ostringstream s;
    s << "[output]\nsize = [" << size * scale << ", " << size * scale << "]\nframes = " << frames
      << "\nfps = 10\n[camera]\ncenter = [500.0, 500.0]\nantialias = \"" << antialias << "\"\n"
      << "zoom = { keys = [";
    for (int f = 0; f < frames; ++f)
        s << (f ? ", " : "") << "[" << f / 10.0 << ", "
          << scale * std::pow(8.0, -f / double(frames - 1)) << "]";
    s << "] }\n[[layer]]\nseed = 5\ndensity = 16.0\n[layer.kernel]\ntype = \"cosine\"\nradius = "
         "8.0\n";
    return s.str();
}

std::vector<Frame> render_zoom(const std::string& text, int frames) {
    impulse::scenes::Renderer r(impulse::scenes::load_scene_string(text, "zoom.toml"));
    std::vector<Frame> out(static_cast<size_t>(frames));
    for (int f = 0; f < frames; ++f) r.render(f, out[size_t(f)]);
    return out;
}

/// The reference frame: 16 x 16 samples per pixel (a render at 16x the size and zoom, no
/// filtering) through the Gaussian pixel filter (sd 0.5 px, truncated at 3 sd, normalised).
Frame downsample(const Frame& hi, int n) {
    Frame lo;
    lo.resize(hi.width / n, hi.height / n);
    std::vector<double> w;
    for (int j = 0; j < lo.height; ++j)
        for (int i = 0; i < lo.width; ++i) {
            const double cx = (i + 0.5) * n, cy = (j + 0.5) * n;
            double s = 0.0, ws = 0.0;
            for (int b = static_cast<int>(cy - 1.5 * n); b <= static_cast<int>(cy + 1.5 * n); ++b)
                for (int a = static_cast<int>(cx - 1.5 * n); a <= static_cast<int>(cx + 1.5 * n);
                     ++a) {
                    const double dx = (a + 0.5 - cx) / n, dy = (b + 0.5 - cy) / n;
                    const double d2 = dx * dx + dy * dy;
                    if (d2 > 2.25 || a < 0 || b < 0 || a >= hi.width || b >= hi.height) continue;
                    const double wt = std::exp(-2.0 * d2);
                    s += wt * hi.at(a, b);
                    ws += wt;
                }
            lo.data[size_t(j) * lo.width + i] = static_cast<float>(s / ws);
        }
    return lo;
}

double diff_variance(const Frame& a, const Frame& b) {
    double s = 0.0, s2 = 0.0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - b.data[i];
        s += d, s2 += d * d;
    }
    const double n = double(a.data.size());
    return s2 / n - (s / n) * (s / n);
}

double rmse(const Frame& a, const Frame& b) {
    double e = 0.0;
    for (size_t i = 0; i < a.data.size(); ++i) e += std::pow(double(a.data[i]) - b.data[i], 2);
    return std::sqrt(e / double(a.data.size()));
}

}  // namespace

TEST_CASE(
    "zoom (b): blended levels change frame to frame like the supersampled reference while "
    "nearest levels pop and unfiltered frames bubble",
    "[render][perspective][stats]") {
    const int size = 64, frames = 40, n = 16;
    const auto blend = render_zoom(zoom_scene(size, frames, 1, "blend"), frames);
    const auto nearest = render_zoom(zoom_scene(size, frames, 1, "nearest"), frames);
    const auto off = render_zoom(zoom_scene(size, frames, 1, "off"), frames);
    std::vector<Frame> ref;
    {
        impulse::scenes::Renderer r(
            impulse::scenes::load_scene_string(zoom_scene(size, frames, n, "off"), "ref.toml"));
        Frame hi;
        for (int f = 0; f < frames; ++f) {
            r.render(f, hi);
            ref.push_back(downsample(hi, n));
        }
    }
    // sd of the unfiltered texture (Campbell): lambda int h^2 with lambda = 16 / (pi 8^2)
    KernelParams kp;
    kp.type = KernelType::Cosine;
    kp.radius = 8.0;
    const Kernel k(kp);
    const double var0 = 16.0 / k.support_area() * k.integral_sq();

    // Accuracy of every blended frame (the contract of (a)): RMSE against the reference, and
    // relative to the reference's own sd.
    std::vector<double> rel(static_cast<size_t>(frames));
    double eps = 0.0;
    for (int f = 0; f < frames; ++f) {
        const double e = rmse(blend[size_t(f)], ref[size_t(f)]);
        CHECK(e / std::sqrt(var0) <= 0.05);
        eps = std::max(eps, e / std::sqrt(var0));
        const double m =
            std::accumulate(ref[size_t(f)].data.begin(), ref[size_t(f)].data.end(), 0.0) /
            double(ref[size_t(f)].data.size());
        double v = 0.0;
        for (float x : ref[size_t(f)].data) v += (x - m) * (x - m);
        rel[size_t(f)] = e / std::sqrt(v / double(ref[size_t(f)].data.size()));
    }
    // Tolerance. Write render_f = ref_f + e_f. Then D_render - D_ref = var(de) + 2 cov(dref, de),
    // so |D_render - D_ref| <= var(de) + 2 sqrt(D_ref var(de)) (Cauchy-Schwarz). The error e_f is
    // the difference between two filters of the same moving texture (the pyramid's Gaussian
    // levels, blended, against the 3-sd truncated Gaussian of the reference), so it acts on the
    // frame difference as on the frame: var(de) <= r^2 D_ref with r the frame's relative error
    // RMSE / sd(ref) (the larger of the two frames). Hence |D_render / D_ref - 1| <= 2 r + r^2.
    // Nearest levels and unfiltered frames are held to the same tolerance, set by the accuracy
    // the blended render achieves.
    int pops = 0, bubbles = 0, worst_frame = 0;
    double worst = 0.0;
    std::ostringstream log;
    for (int f = 0; f + 1 < frames; ++f) {
        const double r = std::max(rel[size_t(f)], rel[size_t(f) + 1]);
        const double tol = 2.0 * r + r * r;
        const double dref = diff_variance(ref[size_t(f) + 1], ref[size_t(f)]);
        const double xb = diff_variance(blend[size_t(f) + 1], blend[size_t(f)]) / dref - 1.0;
        const double xn = diff_variance(nearest[size_t(f) + 1], nearest[size_t(f)]) / dref - 1.0;
        const double xo = diff_variance(off[size_t(f) + 1], off[size_t(f)]) / dref - 1.0;
        log << "frames " << f << "-" << f + 1 << ": D_ref/var0 " << dref / var0 << ", tolerance "
            << tol << " | D/D_ref - 1: blend " << xb << " nearest " << xn << " off " << xo << "\n";
        CHECK(std::abs(xb) <= tol);
        if (std::abs(xb) / tol > worst) worst = std::abs(xb) / tol, worst_frame = f;
        pops += std::abs(xn) > tol;
        bubbles += std::abs(xo) > tol;
    }
    WARN("zoom (b): max blended RMSE "
         << eps << " sd0; worst |D/D_ref - 1| / tolerance " << worst << " at frame " << worst_frame
         << "; frame pairs out of tolerance: nearest " << pops << ", off " << bubbles << " of "
         << frames - 1 << "\n"
         << log.str());
    // Nearest levels pop at every half-octave switch (6 in 3 octaves); no filtering bubbles.
    CHECK(pops >= 4);
    CHECK(bubbles >= (frames - 1) / 2);
}

// ---------------------------------------------------------------------------------------------
// (d) energy above the pixel Nyquist rate per depth band

TEST_CASE("perspective (d): spectral energy above the pixel Nyquist rate per depth band",
          "[render][perspective][stats]") {
    // The rendered field before pixel sampling is measured directly: the same frame rendered
    // with 8 x 8 samples per pixel and every impulse filtered for its 1x footprint
    // (footprint_scale 8). Per depth band, the Hann-windowed periodogram of those samples gives
    // the fraction of the band's energy at |k_x| or |k_y| above 0.5 cycles per pixel, which the
    // 1x frame folds back (aliases). Without depth selection the same fraction is measured.
    PerspectiveCase pc;
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    const int n = 8;
    const PerspectiveCamera hi = pc.camera.window(0, 0, pc.camera.width, pc.camera.height, n);
    AntiAlias aa;
    aa.footprint_scale = n;
    const Frame ours = render_frame(pc.pyramid, s, hi, aa);
    AntiAlias raw = aa;
    raw.enabled = false;
    const Frame unf = render_frame(pc.pyramid, s, hi, raw);
    const auto bands = depth_bands(PerspectiveView(pc.camera), 8);
    auto above_nyquist = [&](const Frame& f, std::pair<int, int> rows) {
        impulse::analysis::Image img;
        img.width = f.width, img.height = (rows.second - rows.first) * n;
        img.data.assign(f.data.begin() + size_t(rows.first) * n * f.width,
                        f.data.begin() + size_t(rows.second) * n * f.width);
        const auto p = impulse::analysis::periodogram(img, impulse::analysis::Window::Hann);
        double all = 0.0, above = 0.0;
        for (int ky = 0; ky < p.height; ++ky)
            for (int kx = 0; kx < p.width; ++kx) {
                const double fx = std::abs(p.frequency(kx, p.width)) * n;
                const double fy = std::abs(p.frequency(ky, p.height)) * n;
                const double v = p.power[size_t(ky) * p.width + kx];
                all += v;
                if (fx > 0.5 || fy > 0.5) above += v;
            }
        return above / all;
    };
    // The ideal: the unfiltered samples through the pixel filter itself (sd 0.5 px = 4 samples,
    // truncated at 3 sd), i.e. the supersampled reference's field before pixel sampling. With
    // a Gaussian of sd 0.5 px, content that is white at the pixel scale keeps
    // 2 Phi(-0.5 / (1 / (2 sqrt(2) pi 0.5))) = 2.6 % of its energy above Nyquist per axis: the
    // 1 % bound can only hold where the texture itself is resolved, so the band nearest the
    // horizon is held to the ideal filter's own fraction (+10 %) instead, when that exceeds 1 %.
    auto ideal = [&](std::pair<int, int> rows) {
        const int r0 = rows.first * n, r1 = rows.second * n, W = unf.width;
        const int rad = static_cast<int>(1.5 * n);
        Frame g;
        g.resize(W, r1 - r0);
        tbb::parallel_for(r0, r1, [&](int y) {
            for (int x = 0; x < W; ++x) {
                double sum = 0.0, ws = 0.0;
                for (int b = y - rad; b <= y + rad; ++b)
                    for (int a = x - rad; a <= x + rad; ++a) {
                        const double dx = double(a - x) / n, dy = double(b - y) / n;
                        const double d2 = dx * dx + dy * dy;
                        if (d2 > 2.25 || a < 0 || b < 0 || a >= W || b >= unf.height) continue;
                        const double w = std::exp(-2.0 * d2);
                        sum += w * unf.at(a, b);
                        ws += w;
                    }
                g.data[size_t(y - r0) * W + x] = static_cast<float>(sum / ws);
            }
        });
        Frame full;
        full.resize(W, unf.height);
        std::copy(g.data.begin(), g.data.end(), full.data.begin() + size_t(r0) * W);
        return above_nyquist(full, rows);
    };
    std::ostringstream log;
    for (size_t b = 0; b < bands.size(); ++b) {
        const double fo = above_nyquist(ours, bands[b]), fu = above_nyquist(unf, bands[b]);
        const double fi = b >= 6 ? ideal(bands[b]) : 0.0;
        log << "band " << b << " rows " << bands[b].first << "-" << bands[b].second
            << ": energy above Nyquist " << fo << " (no depth selection " << fu;
        if (b >= 6) log << ", ideal pixel filter " << fi;
        log << ")\n";
        CHECK(fo <= std::max(0.01, 1.1 * fi));
    }
    WARN("perspective (d):\n" << log.str());
    CHECK(above_nyquist(unf, bands[7]) > 0.01);
}

// ---------------------------------------------------------------------------------------------
// Determinism, scenes, errors

TEST_CASE(
    "perspective frames are bit-identical across threads and tiles and SIMD paths and access order",
    "[render][perspective][determinism]") {
    const std::string text = R"(
[output]
size = [160, 96]
frames = 6
[camera]
type = "perspective"
height = 24.0
pitch = 12.0
fov = 50.0
heading = { keys = [[0.0, 10.0], [0.2, 14.0]] }
[[layer]]
seed = 3
density = 12.0
lifetime = 2.0
orientation = { type = "circular", center = [80.0, 0.0] }
[layer.kernel]
type = "gabor"
radius = 12.0
frequency = 0.1
aspect = 2.0
[[layer.flow]]
type = "uniform"
velocity = [20.0, -5.0]
[[layer]]
seed = 4
density = 16.0
gain = 0.5
[layer.kernel]
type = "cosine"
radius = 10.0
)";
    const auto scene = impulse::scenes::load_scene_string(text, "det.toml");
    auto bits = [](const Frame& f) { return std::vector<float>(f.data.begin(), f.data.end()); };
    // sequential frames with 2 threads, tiles of 64, AVX2 where available
    std::vector<std::vector<float>> seq;
    {
        impulse::scenes::Renderer r(scene);
        Frame f;
        for (int i = 0; i < 6; ++i) {
            r.render(i, f);
            seq.push_back(bits(f));
        }
        // the frame is not empty, and the sky above the horizon is the mean (0)
        double e = 0.0;
        for (float v : f.data) e += double(v) * v;
        CHECK(e > 0.0);
        CHECK(f.at(80, 0) == 0.0f);
    }
    // frame 5 alone, serial, tiles of 16, baseline loops, one thread
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    impulse::scenes::Renderer r(scene);
    Frame f;
    render::EvalOptions eo;
    eo.parallel = false, eo.tile_size = 16, eo.use_avx2 = false;
    r.render(5, f, eo);
    CHECK(std::memcmp(f.data.data(), seq[5].data(), seq[5].size() * sizeof(float)) == 0);
    r.render(2, f);
    CHECK(std::memcmp(f.data.data(), seq[2].data(), seq[2].size() * sizeof(float)) == 0);
}

TEST_CASE("camera scene keys: perspective cameras load and bad cameras get one line each",
          "[render][perspective][scenes][errors]") {
    using Catch::Matchers::Contains;
    using impulse::scenes::load_scene_string;
    auto scene = [](const std::string& camera) {
        return "[output]\nsize = [64, 48]\n[camera]\n" + camera +
               "\n[[layer]]\n[layer.kernel]\nradius = 8.0\n";
    };
    auto error_of = [&](const std::string& camera) {
        try {
            load_scene_string(scene(camera), "cam.toml");
        } catch (const impulse::SceneError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    const auto s = load_scene_string(
        scene("type = \"perspective\"\nplane = \"sky\"\nposition = [5.0, 6.0]\nheight = 30.0\n"
              "pitch = 35.0\nheading = { keys = [[0.0, 0.0], [1.0, 90.0]] }\nfov = 45.0\n"
              "antialias = \"nearest\"\nfilter = 0.6\ncutoff = 0.02\nanisotropic = false"),
        "cam.toml");
    const auto& c = s.camera;
    CHECK(c.type == impulse::scenes::CameraConfig::Type::Perspective);
    CHECK(c.plane == render::Plane::Sky);
    const auto pc = c.perspective(64, 48, 0.5);
    CHECK(pc.x == 5.0);
    CHECK(pc.heading_deg == Approx(45.0));
    CHECK(pc.altitude == 30.0);
    const auto aa = c.antialias_options();
    CHECK((aa.enabled && !aa.blend && !aa.anisotropic && aa.filter_px == 0.6 && aa.cutoff == 0.02));
    // auto anti-aliasing: perspective always; orthographic only when it zooms out
    CHECK(load_scene_string(scene("type = \"perspective\""), "c.toml").camera.antialiased());
    CHECK(!load_scene_string(scene("zoom = 2.0"), "c.toml").camera.antialiased());
    CHECK(load_scene_string(scene("zoom = { keys = [[0.0, 1.0], [1.0, 0.5]] }"), "c.toml")
              .camera.antialiased());

    CHECK(error_of("type = \"perspective\"\nfov = 190.0") ==
          "cam.toml:5:7: camera.fov = 190: expected a vertical field of view in (0, 180) degrees");
    CHECK(
        error_of("type = \"perspective\"\nheight = 0.0") ==
        "cam.toml:5:10: camera.height = 0: expected a height > 0 above the plane (texture units)");
    CHECK(
        error_of("type = \"perspective\"\npitch = -40.0") ==
        "cam.toml:5:9: camera.pitch = -40: the camera sees no part of the ground plane (pitch -40, "
        "fov 60): expected pitch > -fov/2 = -30 degrees below the horizon");
    CHECK_THAT(error_of("type = \"perspective\"\nplane = \"sky\"\npitch = { keys = [[0.0, 10.0], "
                        "[1.0, -50.0]] }"),
               Contains("camera.pitch") && Contains("sees no part of the sky plane at t = "));
    CHECK_THAT(error_of("type = \"perspective\"\nzoom = 2.0"),
               Contains("cam.toml:5:8: camera.zoom = 2: applies to orthographic cameras"));
    CHECK_THAT(error_of("pitch = 10.0"),
               Contains("camera.pitch = 10: applies to perspective cameras"));
    CHECK(error_of("type = \"fisheye\"") ==
          "cam.toml:4:8: camera.type = \"fisheye\": expected one of orthographic, perspective");
    CHECK_THAT(error_of("type = \"perspective\"\nplane = \"wall\""),
               Contains("camera.plane = \"wall\": expected one of ground, sky"));
    CHECK_THAT(error_of("antialias = \"fast\""),
               Contains("expected one of auto, blend, nearest, off"));
    CHECK_THAT(error_of("cutoff = 0.0"),
               Contains("camera.cutoff = 0: expected a fraction in [1e-6, 0.5]"));
}

TEST_CASE("perspective frames stay bounded however close the horizon", "[render][perspective]") {
    // The camera tilts up until the horizon is at the centre of the frame: the number of
    // impulses generated stays bounded by the cut-off distance, whatever the pitch.
    PerspectiveCase pc;
    size_t most = 0, least = SIZE_MAX;
    for (double pitch : {40.0, 20.0, 10.0, 5.0, 1.0, 0.0}) {
        PerspectiveCamera c = pc.camera;
        c.pitch_deg = pitch;
        const PerspectiveView v(c);
        const numeric::Region b = render::perspective_region(pc.pyramid, v, AntiAlias{});
        const double n = sim::expected_impulses(pc.process, b);
        most = std::max(most, size_t(n)), least = std::min(least, size_t(n));
        INFO("pitch " << pitch << ": " << n << " impulses expected");
        CHECK(n < 4e6);
    }
    // and the cut-off is what bounds it: a 0.1 % cut-off needs more
    PerspectiveCamera c = pc.camera;
    c.pitch_deg = 0.0;
    AntiAlias fine;
    fine.cutoff = 0.001;
    CHECK(sim::expected_impulses(
              pc.process, render::perspective_region(pc.pyramid, PerspectiveView(c), fine)) > most);
}

// ---------------------------------------------------------------------------------------------
// The far field (render/detail/persp_far.h)

TEST_CASE(
    "the far field draws most impulses of a grazing view for a fraction of the work and "
    "agrees with the line form",
    "[render][perspective]") {
    // The frame of test (a), where the supersampled reference holds every band within 5 % of the
    // texture's sd with the far field on (test (a) runs the defaults). Here: what the far field
    // is for. With it off, the line form draws the same impulses pixel by pixel.
    PerspectiveCase pc;
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    AntiAlias on;
    AntiAlias off = on;
    off.far_field = false;
    render::PerspectiveStats son, soff;
    const Frame a = render_frame(pc.pyramid, s, pc.camera, on, &son);
    const Frame b = render_frame(pc.pyramid, s, pc.camera, off, &soff);
    INFO("far field: " << son.far << " impulses, " << son.pixels << " pixel evaluations; line form "
                       << soff.line << " impulses, " << soff.pixels << " pixel evaluations");
    // Most of the kept impulses of a grazing view lie far away ...
    const size_t kept = son.impulses - son.culled;
    CHECK(son.far > 0.6 * kept);
    CHECK(soff.far == 0);
    // ... where the line form evaluates each over about a hundred pixels (130 here): the far
    // field deposits them instead (a few additions each). What remains is the near field's.
    CHECK(son.pixels < 0.5 * soff.pixels);
    // The two agree: over the rows the far field draws, the RMS difference is a small part of
    // the texture's sd (the far field's approximations, render/perspective.h, are each below
    // 1 %; against the supersampled reference both forms err by about 2 % there, test (a)).
    const int W = pc.camera.width;
    const auto bands = depth_bands(PerspectiveView(pc.camera), 8);
    const double d = band_rmse(a.data, b.data, W, bands[7]) / pc.sd0();
    INFO("RMS difference in the band nearest the horizon: " << d << " sd0");
    CHECK(d > 0.0);
    CHECK(d < 0.02);
}

TEST_CASE("far-field frames are bit-identical across threads, tiles and SIMD paths",
          "[render][perspective][determinism]") {
    PerspectiveCase pc;
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    render::PerspectiveStats st;
    const Frame a = render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, &st);
    REQUIRE(st.far > 10000);
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    render::EvalOptions eo;
    eo.parallel = false, eo.tile_size = 16, eo.use_avx2 = false;
    const Frame b = render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, nullptr, eo);
    CHECK(same_bits(a, b));
}

TEST_CASE("a perspective frame over its pixel budget is refused before any pixel is drawn",
          "[render][perspective][errors]") {
    PerspectiveCase pc;
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    render::PerspectiveStats st;
    const Frame a = render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, &st);
    REQUIRE(st.pixels > 1000);
    render::EvalOptions eo;
    eo.max_pixel_evaluations = double(st.pixels);  // exactly enough: drawn, same bits
    const Frame b = render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, nullptr, eo);
    CHECK(same_bits(a, b));
    eo.max_pixel_evaluations = double(st.pixels) - 1.0;
    try {
        render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, nullptr, eo);
        FAIL("no PixelBudgetError");
    } catch (const render::PixelBudgetError& e) {
        CHECK(e.needed == double(st.pixels));
        CHECK(e.budget == double(st.pixels) - 1.0);
    }
}

TEST_CASE("a perspective workspace reused across frames and views changes no bits",
          "[render][perspective][determinism]") {
    PerspectiveCase pc;
    sim::LayerSimulator s(pc.process, nullptr, {}, pc.kernel.radius());
    PerspectiveCamera other = pc.camera;
    other.width = 200, other.height = 240, other.pitch_deg = 35.0, other.heading_deg = 30.0;
    AntiAlias coarse;
    coarse.cutoff = 0.05;
    render::PerspectiveStats st;
    const Frame a = render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, &st);
    REQUIRE(st.far > 10000);
    const Frame b = render_frame(pc.pyramid, s, other, coarse);
    render::PerspectiveWorkspace ws;
    render::PerspectiveStats sw;
    // a large frame, a smaller and different one (stale memory of the first must not leak in),
    // the first again
    CHECK(same_bits(render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, &sw, {}, &ws), a));
    CHECK(sw.far == st.far);
    CHECK(sw.culled == st.culled);
    CHECK(same_bits(render_frame(pc.pyramid, s, other, coarse, nullptr, {}, &ws), b));
    CHECK(same_bits(render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, nullptr, {}, &ws), a));
    // a workspace held by another call is not shared: the call uses memory of its own
    REQUIRE(ws.acquire() != nullptr);
    CHECK(same_bits(render_frame(pc.pyramid, s, other, coarse, nullptr, {}, &ws), b));
    ws.release();

    // The far field's set-up is kept while its inputs are unchanged: any one of them changed
    // alone must set it up again (the camera moved a little, the anti-aliasing options, another
    // pyramid seen by the same camera).
    CHECK(same_bits(render_frame(pc.pyramid, s, pc.camera, AntiAlias{}, nullptr, {}, &ws), a));
    PerspectiveCamera moved = pc.camera;
    moved.x += 3.0;
    const Frame c = render_frame(pc.pyramid, s, moved, AntiAlias{});
    CHECK(!same_bits(c, a));
    CHECK(same_bits(render_frame(pc.pyramid, s, moved, AntiAlias{}, nullptr, {}, &ws), c));
    const Frame d = render_frame(pc.pyramid, s, moved, coarse);
    CHECK(!same_bits(d, c));
    CHECK(same_bits(render_frame(pc.pyramid, s, moved, coarse, nullptr, {}, &ws), d));
    Kernel wider_kernel = [] {
        KernelParams p;
        p.type = KernelType::Cosine;
        p.radius = 24.0;
        return Kernel(p);
    }();
    const KernelPyramid wider(wider_kernel);
    const Frame e = render_frame(wider, s, moved, coarse);
    CHECK(!same_bits(e, d));
    CHECK(same_bits(render_frame(wider, s, moved, coarse, nullptr, {}, &ws), e));
    CHECK(same_bits(render_frame(pc.pyramid, s, moved, coarse, nullptr, {}, &ws), d));
}
