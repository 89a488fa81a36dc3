// SPDX-License-Identifier: Apache-2.0
// Exact 2-D fBm by Stein's (2002) intrinsic circulant embedding. The fBm variogram
// 2 r^alpha (alpha = 2H) is not a covariance, but c(r) = c0 - r^alpha + c2 r^2 for r <= 1,
// extended smoothly to 0 at r = R, is a positive definite covariance on the plane for the
// (c0, c2, beta, R) below. A stationary field Z with covariance c has, for |x - y| <= 1,
// VAR[Z(x) - Z(y)] = 2 (r^alpha - c2 r^2); adding the independent random plane
// sqrt(2 c2) (X1 x + X2 y) restores 2 r^alpha, and anchoring at the origin gives B(0) = 0.
// Z is drawn exactly by circulant embedding (a periodic field whose DFT eigenvalues are >= 0).
// Derivation and the grid geometry: docs/fbm.md.

#include <cmath>
#include <string>

#include "synth/detail/fbm.h"
#include "synth/detail/periodic.h"
#include "numeric/errors.h"

namespace impulse::synth {
namespace detail {
namespace {

// Stein (2002): R = 1 for alpha <= 3/2, R = 2 above; beta makes c twice differentiable at r = 1.
struct SteinCovariance {
    double alpha = 1, R = 1, beta = 0, c0 = 0, c2 = 0;
    explicit SteinCovariance(double hurst) : alpha(2.0 * hurst) {
        if (alpha <= 1.5) {
            R = 1.0, beta = 0.0, c2 = alpha / 2.0, c0 = 1.0 - alpha / 2.0;
        } else {
            R = 2.0;
            beta = alpha * (2.0 - alpha) / (3.0 * R * (R * R - 1.0));
            c2 = (alpha - beta * (R - 1.0) * (R - 1.0) * (R + 2.0)) / 2.0;
            c0 = beta * (R - 1.0) * (R - 1.0) * (R - 1.0) + 1.0 - c2;
        }
    }
    double operator()(double r2) const {  // c at r = sqrt(r2)
        if (r2 <= 1.0) return c0 - std::pow(r2, alpha / 2.0) + c2 * r2;
        const double r = std::sqrt(r2);
        return r < R ? beta * (R - r) * (R - r) * (R - r) / r : 0.0;
    }
};

// Pixel spacing h (in c's units) and torus side G: every lag between the N x N pixels and the
// origin is <= (N-1) sqrt(2) pixels, so h = 1 / (sqrt(2) (N-1)) keeps them all where c has the
// intrinsic form (r <= 1). The periodic copies of c must not reach a lag of the output: their
// lags d + G e have |d_i + G| >= G - (N-1), so G h >= R + (N-1) h.
double pixel_spacing(int size) { return 1.0 / (std::sqrt(2.0) * (size - 1)); }

class ExactFbm : public FbmSynth::Impl {
public:
    explicit ExactFbm(const FbmOptions& o)
        : m_size(o.size), m_c(o.hurst), m_h(pixel_spacing(o.size)),
          m_G(exact_grid(o.size, o.hurst)), m_amp(eigenvalues()) {}

    Surface realize(uint64_t seed) const override {
        PeriodicField field(m_G, m_size);
        field.fill(m_amp, seed, kStreamField);
        field.inverse();
        // The random plane's X1, X2: real and imaginary parts of one complex normal, each
        // N(0, 1/2) there.
        const std::complex<double> x = complex_normal(seed, kStreamPlane, 0, 0, false);
        const double plane = std::sqrt(2.0 * m_c.c2) * m_h * std::sqrt(2.0);
        const double px = plane * x.real(), py = plane * x.imag();
        // sigma^2 = 1: VAR[Y(x + h e) - Y(x)] = 2 h^alpha.
        const double scale = 1.0 / std::sqrt(2.0 * std::pow(m_h, m_c.alpha));
        const double z0 = field.at(0, 0);
        Surface out{m_size, m_size, std::vector<float>(size_t(m_size) * m_size)};
        parallel_blocks(m_size, 64, [&](int y0, int y1) {
            for (int my = y0; my < y1; ++my)
                for (int mx = 0; mx < m_size; ++mx)
                    out.data[size_t(my) * m_size + mx] =
                        float(scale * (field.at(mx, my) - z0 + px * mx + py * my));
        });
        return out;
    }
    int fft_size() const override { return m_G; }

private:
    // sqrt(lambda(k)) / G on the quarter: lambda the DFT of the periodised c on the torus.
    std::vector<float> eigenvalues() const {
        const int G = m_G, hq = G / 2 + 1;
        std::vector<double> q(size_t(hq) * hq);
        const double h2 = m_h * m_h, reach2 = m_c.R * m_c.R / h2;
        parallel_blocks(hq, 16, [&](int j0, int j1) {
            for (int j = j0; j < j1; ++j)
                for (int i = 0; i <= j; ++i) {
                    // c_P(i, j) = sum over the images (i or i - G, j or j - G) within reach.
                    double s = 0.0;
                    for (double a : {double(i), double(G - i)})
                        for (double b : {double(j), double(G - j)}) {
                            const double d2 = a * a + b * b;
                            if (d2 < reach2) s += m_c(d2 * h2);
                        }
                    q[size_t(j) * hq + i] = q[size_t(i) * hq + j] = s;
                }
        });
        symmetric_dft_2d(q, hq);
        double top = 0.0, low = 0.0;
        for (double v : q) top = std::max(top, v), low = std::min(low, v);
        // Stein proves lambda >= 0; what is left is the DCT's rounding.
        if (low < -1e-9 * top)
            throw Error("synth: circulant embedding is not positive definite (min eigenvalue " +
                        std::to_string(low / top) + " of the largest)");
        std::vector<float> amp(q.size());
        for (size_t k = 0; k < q.size(); ++k) amp[k] = float(std::sqrt(std::max(q[k], 0.0)) / G);
        return amp;
    }

    int m_size;
    SteinCovariance m_c;
    double m_h;
    int m_G;
    std::vector<float> m_amp;
};

}  // namespace

int exact_grid(int size, double hurst) {
    const SteinCovariance c(hurst);
    const double h = pixel_spacing(size);
    return fast_size(int(std::ceil((c.R + (size - 1) * h) / h)));
}

std::unique_ptr<FbmSynth::Impl> make_exact(const FbmOptions& options) {
    return std::make_unique<ExactFbm>(options);
}

double exact_bytes(const FbmOptions& o) {
    const double G = exact_grid(o.size, o.hurst), hq = G / 2 + 1;
    const double build = 12.0 * hq * hq;
    const double run = PeriodicField::bytes(int(G)) + 4.0 * hq * hq + 4.0 * o.size * o.size;
    return std::max(build, run);
}

}  // namespace detail
}  // namespace impulse::synth
