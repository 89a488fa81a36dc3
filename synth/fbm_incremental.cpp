// SPDX-License-Identifier: Apache-2.0
// Incremental Fourier synthesis (Kaplan & Kuo 1996 §IV): the stationary second-order increments
// I_2 of fBm are drawn as an N x N periodic field (N = 2M) whose correlation matches eq. 8 over
// [-M, M]^2, the first-order increments along the two image edges from the same DFT
// coefficients (so that eq. 5 holds and nothing creases), and the increments summed into
// B(m_x, m_y) for m in [0, M]^2 (step 13). M = the output size: the (M+1)^2 samples are cropped
// to M x M. Step numbers below are the paper's; docs/fbm.md lists them with the typos fixed.

#include <cmath>
#include <complex>

#include "synth/detail/fbm.h"
#include "synth/detail/periodic.h"

namespace impulse::synth {
namespace detail {
namespace {

using cd = std::complex<double>;

// Steps 2-4 and 8-10: the spectra, computed once per (M, f~).
struct IncrementSpectra {
    std::vector<float> amp2;   ///< sqrt(S^_2(k_x, k_y)) / N on the quarter (M+1)^2 (step 4)
    std::vector<double> ampx;  ///< sqrt(S^_x(k_x, 0)) / N = sqrt(S^_y(0, k_y)) / N, k in [0, M]
};

// f(m_x, m_y) = f~(|m|) on one row m_y, m_x in [0, M+1] (eq. 3 or any f~, §VI).
void structure_row(const std::function<double(double)>& ft, int my, std::vector<double>& row) {
    for (size_t mx = 0; mx < row.size(); ++mx)
        row[mx] = ft(std::sqrt(double(mx) * double(mx) + double(my) * double(my)));
}

IncrementSpectra increment_spectra(int M, const std::function<double(double)>& ft) {
    const int h = M + 1, N = 2 * M;
    // Step 2: R_2 by eq. 8 (sigma^2 = 1) on [0, M]^2, its even extension implied (eqs. 12-13).
    // Step 8: R_x by eq. 6, summed over m_y of the extension (the inner sum of eq. 17).
    std::vector<double> r2(size_t(h) * h);
    const int grain = 32;
    std::vector<std::vector<double>> sx_part((h + grain - 1) / grain);
    parallel_blocks(h, grain, [&](int y0, int y1) {
        std::vector<double> fm(h + 1), f0(h + 1), fp(h + 1), sx(h, 0.0);
        structure_row(ft, std::abs(y0 - 1), fm);
        structure_row(ft, y0, f0);
        for (int my = y0; my < y1; ++my) {
            structure_row(ft, my + 1, fp);
            const double w = (my == 0 || my == M) ? 1.0 : 2.0;  // row weight in the extension
            for (int mx = 0; mx < h; ++mx) {
                const int l = std::abs(mx - 1), r = mx + 1;
                // Kaplan & Kuo eq. 8
                r2[size_t(my) * h + mx] =
                    0.5 * (2.0 * (f0[r] + f0[l] + fp[mx] + fm[mx]) -
                           (fp[r] + fm[r] + fp[l] + fm[l]) - 4.0 * f0[mx]);
                sx[mx] += w * 0.5 * (f0[r] + f0[l] - 2.0 * f0[mx]);  // Kaplan & Kuo eq. 6
            }
            std::swap(fm, f0);
            std::swap(f0, fp);
        }
        sx_part[y0 / grain] = std::move(sx);
    });
    // Step 3: R^_2 (eq. 15); step 4: S^_2 = 0 on the axes and where R^_2 < 0 (Gibbs).
    symmetric_dft_2d(r2, h);
    IncrementSpectra s;
    s.amp2.resize(r2.size());
    for (int ky = 0; ky < h; ++ky)
        for (int kx = 0; kx < h; ++kx) {
            const double v = r2[size_t(ky) * h + kx];
            const bool axis = kx == 0 || ky == 0;
            s.amp2[size_t(ky) * h + kx] = axis || v < 0 ? 0.0f : float(std::sqrt(v) / N);
        }
    // Step 9: R^_x(k_x, 0) (eq. 17; eq. 18's R^_y(0, k) is the same by the symmetry of f in
    // m_x <-> m_y); step 10: negative values clipped.
    std::vector<double> sx(h, 0.0);
    for (const auto& part : sx_part)  // fixed order: thread-count free
        for (int mx = 0; mx < h; ++mx) sx[mx] += part[mx];
    symmetric_dft_1d(sx);
    s.ampx.resize(h);
    for (int k = 0; k < h; ++k) s.ampx[k] = sx[k] < 0 ? 0.0 : std::sqrt(sx[k]) / N;
    return s;
}

// -j e^{-j pi k / N} / (2 sin(pi k / N)): the factor that turns I^_2 into I^_x (at k = k_y) or
// I^_y (at k = k_x) in step 11 — the DFT of eq. 5, I_2(m) = I_x(m_x, m_y + 1) - I_x(m).
cd increment_factor(int k, int N) {
    const double t = M_PI * k / N;
    return cd(0.0, -1.0) * std::polar(1.0, -t) / (2.0 * std::sin(t));
}

// Steps 7 and 11-12 up to the 1-D DFT: C_x(k_x) = sum_{k_y} I^_x(k_x, k_y) for k_x in [0, M]
// and C_y(k_y) = sum_{k_x} I^_y(k_x, k_y) for k_y in [0, M] (I^ divided by N^2, as the field's
// coefficients are), from I^_2 still in `field` and the axis noise W_x, W_y.
struct EdgeSums {
    std::vector<cd> cx, cy;
};

EdgeSums edge_sums(const PeriodicField& field, const std::vector<double>& ampx, uint64_t seed) {
    const int N = field.n(), h = field.half();
    std::vector<cd> gx(N);  // the factor at k_y (or k_x), k in [1, N-1]
    for (int k = 1; k < N; ++k) gx[k] = increment_factor(k, N);
    // Row sums over k_x in [1, N/2] (A) for I^_y; per-block column sums over k_y (C_x).
    std::vector<cd> a(N), b(N);
    const int grain = 64;
    std::vector<std::vector<cd>> cx_part((N + grain - 1) / grain);
    parallel_blocks(N, grain, [&](int y0, int y1) {
        std::vector<cd> cx(h, cd(0.0));
        for (int ky = y0; ky < y1; ++ky) {
            const std::complex<float>* x2 = field.row(ky);
            cd sum(0.0);
            for (int kx = 1; kx < h; ++kx) sum += gx[kx] * cd(x2[kx]);
            a[ky] = sum;
            b[ky] = sum - gx[h - 1] * cd(x2[h - 1]);  // k_x in [1, N/2 - 1]
            if (ky == 0) continue;
            for (int kx = 0; kx < h; ++kx) cx[kx] += gx[ky] * cd(x2[kx]);
        }
        cx_part[y0 / grain] = std::move(cx);
    });
    EdgeSums e;
    e.cx.assign(h, cd(0.0));
    e.cy.assign(h, cd(0.0));
    for (const auto& part : cx_part)
        for (int kx = 0; kx < h; ++kx) e.cx[kx] += part[kx];
    for (int k = 0; k < h; ++k) {
        const bool real = k == 0 || k == h - 1;  // step 7: phi_x(0) = phi_x(N/2) = 0
        // Step 11 at k_y = 0 (the paper's S^_x(0, 0) there means S^_x(k_x, 0)).
        e.cx[k] += ampx[k] * complex_normal(seed, kStreamAxisX, k, 0, real);
        // I^_y(k_x, k_y) for k_x > N/2 is conj I^_y(N - k_x, N - k_y): those columns add
        // conj B(N - k_y).
        e.cy[k] = ampx[k] * complex_normal(seed, kStreamAxisY, k, 0, real) + a[k] +
                  std::conj(b[(N - k) % N]);
    }
    return e;
}

class IncrementalFbm : public FbmSynth::Impl {
public:
    IncrementalFbm(int size, const std::function<double(double)>& ft)
        : m_M(size), m_spectra(increment_spectra(size, ft)) {}

    Surface realize(uint64_t seed) const override {
        const int M = m_M, N = 2 * M;
        PeriodicField field(N, M);
        field.fill(m_spectra.amp2, seed, kStreamField);  // steps 1 and 5
        const EdgeSums e = edge_sums(field, m_spectra.ampx, seed);
        field.inverse();  // step 6, eq. 16
        // Step 12: eqs. 19-20 (the sums run with e^{+j...}, the inverse DFT, as in eq. 16; eq.
        // 20's I^_x means I^_y).
        const std::vector<double> ix = inverse_real_1d(e.cx, N, M);
        const std::vector<double> iy = inverse_real_1d(e.cy, N, M);
        return sum_increments(field, ix, iy);
    }
    int fft_size() const override { return 2 * m_M; }

private:
    // Step 13, in double: B(0, 0) = 0; the edges from I_x, I_y; the inside from eq. 5,
    // B(m_x, m_y) = B(m_x, m_y - 1) + I_y(m_x, m_y - 1) with
    // I_y(m_x, m) = I_y(0, m) + sum_{i < m_x} I_2(i, m). Cropped to M x M.
    Surface sum_increments(const PeriodicField& field, const std::vector<double>& ix,
                         const std::vector<double>& iy) const {
        const int M = m_M;
        Surface out{M, M, std::vector<float>(size_t(M) * M)};
        std::vector<double> b(M, 0.0);
        for (int mx = 1; mx < M; ++mx) b[mx] = b[mx - 1] + ix[mx - 1];
        for (int mx = 0; mx < M; ++mx) out.data[mx] = float(b[mx]);
        for (int my = 1; my < M; ++my) {
            double iy_run = iy[my - 1];
            b[0] += iy_run;
            for (int mx = 1; mx < M; ++mx) {
                iy_run += field.at(mx - 1, my - 1);
                b[mx] += iy_run;
            }
            float* row = out.data.data() + size_t(my) * M;
            for (int mx = 0; mx < M; ++mx) row[mx] = float(b[mx]);
        }
        return out;
    }

    int m_M;
    IncrementSpectra m_spectra;
};

}  // namespace

std::unique_ptr<FbmSynth::Impl> make_incremental(int size,
                                                 const std::function<double(double)>& ft) {
    return std::make_unique<IncrementalFbm>(size, ft);
}

double incremental_bytes(int size) {
    const double h = size + 1.0;
    const double build = 12.0 * h * h;  // R_2 in double, then the float amplitudes
    const double run = PeriodicField::bytes(2 * size) + 4.0 * h * h + 4.0 * size * size;
    return std::max(build, run);
}

}  // namespace detail
}  // namespace impulse::synth
