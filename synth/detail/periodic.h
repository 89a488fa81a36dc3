// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to impulse::synth: the machinery every method shares — a periodic stationary
// Gaussian random field (PSGRF, Kaplan & Kuo §III) drawn by scaling white noise by the square
// root of its power spectrum and inverting the DFT, and the DFT of an even-symmetric correlation
// (their eqs. 12-13) by a DCT-I of its quarter.

#include <complex>
#include <functional>
#include <cstdint>
#include <vector>

#include "numeric/fft.h"

namespace impulse::synth::detail {

/// Stream tags of the counter RNG (xored into the key): one per independent white noise.
inline constexpr uint32_t kStreamField = 0x46424D31u;  ///< W, phi of the 2-D field (step 1)
inline constexpr uint32_t kStreamAxisX = 0x46424D58u;  ///< W_x, phi_x (step 7)
inline constexpr uint32_t kStreamAxisY = 0x46424D59u;  ///< W_y, phi_y (step 7)
inline constexpr uint32_t kStreamPlane = 0x46424D50u;  ///< X1, X2 of Stein's random plane

/// Smallest even n' >= n whose prime factors are 2, 3, 5, 7 (FFTW's fast sizes).
int fast_size(int n);

/// In place: q holds the quarter h x h (h = n/2 + 1, row-major) of an n x n array that is even
/// in both axes (Kaplan & Kuo eqs. 12-13); on return its 2-D DFT (real by symmetry) at
/// frequencies (k_x, k_y), k in [0, n/2]. A DCT-I (FFTW_REDFT00) per axis: exactly the DFT of the
/// symmetric extension (eq. 15).
void symmetric_dft_2d(std::vector<double>& q, int h);
/// The same in 1-D: v holds m in [0, n/2] of an even length-n sequence.
void symmetric_dft_1d(std::vector<double>& v);

/// A standard complex normal (E|z|^2 = 1, independent real and imaginary parts of variance 1/2)
/// keyed by (seed, stream, a, b); `real_only`: a real N(0, 1) (self-conjugate frequencies).
std::complex<double> complex_normal(uint64_t seed, uint32_t stream, int64_t a, int64_t b,
                                    bool real_only);

/// An n x n real field and its half spectrum in one float buffer (FFTW's in-place c2r layout:
/// rows k_y in [0, n), n/2 + 1 complex values k_x in [0, n/2] each; after `inverse`, real rows
/// of stride 2 (n/2 + 1) floats).
class PeriodicField {
public:
    /// `rows`: how many rows m_y in [0, rows) `inverse` must produce (the rest is left
    /// undefined): the transform along x is skipped for the others (Kaplan & Kuo keep M of N
    /// rows, Stein's embedding N of G).
    PeriodicField(int n, int rows);
    PeriodicField(const PeriodicField&) = delete;
    PeriodicField& operator=(const PeriodicField&) = delete;

    int n() const { return m_fft.n(); }
    int half() const { return m_fft.half(); }
    std::complex<float>* row(int ky) { return m_fft.spectrum() + size_t(ky) * half(); }
    const std::complex<float>* row(int ky) const { return m_fft.spectrum() + size_t(ky) * half(); }
    /// Bytes of the buffer for side n.
    static double bytes(int n) { return numeric::InverseFft2dFloat::bytes(n); }

    /// Kaplan & Kuo steps 1 and 5: X(k) = amp(k') z(k) with z standard complex normals keyed by
    /// (seed, stream, k), Hermitian (z(n - k) = conj z(k); real at the four self-conjugate
    /// frequencies, their phi = 0), amp the (n/2+1)^2 quarter table at the folded frequency
    /// k' = min(k, n - k) per axis; with quarter = false amp is the whole half spectrum's table,
    /// n rows k_y of n/2 + 1 (a density even only under k -> -k, e.g. an oriented kernel's).
    void fill(const std::vector<float>& amp, uint64_t seed, uint32_t stream, bool quarter = true);
    /// In place: X -> x(m) = sum_k X(k) e^{+2 pi i k.m / n} (unnormalised inverse DFT, eq. 16)
    /// for m_y < rows: complex transforms along y for every k_x, then c2r along x row by row.
    void inverse() { m_fft.inverse(); }
    /// x(m_x, m_y) after `inverse`.
    float at(int mx, int my) const { return m_fft.real()[size_t(my) * 2 * half() + mx]; }

private:
    numeric::InverseFft2dFloat m_fft;
};

/// The periodic field with amplitude table `amp` (see fill), cropped to its top-left size^2.
/// Peak memory: PeriodicField::bytes(n) + the output.
std::vector<float> periodic_crop(int n, const std::vector<float>& amp, uint64_t seed, int size,
                                 bool quarter = true);

/// x(m) = sum_{k=0}^{n-1} X(k) e^{+2 pi i k m / n} for m in [0, count) of a Hermitian X given
/// by X(0..n/2) (eqs. 19-20).
std::vector<double> inverse_real_1d(const std::vector<std::complex<double>>& half, int n,
                                    int count);

/// Runs body(begin, end) over [0, count) in blocks of `grain` (TBB; each index in one block, the
/// block boundaries fixed, so per-block partial sums combined in order are thread-count free).
void parallel_blocks(int count, int grain, const std::function<void(int, int)>& body);

}  // namespace impulse::synth::detail
