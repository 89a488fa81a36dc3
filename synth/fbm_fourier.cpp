// SPDX-License-Identifier: Apache-2.0
// Standard Fourier synthesis (Kaplan & Kuo 1996 §III): white noise scaled by the square root of
// R^(k) = C / |k|^{2H+2} (eq. 14), inverse DFT. The field is a periodic stationary Gaussian
// random field (PSGRF), not fBm: its structure function saturates at the period and its
// generalised Hurst exponent H(s) (eq. 21) drifts with the scale s (their Fig. 3). As the paper
// says is usual, the field is drawn on a 2N x 2N torus and its first N x N values kept; the
// seamless variant keeps the N x N torus itself.

#include <cmath>

#include "synth/detail/fbm.h"
#include "synth/detail/periodic.h"

namespace impulse::synth {
namespace detail {
namespace {

// Weight of the quarter entry k (k in [0, n/2]) in a sum over the whole n-periodic axis.
double fold_weight(int k, int n) { return (k == 0 || 2 * k == n) ? 1.0 : 2.0; }

// R^(k) of eq. 14 with C = 1 at the quarter entry (k_x, k_y).
double fbm_spectrum(int kx, int ky, double hurst) {
    const double k2 = double(kx) * kx + double(ky) * ky;
    return k2 > 0 ? std::pow(k2, -(hurst + 1.0)) : 0.0;
}

// sqrt(R^(k)) / n on the quarter (n/2+1)^2, C chosen so that sigma^2 = VAR[B(m+e_x) - B(m)] =
// 2 (R(0,0) - R(1,0)) = (2/n^2) sum_k R^(k) (1 - cos(2 pi k_x / n)) = 1 (eq. 2 with f(1,0) = 1).
std::vector<float> fbm_amplitudes(int n, double hurst) {
    const int h = n / 2 + 1;
    std::vector<double> spectrum(size_t(h) * h);
    const int grain = 64;
    std::vector<double> partial((h + grain - 1) / grain, 0.0), step(h);
    for (int kx = 0; kx < h; ++kx) step[kx] = 1.0 - std::cos(2.0 * M_PI * kx / n);
    parallel_blocks(h, grain, [&](int y0, int y1) {
        double sum = 0.0;
        for (int ky = y0; ky < y1; ++ky)
            for (int kx = 0; kx < h; ++kx) {
                const double s = fbm_spectrum(kx, ky, hurst);
                spectrum[size_t(ky) * h + kx] = s;
                sum += fold_weight(kx, n) * fold_weight(ky, n) * s * step[kx];
            }
        partial[y0 / grain] = sum;
    });
    double sigma2 = 0.0;
    for (double p : partial) sigma2 += p;  // fixed order: thread-count free
    sigma2 *= 2.0 / (double(n) * n);
    std::vector<float> amp(spectrum.size());
    for (size_t i = 0; i < amp.size(); ++i) amp[i] = float(std::sqrt(spectrum[i] / sigma2) / n);
    return amp;
}

class FourierFbm : public FbmSynth::Impl {
public:
    explicit FourierFbm(const FbmOptions& o)
        : m_size(o.size), m_n(o.seamless ? o.size : 2 * o.size),
          m_amp(fbm_amplitudes(m_n, o.hurst)) {}
    Surface realize(uint64_t seed) const override {
        return {m_size, m_size, periodic_crop(m_n, m_amp, seed, m_size)};
    }
    int fft_size() const override { return m_n; }

private:
    int m_size, m_n;
    std::vector<float> m_amp;
};

}  // namespace

std::unique_ptr<FbmSynth::Impl> make_fourier(const FbmOptions& options) {
    return std::make_unique<FourierFbm>(options);
}

double fourier_bytes(const FbmOptions& o) {
    const double n = o.seamless ? o.size : 2.0 * o.size, h = n / 2 + 1;
    return std::max(12.0 * h * h, PeriodicField::bytes(int(n)) + 4.0 * h * h) +
           4.0 * o.size * o.size;
}

}  // namespace detail

std::vector<double> fourier_fbm_structure(const FbmOptions& o, const std::vector<int>& lags) {
    // 2 (R(0,0) - R(d,0)) = (2/n^2) sum_k R^(k) (1 - cos(2 pi k_x d / n)), normalised by d = 1.
    const int n = o.seamless ? o.size : 2 * o.size, h = n / 2 + 1;
    std::vector<double> sums(lags.size() + 1, 0.0);
    for (int ky = 0; ky < h; ++ky)
        for (int kx = 0; kx < h; ++kx) {
            const double w = detail::fold_weight(kx, n) * detail::fold_weight(ky, n) *
                             detail::fbm_spectrum(kx, ky, o.hurst);
            sums[0] += w * (1.0 - std::cos(2.0 * M_PI * kx / n));
            for (size_t i = 0; i < lags.size(); ++i)
                sums[i + 1] += w * (1.0 - std::cos(2.0 * M_PI * kx * double(lags[i]) / n));
        }
    std::vector<double> f(lags.size());
    for (size_t i = 0; i < lags.size(); ++i) f[i] = sums[i + 1] / sums[0];
    return f;
}

double fourier_fbm_variance(const FbmOptions& o) {
    // R(0) = (1/n^2) sum_k R^(k) and sigma^2 = (2/n^2) sum_k R^(k) (1 - cos(2 pi k_x / n)) = 1.
    const int n = o.seamless ? o.size : 2 * o.size, h = n / 2 + 1;
    double all = 0.0, step = 0.0;
    for (int ky = 0; ky < h; ++ky)
        for (int kx = 0; kx < h; ++kx) {
            const double w = detail::fold_weight(kx, n) * detail::fold_weight(ky, n) *
                             detail::fbm_spectrum(kx, ky, o.hurst);
            all += w;
            step += w * (1.0 - std::cos(2.0 * M_PI * kx / n));
        }
    return all / (2.0 * step);
}

Surface fourier_synthesis(int n, const std::function<double(double, double)>& density,
                        uint64_t seed) {
    const int h = n / 2 + 1;
    std::vector<float> amp(size_t(n) * h);  // the whole half spectrum: density even in k only
    detail::parallel_blocks(n, 64, [&](int y0, int y1) {
        for (int ky = y0; ky < y1; ++ky) {
            const double fy = double(2 * ky < n ? ky : ky - n) / n;
            for (int kx = 0; kx < h; ++kx) {
                const double s = (kx == 0 && ky == 0) ? 0.0 : density(double(kx) / n, fy);
                amp[size_t(ky) * h + kx] = float(std::sqrt(std::max(s, 0.0)) / n);
            }
        }
    });
    return {n, n, detail::periodic_crop(n, amp, seed, n, false)};
}

}  // namespace impulse::synth
