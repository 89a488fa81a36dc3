// SPDX-License-Identifier: Apache-2.0
// Statistics of rendered still frames against the closed forms of design.md §1 (Campbell's
// theorem): mean, variance, the radially averaged power spectrum, and the seamlessness of a
// periodic (torus) frame. Fixed seeds; every band is derived from the estimator's sampling
// error in the comment next to it (design.md §5), not tuned.
//
// Notation: lambda = impulses per px^2, A = N = pixels of the frame, h the kernel, H its
// Fourier transform, P = |H|^2, S(k) = lambda E[a^2] P(k) the spectral density of the field,
// C(tau) its covariance, S(0) = lambda E[a^2] (int h)^2.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace {

using impulse::analysis::Image;
using impulse::kernels::Kernel;
using impulse::render::Frame;

constexpr double kPi = std::numbers::pi;

struct Rendered {
    impulse::scenes::Scene scene;
    Frame frame;
};

Rendered render_still(const std::string& text) {
    Rendered r{impulse::scenes::load_scene_string(text, "stats.toml"), {}};
    impulse::scenes::Renderer renderer(r.scene);
    renderer.render(0, r.frame);
    return r;
}

Image to_image(const Frame& f) { return Image{f.width, f.height, f.data}; }

std::string cosine_scene(int size, double radius, bool periodic, const char* amplitude = "normal") {
    std::string s = "[output]\nsize = [" + std::to_string(size) + ", " + std::to_string(size) +
                    "]\n[[layer]]\nseed = 3\ndensity = 16.0\namplitude = \"" + amplitude + "\"\n";
    if (periodic) s += "period = [" + std::to_string(size) + ".0, " + std::to_string(size) + ".0]\n";
    s += "[layer.kernel]\ntype = \"cosine\"\nradius = " + std::to_string(radius) + "\n";
    return s;
}

const char* kGaborScene = R"(
[output]
size = [1024, 1024]
[[layer]]
seed = 4
density = 16.0
amplitude = "uniform"
orientation = "random"
period = [1024.0, 1024.0]
[layer.kernel]
type = "gabor"
radius = 16.0
frequency = 0.0625
aspect = 2.0
)";

/// Radial table of P(k) = Kernel::radial_power_spectrum on [0, kmax] with step dk, evaluated
/// with Catmull-Rom interpolation (exact for quadratics, so also near the double zeros of P).
class RadialTable {
public:
    RadialTable(const Kernel& k, double kmax, double dk) : m_dk(dk) {
        for (double q = -dk; q <= kmax + 3 * dk; q += dk) m_p.push_back(k.radial_power_spectrum(std::abs(q)));
    }
    double operator()(double q) const {
        const double t = q / m_dk + 1.0;  // table index of q (entry 0 is q = -dk)
        const size_t i = static_cast<size_t>(t);
        const double u = t - i;
        const double p0 = m_p[i - 1], p1 = m_p[i], p2 = m_p[i + 1], p3 = m_p[i + 2];
        return p1 + 0.5 * u * (p2 - p0 + u * (2 * p0 - 5 * p1 + 4 * p2 - p3 + u * (3 * (p1 - p2) + p3 - p0)));
    }
    /// 2 pi int_0^kmax P(q)^2 q dq (trapezoid on the table).
    double integral_sq() const {
        double s = 0.0;
        for (size_t i = 1; i + 3 < m_p.size(); ++i) {
            const double q0 = (i - 1.0) * m_dk, q1 = q0 + m_dk;
            s += 0.5 * (m_p[i] * m_p[i] * q0 + m_p[i + 1] * m_p[i + 1] * q1) * m_dk;
        }
        return 2.0 * kPi * s;
    }

private:
    double m_dk;
    std::vector<double> m_p;
};

/// int (E_theta P_theta(k))^2 d^2k for a kernel with random orientation, independently of
/// Kernel::power_spectrum: sample h on a 512^2 grid of spacing 1/4 px (window 128 px), FFT
/// (analysis::periodogram: |DFT|^2 / n^2, DFT * spacing^2 = H), average over rings of width
/// dk = 1/128 cycles/px (the orientation average), then sum ring^2 over all bins * dk^2.
/// Ring quantisation and sampling make this good to ~1 %, plenty for a standard error.
double integral_mean_spectrum_sq(const Kernel& k) {
    const int n = 512;
    const double d = 0.25;
    Image img{n, n, std::vector<float>(size_t(n) * n)};
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            img.data[size_t(j) * n + i] = static_cast<float>(k.evaluate((i - n / 2) * d, (j - n / 2) * d));
    const auto pg = impulse::analysis::periodogram(img, impulse::analysis::Window::None);
    const auto ring = impulse::analysis::radial_average(pg);
    const double to_p = double(n) * n * d * d * d * d;  // periodogram value -> |H|^2
    const double dk = 1.0 / (n * d);
    double s = std::pow(k.integral(), 4) * dk * dk;  // the DC bin, P(0) = (int h)^2
    for (size_t b = 0; b < ring.power.size(); ++b)
        s += ring.count[b] * std::pow(ring.power[b] * to_p, 2) * dk * dk;
    return s;
}

/// Mean and variance of a still frame against Campbell's theorem. Derivation of the bands:
///  * sample mean: (1/N) sum_k a_k sum_p h(p - x_k) over the torus; its variance is
///    lambda E[a^2] sum_m |H(m)|^2 / N = S(0) / N (the aliases m != 0 are < 1e-10 of it).
///  * sample variance s^2 = (1/N) sum_p (f_p - fbar)^2, E[s^2] = sigma^2 - S(0)/N. With the
///    fourth cumulant of shot noise, k4(p,p,q,q) = lambda E[a^4] int h(p-y)^2 h(q-y)^2 dy,
///      Var(s^2) ~ (1/N^2) sum_p sum_q [2 C(p-q)^2 + k4(p,p,q,q)]
///               = (1/N) [2 int C^2 + lambda E[a^4] (int h^2)^2]
///    and by Parseval int C^2 = int S(k)^2 d^2k = (lambda E[a^2])^2 int (E_theta P)^2 d^2k.
/// Bands: 5 standard errors.
struct MomentCheck {
    double mean, sd_mean, var, expected_var, sd_var;
};

MomentCheck check_moments(const Rendered& r, double int_mean_p_sq) {
    const auto& layer = r.scene.layers.at(0);
    const Kernel k(layer.kernel);
    const double lambda = layer.process.intensity;
    const double ea2 = impulse::sim::amplitude_second_moment(layer.process.amplitude);
    const double ea4 = impulse::sim::amplitude_fourth_moment(layer.process.amplitude);
    const double n = static_cast<double>(r.frame.data.size());
    const auto theory = impulse::scenes::layer_theory(layer);
    const double s0 = lambda * ea2 * k.integral() * k.integral();
    const auto m = impulse::analysis::moments(r.frame.data);
    const double int_c2 = lambda * ea2 * lambda * ea2 * int_mean_p_sq;
    const double var_s2 = (2.0 * int_c2 + lambda * ea4 * std::pow(k.integral_sq(), 2)) / n;
    return {m.mean - theory.mean, std::sqrt(s0 / n), m.variance, theory.variance - s0 / n,
            std::sqrt(var_s2)};
}

}  // namespace

TEST_CASE("mean and variance of a still frame match Campbell's theorem", "[render][stats]") {
    SECTION("cosine r=16, density 16, normal amplitudes") {
        const auto r = render_still(cosine_scene(1024, 16.0, true));
        const Kernel k(r.scene.layers[0].kernel);
        // int P^2 d^2k from the library's spectrum, cross-checked by the FFT route (1 %).
        const RadialTable table(k, 0.3, 1.0 / 4096.0);
        const double ip2 = table.integral_sq();
        CHECK(std::abs(integral_mean_spectrum_sq(k) / ip2 - 1.0) < 0.02);
        const auto c = check_moments(r, ip2);
        CAPTURE(c.mean, c.sd_mean, c.var, c.expected_var, c.sd_var);
        CHECK(std::abs(c.mean) < 5.0 * c.sd_mean);
        CHECK(std::abs(c.var - c.expected_var) < 5.0 * c.sd_var);
        // Campbell's variance here is 16 (3/8 - 2/pi^2) = 2.758 whatever the radius.
        CHECK(c.expected_var == Approx(16.0 * (0.375 - 2.0 / (kPi * kPi))).epsilon(1e-3));
    }
    SECTION("gabor r=16 f=1/16 aspect 2, random orientation, uniform amplitudes") {
        const auto r = render_still(kGaborScene);
        const Kernel k(r.scene.layers[0].kernel);
        const auto c = check_moments(r, integral_mean_spectrum_sq(k));
        CAPTURE(c.mean, c.sd_mean, c.var, c.expected_var, c.sd_var);
        CHECK(std::abs(c.mean) < 5.0 * c.sd_mean);
        CHECK(std::abs(c.var - c.expected_var) < 5.0 * c.sd_var);
        // Teeth: a theory that took E[a^2] = 1 (normal) for uniform amplitudes is 3x off.
        CHECK(std::abs(c.var - 3.0 * c.expected_var) > 5.0 * c.sd_var);
    }
}

TEST_CASE("radially averaged periodogram of a periodic frame matches lambda E[a^2] |H|^2",
          "[render][stats]") {
    // The frame is a torus (period = frame size), so no window is needed and there is no
    // leakage: the DFT of the sampled field is sum_k a_k sum_m H(k + m) e^{-2 pi i (k+m).x_k}
    // (Poisson summation over the pixel lattice), and averaging over uniform x_k on the torus
    // gives E[I(k)] = lambda E[a^2] sum_m P(k + m) exactly. m = 0 is the theory; the aliases
    // m != 0 sit at |k + m| >= 0.75 for |k| <= 0.25, where P <= Pmax_alias (measured below;
    // ~2.6e-11 P(0) for this kernel), so they add at most 8 Pmax_alias plus a negligible
    // |m| >= 2 tail (P < 1e-13 P(0) there): that is the aliasing allowance.
    //
    // Sampling error of an annulus mean: each DFT bin is a sum over ~2e4 impulses, hence
    // complex Gaussian, and I(k) ~ S(k) Exp(1); the annulus holds `count` bins in conjugate
    // pairs, M = count / 2 independent values, so sd / mean = 1 / sqrt(M). Shot noise adds a
    // fourth-cumulant covariance lambda E[a^4] P(k) P(k') / A between all bins, which does not
    // average away: relative variance + E[a^4] / (lambda A E[a^2]^2) (= 1.4e-4 here).
    // Band: |measured - expected| <= 5 sd + aliasing allowance, for annuli 1 <= b < 256
    // (k < 0.25 cycles/px) whose expected power is above 1e-6 S(0) — below that (near the
    // zeros of the cosine bump's spectrum) the aliasing allowance would no longer be small.
    // With ~200 annuli, the heavier Gamma tails of the small annuli (M = 4, 8, ...) give a false
    // alarm probability of ~1e-3 for a random seed; the seed is fixed.
    const auto r = render_still(cosine_scene(1024, 16.0, true));
    const auto& layer = r.scene.layers[0];
    const double lambda = layer.process.intensity;
    const double ea2 = 1.0, ea4 = 3.0;
    const int n = 1024;
    const auto pg = impulse::analysis::periodogram(to_image(r.frame), impulse::analysis::Window::None);
    const auto prof = impulse::analysis::radial_average(pg);

    const Kernel k(layer.kernel);
    const RadialTable table(k, 0.36, 1.0 / 4096.0);
    double pmax_alias = 0.0;
    for (double q = 0.75; q <= 1.8; q += 0.01) pmax_alias = std::max(pmax_alias, k.radial_power_spectrum(q));
    const double alias = 8.0 * lambda * ea2 * pmax_alias;
    const double s0 = lambda * ea2 * k.integral() * k.integral();
    CHECK(pmax_alias < 1e-10 * k.power_spectrum(0, 0));

    // Teeth: the same measurement against a radius-12 kernel at the same density per kernel
    // area (lambda' = 16 / (pi 12^2)).
    impulse::kernels::KernelParams p12 = layer.kernel;
    p12.radius = 12.0;
    const Kernel k12(p12);
    const double lambda12 = 16.0 / k12.support_area();
    const RadialTable table12(k12, 0.36, 1.0 / 4096.0);

    // Expected power per annulus: the per-bin average of S over exactly the bins that
    // radial_average puts there (same binning rule: annulus floor(|k| n)).
    const size_t nb = 256;
    std::vector<double> expect(nb, 0.0), expect12(nb, 0.0);
    std::vector<uint64_t> count(nb, 0);
    for (int ky = -int(nb); ky <= int(nb); ++ky)
        for (int kx = -int(nb); kx <= int(nb); ++kx) {
            const double rho = std::sqrt(double(kx) * kx + double(ky) * ky);
            if (rho == 0.0 || rho >= double(nb)) continue;
            const size_t b = static_cast<size_t>(rho);
            expect[b] += lambda * ea2 * table(rho / n);
            expect12[b] += lambda12 * ea2 * table12(rho / n);
            ++count[b];
        }
    int tested = 0, out_of_band = 0, out_of_band12 = 0;
    double worst_z = 0.0;
    for (size_t b = 1; b < nb; ++b) {
        REQUIRE(count[b] == prof.count[b]);
        expect[b] /= count[b];
        expect12[b] /= count[b];
        if (expect[b] < 1e-6 * s0) continue;
        const double rel_var = 2.0 / count[b] + ea4 / (lambda * n * n * ea2 * ea2);
        const double sd = expect[b] * std::sqrt(rel_var);
        const double z = (prof.power[b] - expect[b]) / sd;
        worst_z = std::max(worst_z, std::abs(z));
        if (std::abs(prof.power[b] - expect[b]) > 5.0 * sd + alias) {
            ++out_of_band;
            UNSCOPED_INFO("annulus " << b << " k=" << prof.frequency[b] << " measured " << prof.power[b]
                                     << " expected " << expect[b] << " z=" << z);
        }
        const double sd12 = expect12[b] * std::sqrt(rel_var);
        if (std::abs(prof.power[b] - expect12[b]) > 5.0 * sd12 + alias) ++out_of_band12;
        ++tested;
    }
    CAPTURE(tested, worst_z, out_of_band12, alias / s0);
    CHECK(tested > 150);
    CHECK(out_of_band == 0);
    // The wrong kernel fails in most annuli, not marginally in one.
    CHECK(out_of_band12 > tested / 2);
}

TEST_CASE("a periodic frame tiles without a seam", "[render][stats]") {
    // Tile a 256x256 frame 2x2. Across the seam the mosaic compares pixel 255 with pixel 0 of
    // the frame; inside, pixel x with x+1. For a torus frame the seam difference is just one
    // more neighbouring difference D = f(x+1) - f(x), so its mean square must match the
    // interior's.
    //
    // Band (an F-type test on the log ratio of mean squares; E[D] = 0 is known, so no mean is
    // removed): D is shot noise with the difference kernel g(y) = h(y + e) - h(y), so
    //   C_D(tau) = lambda E[a^2] int g(y) g(y + tau) dy,  k4_D(tau) = lambda E[a^4] int g^2 g^2(. + tau)
    // and for the mean square of n values along a column of the torus (lags along the column)
    //   Var(ms_seam) = (1/n) sum_tau [2 C_D(0,tau)^2 + k4_D(0,tau)],
    // for the N_int = 255 * 256 interior values (all lags in the plane)
    //   Var(ms_int) ~ (1/N_int) sum_tau [2 C_D(tau)^2 + k4_D(tau)].
    // sd(log r) <= sqrt(Var(ms_seam) + Var(ms_int)) / C_D(0) (the two share rows, a positive
    // covariance that only narrows the true spread: conservative). Band: |log r| < 5 sd.
    // The integrals are sums over a 1/4-px grid of g, exact enough (~1e-3) for a band.
    const int size = 256;
    const double R = 8.0;
    const auto per = render_still(cosine_scene(size, R, true));
    const auto flat = render_still(cosine_scene(size, R, false));
    const auto& layer = per.scene.layers[0];
    const Kernel k(layer.kernel);
    const double lambda = layer.process.intensity, ea2 = 1.0, ea4 = 3.0;

    // g on a grid of spacing 1/4 px covering its support [-R-1, R+1]^2 plus lags up to 2R+2.
    const int sub = 4, half = static_cast<int>((R + 1) * sub) + 1, L = static_cast<int>(2 * R + 2);
    const int w = 2 * half + 1;
    const double d = 1.0 / sub;
    std::vector<double> g(size_t(w) * w), g2(size_t(w) * w);
    for (int j = 0; j < w; ++j)
        for (int i = 0; i < w; ++i) {
            const double x = (i - half) * d, y = (j - half) * d;
            const double v = k.evaluate(x + 1.0, y) - k.evaluate(x, y);
            g[size_t(j) * w + i] = v;
            g2[size_t(j) * w + i] = v * v;
        }
    auto corr = [&](const std::vector<double>& a, int tx, int ty) {  // sum a(y) a(y + tau) d^2
        double s = 0.0;
        const int ox = tx * sub, oy = ty * sub;
        for (int j = std::max(0, -oy); j < std::min(w, w - oy); ++j)
            for (int i = std::max(0, -ox); i < std::min(w, w - ox); ++i)
                s += a[size_t(j) * w + i] * a[size_t(j + oy) * w + i + ox];
        return s * d * d;
    };
    const double cd0 = lambda * ea2 * corr(g, 0, 0);
    double col = 0.0, plane = 0.0;
    for (int ty = -L; ty <= L; ++ty)
        for (int tx = -L; tx <= L; ++tx) {
            const double c = lambda * ea2 * corr(g, tx, ty);
            const double k4 = lambda * ea4 * corr(g2, tx, ty);
            plane += 2.0 * c * c + k4;
            if (tx == 0) col += 2.0 * c * c + k4;
        }
    const double n_seam = size, n_int = double(size - 1) * size;
    const double sd_log = std::sqrt(col / n_seam + plane / n_int) / cd0;

    // Mean squares of the seam and interior differences of a 2x2 mosaic, both directions.
    auto log_ratio = [&](const Frame& f, bool vertical) {
        Frame m;
        m.resize(2 * size, 2 * size);
        for (int y = 0; y < 2 * size; ++y)
            for (int x = 0; x < 2 * size; ++x) m.data[size_t(y) * m.width + x] = f.at(x % size, y % size);
        auto at = [&](int a, int b) { return vertical ? m.at(b, a) : m.at(a, b); };  // a across the seam
        double seam = 0.0, inner = 0.0;
        for (int b = 0; b < size; ++b) {
            const double ds = double(at(size, b)) - at(size - 1, b);  // mosaic seam at size-1 | size
            seam += ds * ds;
            for (int a = 0; a + 1 < size; ++a) {
                const double di = double(at(a + 1, b)) - at(a, b);
                inner += di * di;
            }
        }
        return std::log((seam / n_seam) / (inner / n_int));
    };
    const double h_per = log_ratio(per.frame, false), v_per = log_ratio(per.frame, true);
    const double h_flat = log_ratio(flat.frame, false), v_flat = log_ratio(flat.frame, true);
    CAPTURE(cd0, sd_log, h_per, v_per, h_flat, v_flat);
    CHECK(std::abs(h_per) < 5.0 * sd_log);
    CHECK(std::abs(v_per) < 5.0 * sd_log);
    // Teeth: a non-periodic frame's mosaic joins independent values, Var = 2 C(0) instead of
    // C_D(0) = 2 (C(0) - C(1)): a log ratio of ~log(C(0) / (C(0) - C(1))), far outside.
    CHECK(h_flat > 5.0 * sd_log);
    CHECK(v_flat > 5.0 * sd_log);
    // And the theory of D itself: the interior mean square of the periodic frame matches C_D(0)
    // (sd of ms_int from the same derivation).
    double inner = 0.0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x + 1 < size; ++x) {
            const double di = double(per.frame.at(x + 1, y)) - per.frame.at(x, y);
            inner += di * di;
        }
    CHECK(std::abs(inner / n_int - cd0) < 5.0 * std::sqrt(plane / n_int));
    // The derived spread of one column's mean square, sqrt(col / n) / C_D(0), is also what the
    // 255 interior columns show (neighbouring columns are correlated over ~2R, so ~16
    // independent groups: the scatter estimate itself is good to ~20 %; allow 0.5x-2x).
    std::vector<double> logs;
    for (int x = 0; x + 1 < size; ++x) {
        double ms = 0.0;
        for (int y = 0; y < size; ++y) {
            const double di = double(per.frame.at(x + 1, y)) - per.frame.at(x, y);
            ms += di * di;
        }
        logs.push_back(std::log(ms / size / cd0));
    }
    double lm = 0.0, lv = 0.0;
    for (double v : logs) lm += v / logs.size();
    for (double v : logs) lv += (v - lm) * (v - lm) / logs.size();
    const double derived_col = std::sqrt(col / n_seam) / cd0;
    CAPTURE(std::sqrt(lv), derived_col);
    CHECK(std::sqrt(lv) > 0.5 * derived_col);
    CHECK(std::sqrt(lv) < 2.0 * derived_col);
}
