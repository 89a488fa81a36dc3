// SPDX-License-Identifier: Apache-2.0
// Second-order statistics in the frequency domain: periodogram, averages over frames, radial
// profiles, and the autocovariance through the Wiener–Khinchine theorem. FFTW (double) does
// the transforms (numeric::RealFft2d); sums are in double in a fixed order, so results are deterministic.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "numeric/check.h"
#include "numeric/errors.h"
#include "numeric/fft.h"

namespace impulse::analysis {
namespace {

void check_image(const Image& image, const char* what) {
    if (image.width <= 0 || image.height <= 0) {
        throw ValueError(std::string(what) + ": image is " + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + ": must be non-empty");
    }
    const size_t n = static_cast<size_t>(image.width) * image.height;
    if (image.data.size() != n) {
        throw ValueError(std::string(what) + ": image data has " +
                         std::to_string(image.data.size()) + " values, expected " +
                         std::to_string(n) + " (" + std::to_string(image.width) + "x" +
                         std::to_string(image.height) + ")");
    }
}

double mean_of(const std::vector<float>& data) {
    double sum = 0.0;
    for (float v : data) sum += v;
    return sum / static_cast<double>(data.size());
}

// Signed FFT index: i <-> i for i < ceil(n/2), i - n otherwise (Periodogram::frequency * n).
int signed_index(int i, int n) { return i < (n + 1) / 2 ? i : i - n; }

// One axis of the window. Hann is used in its periodic ("DFT-even") form
// w(x) = 0.5 - 0.5 cos(2 pi x / n), x = 0..n-1 (the "DFT-even" form of Harris 1978, Proc. IEEE
// 66(1)): its DFT has exactly three taps (1/2, -1/4, -1/4), so the leakage it adds is confined
// to the neighbouring bins, and sum w^2 = 3n/8 for n >= 3. The 2-D window is the separable
// product w(x) w(y).
std::vector<double> window_weights(int n, Window window) {
    std::vector<double> w(static_cast<size_t>(n), 1.0);
    if (window == Window::Hann) {
        for (int x = 0; x < n; ++x) {
            w[static_cast<size_t>(x)] = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * x / n);
        }
    }
    return w;
}

double sum_of_squares(const std::vector<double>& w) {
    double s = 0.0;
    for (double v : w) s += v * v;
    return s;
}

}  // namespace

/// Periodogram of the mean-removed, windowed image; see analysis.h for the normalisation.
/// Deterministic; throws ValueError for an empty or inconsistent image, or a Hann window on an
/// axis of length 1 (the periodic Hann window of length 1 is identically zero).
Periodogram periodogram(const Image& image, Window window) {
    check_image(image, "periodogram");
    const int w = image.width, h = image.height;

    const std::vector<double> wx = window_weights(w, window);
    const std::vector<double> wy = window_weights(h, window);
    // Sum of w^2 over the 2-D window = (sum wx^2)(sum wy^2), separable. For white noise of
    // variance s2, E|F(k)|^2 = sum_x sum_x' w(x) w(x') E[g(x) g(x')] e^{...} = s2 sum_x w(x)^2,
    // so dividing by it gives E[power] = s2 = S(k); for a coloured field the same division gives
    // S convolved with the window's normalised spectral kernel (Percival & Walden 1993, ch. 6).
    // For Window::None it is exactly w*h.
    const double window_energy = sum_of_squares(wx) * sum_of_squares(wy);
    if (!(window_energy > 0.0)) {
        throw ValueError("periodogram: Hann window needs width and height >= 2, image is " +
                         std::to_string(w) + "x" + std::to_string(h));
    }

    numeric::RealFft2d fft(h, w, numeric::FftPlans::Forward);
    const double mean = mean_of(image.data);
    double* in = fft.real();
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            in[i] =
                (image.data[i] - mean) * (wx[static_cast<size_t>(x)] * wy[static_cast<size_t>(y)]);
        }
    }
    fft.forward();

    // The r2c output holds kx = 0..w/2; the rest follow from Hermitian symmetry of a real
    // input, F(kx, ky) = conj F(w - kx, h - ky), whose modulus is the same.
    Periodogram p;
    p.width = w;
    p.height = h;
    p.power.resize(static_cast<size_t>(w) * h);
    const std::complex<double>* spec = fft.spectrum();
    const int hw = fft.half_cols();
    for (int ky = 0; ky < h; ++ky) {
        for (int kx = 0; kx < w; ++kx) {
            const bool stored = kx < hw;
            const int sy = stored ? ky : (h - ky) % h;
            const int sx = stored ? kx : w - kx;
            const std::complex<double> c = spec[static_cast<size_t>(sy) * hw + sx];
            p.power[static_cast<size_t>(ky) * w + kx] =
                (c.real() * c.real() + c.imag() * c.imag()) / window_energy;
        }
    }
    // Without a window the DC term is rounding noise; with one it is sum w (f - mean), the
    // window's leakage of the mean rather than a property of the field. Either way: zero.
    p.power[0] = 0.0;
    return p;
}

/// Element-wise mean of periodograms of one size, summed in input order. Throws ValueError
/// for an empty list or mismatched sizes.
Periodogram average(std::span<const Periodogram> periodograms) {
    if (periodograms.empty()) throw ValueError("average: no periodograms");
    const Periodogram& first = periodograms.front();
    Periodogram mean;
    mean.width = first.width;
    mean.height = first.height;
    mean.power.assign(first.power.size(), 0.0);
    for (size_t j = 0; j < periodograms.size(); ++j) {
        // analyze_frames refuses frames of different sizes before any periodogram is taken
        IMPULSE_DCHECK(periodograms[j].width == first.width && periodograms[j].height == first.height &&
                       periodograms[j].power.size() == first.power.size());
        const Periodogram& p = periodograms[j];
        if (p.power.size() != static_cast<size_t>(p.width) * p.height) {
            throw ValueError("average: periodogram " + std::to_string(j) + " has " +
                             std::to_string(p.power.size()) + " values for " +
                             std::to_string(p.width) + "x" + std::to_string(p.height));
        }
        if (p.width != first.width || p.height != first.height) {
            throw ValueError("average: periodogram " + std::to_string(j) + " is " +
                             std::to_string(p.width) + "x" + std::to_string(p.height) +
                             ", expected " + std::to_string(first.width) + "x" +
                             std::to_string(first.height));
        }
        for (size_t i = 0; i < p.power.size(); ++i) mean.power[i] += p.power[i];
    }
    const double inv = 1.0 / static_cast<double>(periodograms.size());
    for (double& v : mean.power) v *= inv;
    return mean;
}

/// Radial profile with ceil(min(w,h)/2) annuli, index = annulus number b. The DC bin is left
/// out, so for a square image annulus 0 is empty: an empty annulus has count 0, power 0 and
/// frequency 0. Deterministic; throws ValueError for an inconsistent periodogram.
RadialProfile radial_average(const Periodogram& p) {
    const int w = p.width, h = p.height;
    if (w <= 0 || h <= 0 || p.power.size() != static_cast<size_t>(w) * h) {
        throw ValueError("radial_average: periodogram is " + std::to_string(w) + "x" +
                         std::to_string(h) + " with " + std::to_string(p.power.size()) + " values");
    }
    // Work in units of dk = 1/m: rho = |k| * m, annulus b = floor(rho), keep rho < m/2. Each
    // axis coordinate is an integer ratio (i*m/n), exact whenever it is an integer, so bins
    // lying exactly on an annulus boundary (axes; Pythagorean triples on square images) land
    // on the documented side of it.
    const int m = std::min(w, h);
    const int annuli = (m + 1) / 2;  // b * dk < 0.5  <=>  b < m/2
    const double nyquist = 0.5 * m;
    std::vector<double> sum_power(static_cast<size_t>(annuli), 0.0);
    std::vector<double> sum_rho(static_cast<size_t>(annuli), 0.0);
    std::vector<uint64_t> count(static_cast<size_t>(annuli), 0);
    for (int ky = 0; ky < h; ++ky) {
        const double t = static_cast<double>(int64_t{signed_index(ky, h)} * m) / h;
        for (int kx = 0; kx < w; ++kx) {
            if (kx == 0 && ky == 0) continue;
            const double s = static_cast<double>(int64_t{signed_index(kx, w)} * m) / w;
            const double rho = std::sqrt(s * s + t * t);
            if (rho >= nyquist) continue;
            const size_t b = static_cast<size_t>(rho);
            sum_power[b] += p.power[static_cast<size_t>(ky) * w + kx];
            sum_rho[b] += rho;
            ++count[b];
        }
    }
    RadialProfile r;
    r.frequency.assign(static_cast<size_t>(annuli), 0.0);
    r.power.assign(static_cast<size_t>(annuli), 0.0);
    r.count = count;
    for (size_t b = 0; b < static_cast<size_t>(annuli); ++b) {
        if (count[b] == 0) continue;
        const double c = static_cast<double>(count[b]);
        r.power[b] = sum_power[b] / c;
        r.frequency[b] = sum_rho[b] / c / m;
    }
    return r;
}

/// Circular sample autocovariance (population normalisation) of the mean-removed image.
/// Deterministic; throws ValueError for an empty or inconsistent image.
std::vector<double> autocovariance(const Image& image) {
    check_image(image, "autocovariance");
    const int w = image.width, h = image.height;
    const size_t n = static_cast<size_t>(w) * h;

    numeric::RealFft2d fft(h, w, numeric::FftPlans::Both);
    const double mean = mean_of(image.data);
    double* in = fft.real();
    for (size_t i = 0; i < n; ++i) in[i] = image.data[i] - mean;
    fft.forward();

    // Wiener–Khinchine on the torus: IDFT(|F|^2)(tau) = n * sum_x g(x) g(x + tau) for the
    // unnormalised transforms, so acov = IDFT(|F|^2) / n^2 is (1/n) sum_x g(x) g(x + tau).
    // |F|^2 is real and even, so the c2r inverse of the half spectrum is exact. Zeroing the DC
    // term removes the rounding residue of the mean.
    std::complex<double>* spec = fft.spectrum();
    const size_t half = static_cast<size_t>(fft.half_cols()) * h;
    for (size_t i = 0; i < half; ++i)
        spec[i] = {spec[i].real() * spec[i].real() + spec[i].imag() * spec[i].imag(), 0.0};
    spec[0] = 0.0;
    fft.inverse();

    const double inv = 1.0 / (static_cast<double>(n) * static_cast<double>(n));
    std::vector<double> acov(n);
    for (size_t i = 0; i < n; ++i) acov[i] = in[i] * inv;
    return acov;
}

/// Ring means r = 0..max_lag of an autocovariance in FFT lag ordering. max_lag must be in
/// [0, min(width,height)/2]: beyond that rings are cut by the torus and mix lag t with n - t.
/// Deterministic; throws ValueError otherwise or for a size mismatch.
std::vector<double> radial_autocovariance(const std::vector<double>& acov, int width, int height,
                                          int max_lag) {
    if (width <= 0 || height <= 0 || acov.size() != static_cast<size_t>(width) * height) {
        throw ValueError("radial_autocovariance: " + std::to_string(acov.size()) +
                         " values for a " + std::to_string(width) + "x" + std::to_string(height) +
                         " image");
    }
    const int limit = std::min(width, height) / 2;
    if (max_lag < 0 || max_lag > limit) {
        throw ValueError("radial_autocovariance: max_lag = " + std::to_string(max_lag) +
                         ": must be in [0, " + std::to_string(limit) + "]");
    }
    std::vector<double> sum(static_cast<size_t>(max_lag) + 1, 0.0);
    std::vector<uint64_t> count(sum.size(), 0);
    for (int y = 0; y < height; ++y) {
        const int dy = signed_index(y, height);
        if (std::abs(dy) > max_lag) continue;  // round(|tau|) >= |dy|
        for (int x = 0; x < width; ++x) {
            const int dx = signed_index(x, width);
            if (std::abs(dx) > max_lag) continue;
            // |tau| = sqrt(integer) is never exactly half-integer, so round() has no ties.
            const long r = std::lround(std::sqrt(static_cast<double>(dx * dx + dy * dy)));
            if (r > max_lag) continue;
            sum[static_cast<size_t>(r)] += acov[static_cast<size_t>(y) * width + x];
            ++count[static_cast<size_t>(r)];
        }
    }
    // Every ring r <= min(w,h)/2 holds at least the axial lag (r, 0) or (-r, 0): count > 0.
    for (size_t r = 0; r < sum.size(); ++r) sum[r] /= static_cast<double>(count[r]);
    return sum;
}

}  // namespace impulse::analysis
