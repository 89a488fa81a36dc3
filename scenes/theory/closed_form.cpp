// SPDX-License-Identifier: Apache-2.0
// The closed-form theory of a scene as seen through frames of it (scenes/closed_form.h):
// Campbell's theorem per layer (design.md §1) on the frames' DFT grid, with the sampling errors
// the analysis judges the measurements with (design.md §5).

#include "scenes/closed_form.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <cstdio>
#include <numbers>
#include <optional>

#include "kernels/kernels.h"
#include "numeric/fft.h"
#include "numeric/gaussian.h"
#include "output/output.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace impulse::scenes {
namespace {

using analysis::AnalysisResult;
using analysis::format_number;
using analysis::TheoryComparison;
using analysis::TimeCorrelation;

constexpr double kMaxClippedForSpectrum = 1e-4;  ///< display inputs: judge the spectrum below it

// ---------------------------------------------------------------------------------------------
// Theory

/// Moments of Y = clamp(Z, a, b) for a standard normal Z: how a display range censors a
/// Gaussian field (8-bit inputs are clipped to [0, 1] at mean +- 3 sd by default).
struct Censored {
    double mean = 0.0, variance = 1.0;
    double gain = 1.0;  ///< P(a < Z < b): the linear gain of the clip (Price's theorem)
};
Censored censored_normal(double a, double b) {
    const double Pa = numeric::normal_cdf(a), Pb = numeric::normal_cdf(b);
    const double pa = numeric::normal_pdf(a), pb = numeric::normal_pdf(b);
    Censored c;
    c.mean = a * Pa + (pa - pb) + b * (1 - Pb);
    const double m2 = a * a * Pa + (Pb - Pa + a * pa - b * pb) + b * b * (1 - Pb);
    c.variance = m2 - c.mean * c.mean;
    c.gain = Pb - Pa;
    return c;
}

/// Temporal correlation of a layer without flow at lag dt: int w(a)^p w(a + dt)^p da /
/// int w^2p. p = 1: the field (the time half of the space-time covariance, design.md §1);
/// p = 2: the impulse population's fourth-cumulant term, E[a^4 w^4].
double envelope_correlation(sim::Envelope e, double T, double dt, int p = 1) {
    const int n = 4096;
    double s = 0, s2 = 0;
    for (int i = 0; i < n; ++i) {
        const double a = (i + 0.5) * T / n;
        const double w = std::pow(sim::envelope_weight(e, a, T), p);
        s += w * std::pow(sim::envelope_weight(e, a + dt, T), p);
        s2 += w * w;
    }
    return s2 > 0 ? s / s2 : 0.0;
}

bool isotropic(const kernels::Kernel& k) {
    return !k.has_carrier() && k.params().aspect == 1.0 && !k.is_grid();
}

/// A layer's spectrum in pixel units tabulated in |k| (cycles per pixel), interpolated with the
/// 4-point Lagrange cubic: exact for cubics, so the quadratic nulls of |H|^2 between side lobes are
/// followed (linear interpolation fills them in and overstates the power there several-fold).
struct RadialTable {
    double step = 0.0;
    std::vector<double> value;  ///< value[i] = S(i * step); one extra node before 0 by symmetry
    double operator()(double rho) const {
        const double x = rho / step;
        const size_t i = static_cast<size_t>(x);
        if (i + 2 >= value.size()) return 0.0;
        const double t = x - double(i);
        const double p0 = i == 0 ? value[1] : value[i - 1];  // S is even in |k|
        const double p1 = value[i], p2 = value[i + 1], p3 = value[i + 2];
        const double v = -t * (t - 1) * (t - 2) / 6 * p0 + (t + 1) * (t - 1) * (t - 2) / 2 * p1 -
                         (t + 1) * t * (t - 2) / 2 * p2 + (t + 1) * t * (t - 1) / 6 * p3;
        return std::max(v, 0.0);
    }
};

struct LayerSpectrum {
    kernels::Kernel kernel;
    double zoom = 1.0;
    double scale = 0.0;  ///< gain^2 lambda E[a^2] (1/T int w^2): S_tex = scale |H|^2
    bool aliasing = false;
    bool fixed_anisotropic = false;  ///< every impulse has the kernel's own, anisotropic shape
    RadialTable table;               ///< angular mean of S in value^2 px^2 at |k| cycles/px
    double far_alias = 0.0;          ///< images m with max(|mx|, |my|) in [2, 8], summed at k = 0
    /// A source layer: S_tex = scale S_source (scale = gain^2), stated by the source.
    const LayerSource* source = nullptr;
    /// A source that states its spectrum as sampled on the frames' pixel lattice (at the first
    /// frame's layer time t): every alias included, coherent where its lattice and the pixels'
    /// are commensurate (LayerSource::sampled_spectrum).
    bool sampled = false;
    PixelLattice lattice;
    double t = 0.0;
    MotionBlur blur;  ///< the camera's shutter: each kernel's mean along its path
    /// An anti-aliased orthographic camera's pixel filter (camera.filter, a Gaussian of this sd
    /// in pixels; 0: none): the kernels are low-passed by it before sampling (docs/scenes.md
    /// "Anti-aliasing"), so S is multiplied by its |G|^2 = exp(-4 pi^2 filter^2 |k|^2).
    double filter_px = 0.0;
    /// The multi-rate lattice the layer is evaluated on (render/lattice.h; 1: every pixel) and
    /// the largest |k| (cycles per pixel) where its spectrum is not negligible, which bounds the
    /// lattice images summed (docs/multirate.md §6).
    int lattice_h = 1;
    double reach = 0.0;
    double filtered(double fx, double fy) const {
        const double f = 2.0 * std::numbers::pi * filter_px;
        return filter_px > 0.0 ? std::exp(-f * f * (fx * fx + fy * fy)) : 1.0;
    }
    /// An isotropic kernel's S without the blur, at |k| cycles per pixel, tabulated as `table`
    /// is (empty unless the layer is blurred): a blurred layer's bins take it times the blur's
    /// exact anisotropic factor instead of a Hankel quadrature each (40x fewer quadratures
    /// for a 64^2 frame's bins and their images).
    RadialTable unblurred;
    /// S at (fx, fy) cycles per pixel for a blurred layer's bin: `unblurred` times the blur's
    /// factor where the kernel is isotropic, else exact().
    double blurred_at(double fx, double fy) const {
        if (source || unblurred.value.empty()) return exact(fx, fy);
        return unblurred(std::hypot(fx, fy)) * blur.spectrum_factor(fx * zoom, fy * zoom);
    }
    /// S at (fx, fy) cycles per pixel, exact (orientation and aspect included), no aliasing.
    double exact(double fx, double fy) const {
        if (source) return zoom * zoom * scale * source->power_spectrum_2d(fx * zoom, fy * zoom).value_or(0.0);
        return zoom * zoom * scale * kernel.power_spectrum(fx * zoom, fy * zoom) *
               blur.spectrum_factor(fx * zoom, fy * zoom) * filtered(fx, fy);
    }
};

/// Annuli below this index hold too few DFT bins (about 2 pi b) for their mean to stand for the
/// angular average of an anisotropic spectrum: there the bins are evaluated exactly.
constexpr double kExactAnnuli = 16.0;

LayerSpectrum layer_spectrum(const LayerConfig& layer, double zoom, int n_max,
                             const MotionBlur& blur, double filter_px, int lattice_h = 1) {
    LayerSpectrum L{kernels::Kernel(layer.kernel), zoom, 0.0, false, false, {}, 0.0};
    L.blur = blur;
    L.filter_px = filter_px;
    L.lattice_h = lattice_h;
    const kernels::Kernel& k = L.kernel;
    L.scale = layer_theory(layer).variance / k.integral_sq();
    const double R_px = k.radius() * zoom;
    const bool iso = isotropic(k);
    // A random orientation per impulse averages the spectrum over angle: then the angular mean is
    // the spectrum. Flow- or vorticity-driven orientations are approximated by it too.
    L.fixed_anisotropic = !iso && layer.process.orientation == sim::OrientationMode::Fixed;
    // S_px(rho) = zoom^2 S_tex(rho zoom): a pixel is 1/zoom texture units (docs/scenes.md).
    // Anisotropic kernels: the angular mean over 36 directions of Kernel::power_spectrum (the
    // average Kernel::radial_power_spectrum takes over 180, which costs five times as much for
    // a table whose points are 1/8 of an oscillation apart anyway).
    const auto S = [&](double rho) {
        const int n = 36;
        if (iso)
            return zoom * zoom * L.scale * k.radial_power_spectrum(rho * zoom) *
                   L.blur.radial_factor(rho * zoom) * L.filtered(rho, 0.0);
        double sum = 0;
        for (int i = 0; i < n; ++i) {
            const double a = std::numbers::pi * (i + 0.5) / n;
            sum += L.exact(rho * std::cos(a), rho * std::sin(a));
        }
        return sum / n;
    };
    // Pixel sampling aliases frequencies beyond Nyquist onto the grid; the nearest images
    // (|m| <= 1 per axis) are added where the spectrum at Nyquist is not negligible.
    L.aliasing = iso || S(0.5) > 1e-7 * L.scale * k.integral_sq();
    const double rho_max = (L.aliasing ? 1.0 : 0.0) + 0.5 * std::numbers::sqrt2 + 0.01;
    // The spectrum of a kernel of radius R oscillates on a scale of about 1/(2R). Isotropic
    // kernels (one quadrature per point) get 64 points per oscillation, enough for the cubic to
    // follow the nulls to well under the sampling error of a 1024^2 frame (checked against
    // rendered frames), but no finer than 1/8 of the DFT bin spacing; the others (36 directions
    // per point) get 4, an approximation near the nulls of the angular mean.
    L.table.step = iso ? std::max(1.0 / (128.0 * std::max(R_px, 0.5)), 1.0 / (8.0 * n_max))
                       : 1.0 / (8.0 * std::max(R_px, 0.5));
    const size_t n = static_cast<size_t>(std::ceil(rho_max / L.table.step)) + 3;
    L.table.value.assign(n, 0.0);
    tbb::parallel_for(size_t(0), n,
                      [&](size_t i) { L.table.value[i] = S(double(i) * L.table.step); });
    if (iso && !L.blur.paths.empty()) {
        L.unblurred.step = L.table.step;
        L.unblurred.value.assign(n, 0.0);
        tbb::parallel_for(size_t(0), n, [&](size_t i) {
            const double rho = double(i) * L.table.step;
            L.unblurred.value[i] = zoom * zoom * L.scale * k.radial_power_spectrum(rho * zoom) *
                                   L.filtered(rho, 0.0);
        });
    }
    // The reach: past the last table point above 1e-10 of the peak, what a lattice image
    // carries is under the frames' float rounding (the table is 0 beyond its end anyway).
    L.reach = 0.0;
    for (size_t i = n; i-- > 0;)
        if (L.table.value[i] > 1e-10 * L.table.value[0]) {
            L.reach = double(i + 1) * L.table.step;
            break;
        }
    if (L.aliasing) {
        // Kernels cut off with a jump (a Gabor or Gaussian truncated at R) have spectra with
        // slow power-law tails whose far images still add up: sum the images with
        // max(|mx|, |my|) in [2, M] once, at k = 0, as a white floor (they vary little across
        // the band). Isotropic: S depends on |m| only, M = 8; otherwise the exact 2-D spectrum
        // at the lattice points, M = 4 (the quadratures get slower as |k| grows). One half-plane
        // is evaluated: S(m) = S(-m).
        const int M = iso ? 8 : 4;
        std::vector<std::pair<int, int>> points;
        for (int my = 0; my <= M; ++my)
            for (int mx = -M; mx <= M; ++mx)
                if (std::max(std::abs(mx), my) >= 2 && (my > 0 || mx > 0) && (!iso || (mx >= my)))
                    points.push_back({mx, my});
        std::vector<double> value(points.size());
        tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
            const auto [mx, my] = points[i];
            const double v = iso ? S(std::hypot(mx, my)) : L.exact(mx, my);
            // multiplicity: the point and its mirror -m; for isotropic kernels also the other
            // members of the 8-fold symmetry class (mx >= my >= 0 listed once)
            int mult = 2;
            if (iso) mult = (my == 0 || mx == my) ? 4 : 8;
            value[i] = mult * v;
        });
        for (double v : value) L.far_alias += v;
    }
    return L;
}

/// A source layer's spectrum as the source states it (LayerSource::power_spectrum), scaled by the
/// layer's gain: S_px(rho) = zoom^2 gain^2 S(rho zoom). Where the source states it sampled on the
/// pixel lattice of the scene's first frame (sampled_spectrum) that is taken; otherwise its
/// nearest images are added as independent power, which holds where the pixel lattice and the
/// source's own are incommensurate (docs/scenes.md "Analysis of source layers").
LayerSpectrum source_spectrum(const Scene& scene, const LayerConfig& layer, double zoom, int n_max) {
    LayerSpectrum L{kernels::Kernel(layer.kernel), zoom, 0.0, true, false, {}, 0.0};
    L.source = layer.source.get();
    const double t0 = scene.frame_time(0);
    const render::View v = scene.camera.view(scene.output.width, scene.output.height, t0);
    L.lattice = PixelLattice{v.scale, v.x0 + 0.5 * v.scale, v.y0 + 0.5 * v.scale};
    L.t = layer.layer_time(t0);
    L.sampled = L.source->sampled_spectrum(0.25, 0.25, L.lattice, L.t).has_value();
    const double gain = layer.gain.value(0.0);
    L.scale = gain * gain;
    L.fixed_anisotropic = L.source->anisotropic_spectrum();
    L.table.step = 1.0 / (8.0 * n_max);
    const double rho_max = 1.0 + 0.5 * std::numbers::sqrt2 + 0.01;
    const size_t n = static_cast<size_t>(std::ceil(rho_max / L.table.step)) + 3;
    L.table.value.assign(n, 0.0);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        L.table.value[i] =
            zoom * zoom * L.scale * L.source->power_spectrum(double(i) * L.table.step * zoom).value_or(0.0);
    });
    return L;
}

/// The centred cubic B-spline.
double beta3(double x) {
    x = std::abs(x);
    if (x < 1.0) return 2.0 / 3.0 - x * x + 0.5 * x * x * x;
    if (x < 2.0) return (2.0 - x) * (2.0 - x) * (2.0 - x) / 6.0;
    return 0.0;
}

/// Power transfer along one axis of a field sampled every h pixels and reconstructed at the
/// pixels by the interpolating cubic B-spline, over the h^2 of the samples' own spectrum:
/// |sum_d beta3(d / h) e^{-2 pi i f d}|^2 / (h B(f h))^2, B(v) = (2 + cos 2 pi v) / 3 the
/// prefilter's inverse (docs/multirate.md §6). 1 at f = 0; 1 at every f for h = 1.
double lattice_transfer(double f, int h) {
    double re = 0.0, im = 0.0;
    for (int d = -2 * h + 1; d <= 2 * h - 1; ++d) {
        const double b = beta3(double(d) / h), a = -2.0 * std::numbers::pi * f * d;
        re += b * std::cos(a), im += b * std::sin(a);
    }
    const double B = (2.0 + std::cos(2.0 * std::numbers::pi * f * h)) / 3.0;
    return (re * re + im * im) / (double(h) * h * B * B);
}

/// The layer's expected periodogram on the DFT grid of a w x h frame (aliasing included).
std::vector<double> layer_grid(const LayerSpectrum& L, int w, int h) {
    std::vector<double> g(size_t(w) * h);
    // A source with an anisotropic spectrum (an fbm tile's lattice, the bilinear read's
    // separable transfer) is evaluated exactly at every bin and image, two images out per axis:
    // its aliased tails are anisotropic too, which the radial table would smear.
    const bool all_exact = L.source && L.fixed_anisotropic;
    const int m = L.aliasing ? (all_exact ? 2 : 1) : 0;
    // A blurred layer's spectrum is anisotropic (sinc^2 across the motion's nulls), and so are
    // its aliased images: every bin and image exactly.
    const bool blurred = !L.blur.paths.empty();
    const int side = std::min(w, h);
    // The lattice's transfer per column and per row (it is separable).
    std::vector<double> tx, ty;
    if (L.lattice_h > 1) {
        for (int kx = 0; kx < w; ++kx)
            tx.push_back(lattice_transfer(analysis::Periodogram::frequency(kx, w), L.lattice_h));
        for (int ky = 0; ky < h; ++ky)
            ty.push_back(lattice_transfer(analysis::Periodogram::frequency(ky, h), L.lattice_h));
    }
    tbb::parallel_for(0, h, [&](int ky) {
        const double fy = analysis::Periodogram::frequency(ky, h);
        for (int kx = 0; kx < w; ++kx) {
            const double fx = analysis::Periodogram::frequency(kx, w);
            if (L.sampled) {
                g[size_t(ky) * w + kx] =
                    L.scale * L.source->sampled_spectrum(fx, fy, L.lattice, L.t).value_or(0.0);
                continue;
            }
            double s = 0;
            const bool exact = L.fixed_anisotropic && std::hypot(fx, fy) * side < kExactAnnuli;
            if (L.lattice_h > 1) {
                // Sampled every h pixels: the images at multiples of 1/h (the pixels' own among
                // them) within the spectrum's reach, through the spline's transfer.
                const int H = L.lattice_h;
                const int ax0 = int(std::ceil((-L.reach - fx) * H)), ax1 = int(std::floor((L.reach - fx) * H));
                const int ay0 = int(std::ceil((-L.reach - fy) * H)), ay1 = int(std::floor((L.reach - fy) * H));
                for (int ay = ay0; ay <= ay1; ++ay)
                    for (int ax = ax0; ax <= ax1; ++ax) {
                        const double gx = fx + double(ax) / H, gy = fy + double(ay) / H;
                        s += blurred && !all_exact ? L.blurred_at(gx, gy)
                             : all_exact || (exact && ax == 0 && ay == 0)
                                 ? L.exact(gx, gy)
                                 : L.table(std::hypot(gx, gy));
                    }
                g[size_t(ky) * w + kx] = tx[size_t(kx)] * ty[size_t(ky)] * (s + L.far_alias);
                continue;
            }
            for (int my = -m; my <= m; ++my)
                for (int mx = -m; mx <= m; ++mx)
                    s += blurred && !all_exact ? L.blurred_at(fx + mx, fy + my)
                         : all_exact || (exact && mx == 0 && my == 0)
                             ? L.exact(fx + mx, fy + my)
                             : L.table(std::hypot(fx + mx, fy + my));
            g[size_t(ky) * w + kx] = s + L.far_alias;
        }
    });
    return g;
}

/// Expected value of the Hann-windowed periodogram from the unwindowed one: the DFT-even Hann
/// window's transform has taps (1/2, -1/4, -1/4), so E[P_w(k)] = sum_m c_m^2 S(k - m) / sum c^2,
/// i.e. a circular (1/6, 2/3, 1/6) smoothing along each axis. The DC bin is zero first: the
/// estimator removes the mean, whose bin then leaks nothing.
std::vector<double> hann_smooth(std::vector<double> g, int w, int h) {
    g[0] = 0.0;
    std::vector<double> t(g.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            t[size_t(y) * w + x] =
                (2.0 / 3.0) * g[size_t(y) * w + x] +
                (1.0 / 6.0) * (g[size_t(y) * w + (x + 1) % w] + g[size_t(y) * w + (x + w - 1) % w]);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            g[size_t(y) * w + x] =
                (2.0 / 3.0) * t[size_t(y) * w + x] +
                (1.0 / 6.0) * (t[size_t((y + 1) % h) * w + x] + t[size_t((y + h - 1) % h) * w + x]);
    return g;
}

std::vector<double> annulus_means(std::vector<double> grid, int w, int h) {
    analysis::Periodogram p;
    p.width = w;
    p.height = h;
    p.power = std::move(grid);
    return analysis::radial_average(p).power;
}

/// A source layer's autocovariance at integer lags from its radial spectrum (the Hankel
/// transform C(r) = int S(rho) J_0(2 pi rho r) 2 pi rho d rho over the tabulated band, in pixels).
std::vector<double> source_autocovariance(const LayerSpectrum& L, int max_lag) {
    std::vector<double> c(size_t(max_lag) + 1, 0.0);
    const size_t n = L.table.value.size() - 3;
    tbb::parallel_for(0, max_lag + 1, [&](int r) {
        double a = 0;
        for (size_t i = 0; i < n; ++i) {  // midpoint rule on the table's step
            const double rho = (double(i) + 0.5) * L.table.step;
            a += L.table(rho) * std::cyl_bessel_j(0.0, 2.0 * std::numbers::pi * rho * r) * rho;
        }
        c[size_t(r)] = 2.0 * std::numbers::pi * a * L.table.step;
    });
    return c;
}

/// Radial ring values of the theoretical autocovariance at integer lags 0..max_lag (pixels).
std::vector<double> layer_autocovariance(const LayerSpectrum& L, double zoom, int max_lag) {
    if (L.source) return source_autocovariance(L, max_lag);
    std::vector<double> c(size_t(max_lag) + 1, 0.0);
    const kernels::Kernel& k = L.kernel;
    const bool iso = isotropic(k);
    const double reach = 2.0 * k.radius();  // h * h~ vanishes beyond twice the support radius
    tbb::parallel_for(0, max_lag + 1, [&](int r) {
        const double tau = r / zoom;  // texture units
        if (tau >= reach) return;
        double a = 0;
        if (iso) {
            a = k.autocorrelation(tau, 0.0);
        } else {
            // ring average: mean over 8 directions in [0, pi) (C(tau) = C(-tau))
            const int n = 8;
            for (int j = 0; j < n; ++j) {
                const double t = std::numbers::pi * (j + 0.5) / n;
                a += k.autocorrelation(tau * std::cos(t), tau * std::sin(t)) / n;
            }
        }
        c[size_t(r)] = L.scale * a;
    });
    return c;
}


/// From the scene: without flow a layer's field at lags of l frames correlates as its envelope,
/// r(l) = (w * w~)(l / fps) / int w^2 (design.md §1; 1 for a still layer), layers weighted by
/// their variance. The frame mean follows r, periodogram bins and the frame variance follow r^2
/// (Gaussian approximation). Advection by a flow moves the pattern without changing the power of
/// a periodic frame; through a window (a crop) it brings new content in and the frame variance
/// decorrelates sooner than its envelopes say: the level test takes that from
/// frame_variance_covariance (docs/stationarity.md), these correlations serve the spectra.
TimeCorrelation scene_time_correlation(const Scene& scene, size_t n, size_t quarter) {
    std::vector<double> r(n, 0.0), r4(n, 0.0);
    double total = 0, total4 = 0;
    for (const auto& layer : scene.layers) {
        const double v = layer_theory(layer).variance;
        total += v;
        total4 += v * v;
        const auto& p = layer.process;
        for (size_t l = 0; l < n; ++l) {
            const double dt = double(l) / scene.output.fps;
            const bool moving = p.lifetime_s > 0;
            r[l] += v * (moving ? envelope_correlation(p.envelope, p.lifetime_s, dt) : 1.0);
            r4[l] += v * v * (moving ? envelope_correlation(p.envelope, p.lifetime_s, dt, 2) : 1.0);
        }
    }
    for (size_t l = 0; l < n; ++l) {
        if (total > 0) r[l] /= total;
        if (total4 > 0) r4[l] /= total4;
    }
    std::vector<double> r2(n);
    for (size_t l = 0; l < n; ++l) r2[l] = r[l] * r[l];
    TimeCorrelation tc;
    tc.source = "scene";
    tc.r2 = r2;
    tc.r4 = r4;
    tc.n_eff_mean = analysis::effective_frames(n, r);
    tc.n_eff_variance = tc.n_eff_spectrum = analysis::effective_frames(n, r2);
    tc.n_eff_population = analysis::effective_frames(n, r4);
    tc.q_eff = quarter > 0 ? analysis::effective_frames(quarter, r2) : 1.0;
    tc.q_eff_population = quarter > 0 ? analysis::effective_frames(quarter, r4) : 1.0;
    return tc;
}

/// What the closed forms do not cover in this scene, said in R's notes: an animated zoom, a
/// transform or a birth region makes the texture something else, and the comparison says so by
/// disagreeing.
void note_what_theory_misses(const Scene& scene, AnalysisResult& R) {
    if (!scene.camera.zoom.is_constant())
        R.notes.push_back(
            "camera zoom is animated: no theoretical spectrum or autocovariance; the "
            "sampling errors of mean and variance use the zoom at t = 0");
    if (scene.transform.type != output::FieldTransform::Type::None)
        R.notes.push_back(
            "the scene has a [shading.transform] (marble or wood): the theory describes the "
            "field before the transform, not this texture");
    for (size_t i = 0; i < scene.layers.size(); ++i)
        if (scene.layers[i].process.region)
            R.notes.push_back("layer[" + std::to_string(i) +
                              "] has a birth region: the theory holds only where the region "
                              "accepts every birth within a kernel radius");
    if (scene.output.width != R.width || scene.output.height != R.height)
        R.notes.push_back("scene output.size " + std::to_string(scene.output.width) + "x" +
                          std::to_string(scene.output.height) + " differs from the input " +
                          std::to_string(R.width) + "x" + std::to_string(R.height) +
                          " (the theory per pixel does not depend on it)");
}

/// Display inputs: clipping to [lo, hi] (Gaussian approximation of the marginal) and the
/// quantisation to 2^bits - 1 levels (uniform rounding error, white, variance step^2 / 12).
struct DisplayEffects {
    Censored cens;
    double quant = 0.0;
};
DisplayEffects display_effects(const Theory& th, int bits, bool mapped, double lo, double hi) {
    DisplayEffects d;
    if (!mapped) return d;
    const double sd_field = std::sqrt(th.variance);
    if (sd_field > 0)
        d.cens = censored_normal((lo - th.mean) / sd_field, (hi - th.mean) / sd_field);
    const double step = (hi - lo) / (std::ldexp(1.0, std::min(bits, 24)) - 1.0);
    d.quant = step * step / 12.0;
    return d;
}

/// The layers' spectra summed on the DFT grid, with what the sampling errors need from each.
struct LayerSums {
    std::vector<double> grid;                       ///< aliased S on the w x h DFT grid
    std::vector<std::vector<double>> layer_annuli;  ///< each layer's annulus means
    std::vector<double> c4;  ///< relative covariance of all bins from impulse-count fluctuations
    std::vector<double> acov;  ///< autocovariance rings (constant zoom)
    /// each layer's aliased S on a DFT grid padded beyond the window by the covariance's reach
    /// (2 R) and the largest displacement of a layer over the frames (frame_variance_covariance)
    std::vector<std::vector<double>> padded;
    std::vector<double> padded_impulses;  ///< per padded grid: 1 for an impulse layer, 0 a source
    double source_dc = 0.0;  ///< the source layers' S(0): their frames tile, so S(0) / N is exact
    int padded_rows = 0, padded_cols = 0;
    double quant = 0.0;        ///< white quantisation noise, new in every frame
    double population = 0.0;   ///< fourth-cumulant term of Var(a frame's sample variance)
    /// Cov(V_0, V_d) at the lags of FrameLags: the population term (per lag, summed over layers)
    std::vector<double> population_lags;
    double diff_var = 0.0;     ///< Var of a pixel's change between frames (no flow)
    bool diff_known = true, any_animated = false;
};

/// A layer's spectrum on the DFT grid (`ls`) and on the padded grid (`padded_ls`, tabulated for
/// its size), its annuli and autocovariance, added to S.
void add_layer_spectrum(const Scene& scene, const LayerSpectrum& ls, const LayerSpectrum& padded_ls,
                        const AnalysisResult& R, double zoom, double g2, LayerSums& S,
                        bool layer_is_source = false) {
    const int w = R.width, h = R.height;
    std::vector<double> pg = layer_grid(padded_ls, S.padded_cols, S.padded_rows);
    for (double& v : pg) v *= g2;
    S.padded.push_back(std::move(pg));
    S.padded_impulses.push_back(layer_is_source ? 0.0 : 1.0);
    std::vector<double> lg = layer_grid(ls, w, h);
    for (size_t i = 0; i < lg.size(); ++i) {
        lg[i] *= g2;
        S.grid[i] += lg[i];
    }
    S.layer_annuli.push_back(
        annulus_means(R.periodogram.window == "hann" ? hann_smooth(lg, w, h) : lg, w, h));
    if (scene.camera.zoom.is_constant()) {
        const auto ac = layer_autocovariance(ls, zoom, R.max_lag);
        for (size_t r = 0; r < ac.size(); ++r) S.acov[r] += g2 * ac[r];
    }
}

/// A source layer (one that states its spectrum: is_sum_of_layers): Gaussian in the sampling
/// errors (no impulse-count term; the fourth cumulant of solid noise is left out, see
/// docs/scenes.md "Analysis of source layers"), and its change between frames not stated.
void add_source_layer(const Scene& scene, const LayerConfig& layer, const AnalysisResult& R,
                      double zoom, double g2, LayerSums& S) {
    S.c4.push_back(0.0);
    S.diff_known = false;
    const double dc = S.grid[0];
    add_layer_spectrum(scene, source_spectrum(scene, layer, zoom, std::max(R.width, R.height)),
                       source_spectrum(scene, layer, zoom, std::max(S.padded_rows, S.padded_cols)),
                       R, zoom, g2, S, true);
    S.source_dc += S.grid[0] - dc;
}

/// The lags (frames) at which the covariance of the frame variances is evaluated: every lag up
/// to kDenseLags, then 10 % apart up to n - 1 (it varies on the scale of the lifetimes and of
/// the window's crossing time; linear in between), and each layer's rigid displacement over them.
struct FrameLags {
    std::vector<size_t> lags;
    std::vector<std::vector<std::array<double, 2>>> shift;  ///< [layer][lag index], pixels
    double max_shift = 0.0;  ///< largest |component| over layers and lags
};

constexpr size_t kDenseLags = 24;
constexpr double kLagWork = 4e9;  ///< operations for the Gaussian term over all lags

/// The displacement in pixels of a layer's uniform flows over d frames, averaged over the
/// analysed frames' start times (exact for constant velocities; a keyframed wind is taken at its
/// mean displacement over the frames, docs/stationarity.md).
std::array<double, 2> layer_displacement(const LayerConfig& layer, double fps, double zoom,
                                         long long first, size_t n, size_t d) {
    std::array<double, 2> s{0.0, 0.0};
    for (const auto& [vx, vy] : layer.uniform_flows) {
        if (vx.is_constant() && vy.is_constant()) {
            s[0] += vx.value(0.0) * double(d) / fps;
            s[1] += vy.value(0.0) * double(d) / fps;
            continue;
        }
        const size_t starts = n - d;
        for (size_t j = 0; j < starts; ++j) {
            const double t0 = double(first + static_cast<long long>(j)) / fps;
            const double t1 = t0 + double(d) / fps;
            s[0] += (vx.integral(t1) - vx.integral(t0)) / double(starts);
            s[1] += (vy.integral(t1) - vy.integral(t0)) / double(starts);
        }
    }
    return {s[0] * zoom, s[1] * zoom};
}

FrameLags frame_lags(const Scene& scene, const AnalysisResult& R, double zoom) {
    FrameLags F;
    const size_t n = size_t(std::max(R.frames, 1));
    for (size_t d = 0; d < n;
         d = d < kDenseLags ? d + 1 : std::max(d + 1, size_t(1.1 * double(d))))
        F.lags.push_back(d);
    if (F.lags.back() != n - 1) F.lags.push_back(n - 1);
    // Each lag costs about 4 corners x (2w - 1)(2h - 1) lags x components: large windows keep
    // every k-th lag (and the last) so the total stays within kLagWork operations.
    const double per_lag = 4.0 * (2.0 * R.width - 1.0) * (2.0 * R.height - 1.0) *
                           double(scene.layers.size() + 1);
    const size_t keep = std::max<size_t>(8, size_t(kLagWork / per_lag));
    if (F.lags.size() > keep) {
        const size_t k = (F.lags.size() + keep - 1) / keep;
        std::vector<size_t> thinned;
        for (size_t i = 0; i < F.lags.size(); i += k) thinned.push_back(F.lags[i]);
        if (thinned.back() != n - 1) thinned.push_back(n - 1);
        F.lags = std::move(thinned);
    }
    for (const auto& layer : scene.layers) {
        std::vector<std::array<double, 2>> shifts;
        for (size_t d : F.lags) {
            const auto s = layer_displacement(layer, scene.output.fps, zoom, R.first_frame, n, d);
            F.max_shift = std::max({F.max_shift, std::abs(s[0]), std::abs(s[1])});
            shifts.push_back(s);
        }
        F.shift.push_back(std::move(shifts));
    }
    return F;
}

/// An impulse layer's population term of Cov(V_0, V_d) at the lags of F, per unit of its
/// coefficient lambda E[a^4] W4 gain^4: the envelopes' overlap r4(d) times int A(u) A(u + s_d) du
/// (kernels/window_variance.h). Impulses of a random orientation average it over four angles.
std::vector<double> population_lags(const Scene& scene, const LayerConfig& layer, size_t index,
                                    const FrameLags& F, double zoom, int w, int h) {
    const kernels::Kernel k(layer.kernel);
    const bool random_angle = layer.process.orientation != sim::OrientationMode::Fixed;
    std::vector<double> v = kernels::window_population_correlation(
        k, zoom, w, h, isotropic(k) || !random_angle ? 1 : 4, F.shift[index]);
    const auto& p = layer.process;
    for (size_t i = 0; i < v.size(); ++i)
        if (p.lifetime_s > 0)
            v[i] *= envelope_correlation(p.envelope, p.lifetime_s,
                                         double(F.lags[i]) / scene.output.fps, 2);
    return v;
}

/// The largest reach of a layer's covariance in pixels (2 R, plus a margin).
int covariance_reach(const Scene& scene, double zoom) {
    int reach = 0;
    for (const auto& layer : scene.layers)
        reach = std::max(reach,
                         int(std::ceil(2.0 * kernels::Kernel(layer.kernel).radius() * zoom)) + 2);
    return reach;
}

/// Each layer's multi-rate lattice spacing for the scene's first frame, as the renderer takes
/// it (1 for direct evaluation): the frames' spectrum follows it (docs/multirate.md §6).
std::vector<int> lattice_spacings(const Scene& scene) {
    std::vector<int> spacing(scene.layers.size(), 1);
    if (!(scene.render.tolerance > 0.0) || scene.volume ||
        scene.camera.type != CameraConfig::Type::Orthographic)
        return spacing;
    Renderer renderer(scene);
    for (size_t i = 0; i < spacing.size(); ++i)
        if (const auto rule = renderer.lattice(i, 0)) spacing[i] = rule->spacing;
    return spacing;
}

LayerSums sum_layers(const Scene& scene, const AnalysisResult& R, double zoom, double g2,
                     double quant, const FrameLags& F) {
    const int w = R.width, h = R.height;
    const std::vector<int> spacing = lattice_spacings(scene);
    const double N = double(w) * h;
    LayerSums S;
    S.grid.assign(size_t(w) * h, quant);
    S.acov.assign(size_t(R.max_lag) + 1, 0.0);
    S.quant = quant;
    S.population_lags.assign(F.lags.size(), 0.0);
    const int reach = covariance_reach(scene, zoom);
    // Beyond a displacement of the window plus the reach two frames share nothing.
    const int shift = int(std::ceil(std::min(F.max_shift, 1e7))) + 1;
    S.padded_rows = numeric::fast_fft_size(h + reach + std::min(shift, h + reach));
    S.padded_cols = numeric::fast_fft_size(w + reach + std::min(shift, w + reach));
    for (size_t li = 0; li < scene.layers.size(); ++li) {
        const LayerConfig& layer = scene.layers[li];
        if (layer.source) {
            add_source_layer(scene, layer, R, zoom, g2, S);
            continue;
        }
        const auto& p = layer.process;
        const double ea2 = sim::amplitude_second_moment(p.amplitude);
        const double ea4 = sim::amplitude_fourth_moment(p.amplitude);
        const bool animated = p.lifetime_s > 0;
        S.any_animated = S.any_animated || animated;
        const double W2 =
            animated ? sim::envelope_sq_integral(p.envelope, p.lifetime_s) / p.lifetime_s : 1.0;
        const double W4 =
            animated ? sim::envelope_fourth_integral(p.envelope, p.lifetime_s) / p.lifetime_s : 1.0;
        const double lambda_px = p.intensity / (zoom * zoom);
        const double lv = layer_theory(layer).variance;
        // Cov(P(k), P(k')) gains lambda_px N E[a^4 w^4] |H|^2 |H'|^2 / N^2 = c S(k) S(k') for a
        // compound Poisson field: the relative covariance c below is shared by every bin.
        S.c4.push_back(ea4 * W4 / (ea2 * ea2 * W2 * W2 * lambda_px * N));
        const double coefficient =
            g2 * g2 * lambda_px * ea4 * W4 * std::pow(layer.gain.value(0.0), 4);
        const std::vector<double> pop = population_lags(scene, layer, li, F, zoom, w, h);
        for (size_t i = 0; i < pop.size(); ++i) S.population_lags[i] += coefficient * pop[i];
        S.population += coefficient * pop[0];
        if (layer.flow)
            S.diff_known = false;
        else if (animated)
            S.diff_var +=
                2.0 * g2 * lv *
                (1.0 - envelope_correlation(p.envelope, p.lifetime_s, 1.0 / scene.output.fps));
        // One table for both grids, at the window's resolution: the padded grid serves only lags
        // within the window plus the displacement, which 8 table points per window bin resolve
        // (a table at the padded grid's bins made `analyze --scene` 4x slower, issue 18).
        // The pixel filter of an anti-aliased orthographic camera (a zoom below 1, e.g. render
        // --size at fewer pixels): the level blend of the kernel pyramid approximates it, exact
        // to the pyramid's 1 % rms for kernels left unfiltered (docs/scenes.md "Orthographic").
        const bool filters = scene.camera.type == CameraConfig::Type::Orthographic &&
                             scene.camera.antialiased();
        const LayerSpectrum ls = layer_spectrum(layer, zoom, std::max(w, h),
                                                layer_motion_blur(scene, li),
                                                filters ? scene.camera.filter : 0.0, spacing[li]);
        add_layer_spectrum(scene, ls, ls, R, zoom, g2, S);
    }
    return S;
}

/// A layer's field correlation in time over d frames: its envelopes' overlap (1 for still and
/// source layers, which only move).
double field_correlation(const Scene& scene, const LayerConfig& layer, size_t d) {
    const auto& p = layer.process;
    if (layer.source || !(p.lifetime_s > 0)) return 1.0;
    return envelope_correlation(p.envelope, p.lifetime_s, double(d) / scene.output.fps);
}

/// The Gaussian part of Cov(V_0, V_d) at lag index i of F: each layer's covariance scaled by
/// its field correlation and moved by its displacement (the quantisation noise, last component,
/// only at d = 0); a layer moved beyond the window plus the reach shares nothing.
double gaussian_lag(const kernels::WindowCovariance& wc, const Scene& scene, const FrameLags& F,
                    size_t i, int w, int h, int reach) {
    const size_t L = scene.layers.size(), d = F.lags[i];
    std::vector<double> weight(L + 1, d == 0 ? 1.0 : 0.0);
    std::vector<std::array<double, 2>> s(L + 1, {0.0, 0.0});
    for (size_t l = 0; l < L; ++l) {
        weight[l] = field_correlation(scene, scene.layers[l], d);
        s[l] = F.shift[l][i];
        if (std::abs(s[l][0]) >= w + reach || std::abs(s[l][1]) >= h + reach) weight[l] = 0.0;
    }
    return wc.gaussian_term(std::span<const double>(weight),
                            std::span<const std::array<double, 2>>(s));
}

/// Cov(V_t, V_{t+d}) of the frame variances at lags d = 0..n-1 (docs/stationarity.md): the
/// Gaussian part at the lags of F by WindowCovariance plus the population part of S, linear in
/// between. `gaussian0` receives the Gaussian part at d = 0, `frame_mean_var` Var(frame mean)
/// for a window the field does not wrap around (1/N^2 sum_ij C_ij).
std::vector<double> frame_variance_covariance(const LayerSums& S, const Scene& scene,
                                              const FrameLags& F, const AnalysisResult& R,
                                              double zoom, double& gaussian0,
                                              double& frame_mean_var) {
    const int w = R.width, h = R.height;
    kernels::WindowCovariance wc(w, h, S.padded_rows, S.padded_cols);
    for (const auto& grid : S.padded) wc.add(grid);
    wc.add(std::vector<double>(size_t(S.padded_rows) * S.padded_cols, S.quant));
    // Impulse layers and the quantisation noise (last) by the window's sum; source layers
    // (tiles, periodic) by their S(0) / N.
    std::vector<double> impulses = S.padded_impulses;
    impulses.push_back(1.0);
    frame_mean_var = wc.frame_mean_variance(impulses) + S.source_dc / (double(w) * h);
    const int reach = covariance_reach(scene, zoom);
    std::vector<double> at(F.lags.size());
    tbb::parallel_for(size_t(0), F.lags.size(), [&](size_t i) {
        at[i] = gaussian_lag(wc, scene, F, i, w, h, reach) + S.population_lags[i];
    });
    gaussian0 = at[0] - S.population_lags[0];
    const size_t n = size_t(std::max(R.frames, 1));
    std::vector<double> cov(n);
    for (size_t i = 0; i + 1 < F.lags.size(); ++i)
        for (size_t d = F.lags[i]; d < F.lags[i + 1]; ++d) {
            const double u = double(d - F.lags[i]) / double(F.lags[i + 1] - F.lags[i]);
            cov[d] = (1.0 - u) * at[i] + u * at[i + 1];
        }
    cov[n - 1] = at.back();
    return cov;
}

/// Var of the mean of n values whose covariance at lag l is cov[l].
double variance_of_mean(const std::vector<double>& cov) {
    const double n = double(cov.size());
    double v = cov[0];
    for (size_t l = 1; l < cov.size(); ++l) v += 2.0 * (1.0 - double(l) / n) * cov[l];
    return std::max(v, 0.0) / n;
}

/// Mean and variance against their sampling errors. Var(frame mean) = S(0) / N (the DC bin of
/// the aliased spectrum) holds only for frames periodic over the window (source layers' tiles);
/// `frame_mean_var` has the impulse layers' exact (1/N^2) sum_ij C_ij (docs/stationarity.md)
/// and the source layers' S(0) / N; the sample variance over N pixels has the Gaussian field's
/// 2 ||P C P||^2 / N^2 plus the fourth cumulant lambda E[a^4 w^4] int A(u)^2 du of shot noise
/// (kernels/window_variance.h; (int h^2)^2 / N for kernels small against the frame), and over the
/// frames the covariance of frame_variance_covariance.
void compare_one_point(TheoryComparison& T, const AnalysisResult& R, const Theory& th,
                       const LayerSums& S, const TimeCorrelation& tc, const DisplayEffects& d,
                       const std::vector<double>& cov, double gaussian, double frame_mean_var) {
    T.sd_frame_mean = std::sqrt(frame_mean_var);
    T.sd_mean = T.sd_frame_mean / std::sqrt(tc.n_eff_mean);
    T.mean = th.mean + (T.mapped ? std::sqrt(th.variance) * d.cens.mean : 0.0);
    T.frame_variance_gaussian = gaussian;
    T.frame_variance_population = S.population;
    T.frame_variance_covariance = cov;
    T.sd_frame_variance = std::sqrt(gaussian + S.population);
    T.sd_variance = std::sqrt(variance_of_mean(cov));
    const double field_var = T.mapped ? th.variance * d.cens.variance : th.variance;
    // E[pooled sample variance] = sigma^2 - Var(pooled mean).
    T.variance = field_var + d.quant - T.sd_mean * T.sd_mean;
    T.expected_frame_variance = field_var + d.quant - T.sd_frame_mean * T.sd_frame_mean;
    // Where the theory fixes a frame's mean exactly (S(0) = 0: a frame of whole fbm tiles at a
    // whole number of pixels per sample) the frame agrees to the rounding of its float values,
    // taken as 1e-6 of the sd (each value is rounded to 2^-24 of itself).
    const double rounding = 1e-6 * std::sqrt(th.variance);
    T.z_mean = T.sd_mean > 0 ? (R.moments.mean - T.mean) / T.sd_mean
                             : (std::abs(R.moments.mean - T.mean) <= rounding ? 0.0 : INFINITY);
    T.z_variance = T.sd_variance > 0 ? (R.moments.variance - T.variance) / T.sd_variance : INFINITY;
    T.mean_agrees = std::abs(T.z_mean) < analysis::kZLimit;
    T.variance_agrees = std::abs(T.z_variance) < analysis::kZLimit;
}

/// The radial spectrum against its annulus means, each judged with the Wilson–Hilferty z of a
/// mean of exponentials (independent pairs in the annulus, frames worth n_eff_spectrum) plus the
/// impulse population's common level c (shared by all bins).
analysis::SpectrumTheory compare_spectrum(LayerSums S, const AnalysisResult& R,
                                          const TimeCorrelation& tc) {
    const int w = R.width, h = R.height;
    const bool hann = R.periodogram.window == "hann";
    analysis::SpectrumTheory T;
    std::vector<double> grid = hann ? hann_smooth(std::move(S.grid), w, h) : std::move(S.grid);
    grid[0] = 0.0;
    std::vector<double> squares(grid.size());
    for (size_t i = 0; i < grid.size(); ++i) squares[i] = grid[i] * grid[i];
    T.power = annulus_means(std::move(grid), w, h);
    const std::vector<double> mean_square = annulus_means(std::move(squares), w, h);
    const auto& M = R.spectrum;
    const size_t na = M.power.size();
    T.ratio.assign(na, NAN);
    T.z.assign(na, NAN);
    T.common.assign(na, 0.0);
    const double infl = hann ? analysis::kHannInflation : 1.0;
    for (size_t b = 0; b < na; ++b) {
        if (M.count[b] == 0 || !(M.frequency[b] > 0 && M.frequency[b] < 0.5) || !(T.power[b] > 0))
            continue;
        double c = 0;
        for (size_t l = 0; l < S.layer_annuli.size(); ++l)
            c += S.c4[l] * S.layer_annuli[l][b] * S.layer_annuli[l][b];
        c /= T.power[b] * T.power[b];
        T.common[b] = c;
        // Independent pairs in the annulus, reduced where the expected power varies across it
        // (near the nulls between side lobes): a sum of exponentials with means S_i has the
        // variance of (sum S_i)^2 / sum S_i^2 equal ones.
        const double evenness = T.power[b] * T.power[b] / mean_square[b];
        const double pairs = 0.5 * double(M.count[b]) * evenness / infl;
        const double relvar = 1.0 / (pairs * tc.n_eff_spectrum) + c / tc.n_eff_population;
        T.ratio[b] = M.power[b] / T.power[b];
        T.z[b] = analysis::wilson_hilferty_z(T.ratio[b], 1.0 / relvar);
        T.max_abs_z = std::max(T.max_abs_z, std::abs(T.z[b]));
        ++T.compared;
    }
    T.threshold = analysis::bonferroni_threshold(T.compared, analysis::kFamilyAlpha);
    T.agrees = T.compared > 0 && T.max_abs_z < T.threshold;
    return T;
}

TheoryComparison compare_with_theory(const Scene& scene, const std::string& path,
                                     AnalysisResult& R, const TimeCorrelation& tc, bool mapped,
                                     double lo, double hi, double clipped) {
    TheoryComparison T;
    T.scene = path;
    T.hash = scene.hash;
    T.mapped = mapped;
    T.map_lo = lo, T.map_hi = hi;
    T.clipped_fraction = clipped;
    T.z_limit = analysis::kZLimit;
    const Theory th = blurred_scene_theory(scene);
    T.field_mean = th.mean;
    T.field_variance = th.variance;
    const bool zoom_constant = scene.camera.zoom.is_constant();
    T.zoom = scene.camera.zoom.value(0.0);
    if (!zoom_constant) T.no_spectrum = "camera zoom is animated";
    note_what_theory_misses(scene, R);

    const DisplayEffects d = display_effects(th, R.bits, mapped, lo, hi);
    const double g2 = d.cens.gain * d.cens.gain;
    const FrameLags F = frame_lags(scene, R, T.zoom);
    LayerSums S = sum_layers(scene, R, T.zoom, g2, d.quant, F);
    double gaussian = 0.0, frame_mean_var = 0.0;
    const std::vector<double> cov =
        frame_variance_covariance(S, scene, F, R, T.zoom, gaussian, frame_mean_var);
    compare_one_point(T, R, th, S, tc, d, cov, gaussian, frame_mean_var);
    if (zoom_constant) {
        // Autocovariance rings: Campbell's theorem with h * h~, less Var(frame mean) (every frame
        // is measured about its own mean), plus the white quantisation noise at lag 0.
        for (double& v : S.acov) v -= T.sd_frame_mean * T.sd_frame_mean;
        S.acov[0] += d.quant;
        T.autocovariance = S.acov;
        T.spectrum = compare_spectrum(std::move(S), R, tc);
        // Clipping at the ends of the display range is a nonlinearity: its distortion (odd
        // Hermite terms of the clip, Price's theorem) spreads power into the nulls and the high
        // frequencies, and for the heavier-than-Gaussian tails of sparse noise it is not known in
        // closed form. Judge the spectrum of a display input only when clipping is negligible.
        if (mapped && clipped > kMaxClippedForSpectrum) {
            T.spectrum->not_judged =
                format_number(100.0 * clipped, 3) + " % of the display values are clipped (more than " +
                format_number(100.0 * kMaxClippedForSpectrum, 3) +
                " %): the clip distorts the spectrum; widen output.range to compare";
            T.spectrum->agrees = false;
        }
    }
    if (S.diff_known) {
        if (S.any_animated) S.diff_var += 2.0 * d.quant;  // rounding errors of two frames
        T.diff_variance = S.diff_var;
    }
    return T;
}

/// A loaded scene's closed forms, as analysis::analyze_frames asks for them.
class SceneClosedForm final : public analysis::ClosedForm {
public:
    SceneClosedForm(Scene scene, std::string path) : m_scene(std::move(scene)), m_path(std::move(path)) {}

    std::vector<std::string> warnings() const override { return m_scene.warnings; }
    std::pair<double, double> display_range() const override {
        const output::ValueMapping m = Renderer(m_scene).mapping();
        return {m.lo, m.hi};
    }
    bool sum_of_layers() const override { return is_sum_of_layers(m_scene); }
    std::string not_covered() const override {
        for (size_t i = 0; i < m_scene.layers.size(); ++i) {
            const LayerConfig& l = m_scene.layers[i];
            if (!l.source || l.source->no_spectrum_reason().empty()) continue;
            return "layer[" + std::to_string(i) + "] (source \"" + std::string(l.source->kind()) +
                   "\"): " + l.source->no_spectrum_reason() +
                   ": the sampling errors of mean and variance need the spectrum, so no "
                   "comparison with theory (docs/scenes.md \"Analysis of source layers\")";
        }
        return "the scene composes its layers (blend, opacity, visible or warp, docs/scenes.md "
               "\"Composition\"): the theory here covers sums of layers, so no comparison with it; "
               "the display range still maps the values back";
    }
    bool keyframed() const override {
        bool k = false;
        for (const auto& l : m_scene.layers) k = k || l.keyframed();
        return k;
    }
    TimeCorrelation time_correlation(size_t n, size_t quarter) const override {
        return scene_time_correlation(m_scene, n, quarter);
    }
    TheoryComparison compare(AnalysisResult& R, const TimeCorrelation& tc, bool mapped, double lo,
                             double hi, double clipped) const override {
        return compare_with_theory(m_scene, m_path, R, tc, mapped, lo, hi, clipped);
    }

private:
    Scene m_scene;
    std::string m_path;
};

}  // namespace

std::unique_ptr<analysis::ClosedForm> closed_form(const std::string& scene,
                                                  const std::vector<std::string>& sets,
                                                  OutputSize size) {
    if (scene.empty()) return nullptr;
    const std::string path = resolve_scene(scene);
    return std::make_unique<SceneClosedForm>(load_scene(path, sets, size), path);
}

}  // namespace impulse::scenes
