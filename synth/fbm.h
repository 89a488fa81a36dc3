// SPDX-License-Identifier: Apache-2.0
#pragma once
// Fractional Brownian surfaces (2-D fBm) on a grid, three ways (part of impulse::synth):
//   Fourier      standard Fourier synthesis of C / |k|^{2H+2} (Kaplan & Kuo 1996 eq. 14): a
//                stationary, periodic field — not fBm; its H(s) drifts with scale (their Fig. 3);
//   Incremental  Kaplan & Kuo's incremental Fourier synthesis (§IV, 13 steps): the stationary
//                second-order increments by Fourier synthesis, summed; nearly exact fBm;
//   Exact        Stein's (2002) intrinsic circulant embedding: exact fBm (up to float rounding).
// Every field is normalised to sigma^2 = VAR[B(m_x + 1, m_y) - B(m_x, m_y)] = 1 (Kaplan & Kuo
// eq. 2), pixel spacing 1, B(0, 0) = 0 at the top-left pixel (Incremental, Exact). The
// derivations are in docs/fbm.md. Deterministic: a pure function of (options, seed), whatever
// the thread count (counter-based normals keyed by frequency index, fixed-order sums).

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace impulse::synth {

/// A single-channel float field, row-major, row m_y = 0 first: value B(m_x, m_y) at
/// data[m_y * width + m_x].
struct Surface {
    int width = 0, height = 0;
    std::vector<float> data;
    float at(int x, int y) const { return data[size_t(y) * width + x]; }
};

enum class FbmMethod { Fourier, Incremental, Exact };
/// "fourier", "incremental", "exact"; anything else throws ValueError listing them.
FbmMethod parse_fbm_method(const std::string& name);
const char* to_string(FbmMethod method);

struct FbmOptions {
    FbmMethod method = FbmMethod::Incremental;
    double hurst = 0.5;     ///< H in (0, 1)
    int size = 512;         ///< output N x N, N a power of two in [2, 8192]
    bool seamless = false;  ///< Fourier only: the periodic N x N field itself (tiles seamlessly)
};

/// Peak bytes `FbmSynth` + one `realize` need (FFT buffer, spectrum table, output).
double fbm_memory_bytes(const FbmOptions& options);
/// Throws ValueError (H outside (0, 1), N not a power of two in [2, 8192], seamless with a method
/// that is not periodic) or BudgetError (estimate above `budget_bytes`, naming the estimate).
void check_fbm(const FbmOptions& options, double budget_bytes);
/// Default memory budget: half the physical memory.
double default_memory_budget();

/// One method at one size and H with its spectra computed once; `realize` many times (tests,
/// sampling bands). check_fbm is called with an unlimited budget.
class FbmSynth {
public:
    explicit FbmSynth(const FbmOptions& options);
    ~FbmSynth();
    FbmSynth(const FbmSynth&) = delete;
    FbmSynth& operator=(const FbmSynth&) = delete;
    /// One realisation, N x N.
    Surface realize(uint64_t seed) const;
    /// Side of the FFT grid the method uses (2N: Fourier cropped and Incremental; N: seamless
    /// Fourier; Exact: the embedding's torus, about 2.5N or 4N).
    int fft_size() const;

    struct Impl;

private:
    std::unique_ptr<Impl> m_impl;
};

/// FbmSynth(options).realize(seed).
Surface fbm(const FbmOptions& options, uint64_t seed);

/// Theory of the Fourier method: E[(B(m + d e_x) - B(m))^2] at each lag d (pixels) from its
/// periodic covariance R (Kaplan & Kuo §V: f~(d) = (R(0,0) - R(d,0)) / (R(0,0) - R(1,0))), with
/// sigma^2 = 1. Exact fBm has d^{2H}; this saturates at the period.
std::vector<double> fourier_fbm_structure(const FbmOptions& options, const std::vector<int>& lags);

/// R(0), the variance of the seamless Fourier field (options.seamless, a stationary field on the
/// N-torus with sigma^2 = 1): (1/n^2) sum_k R^(k) with C set by sigma^2 (eq. 14). Its spatial
/// mean is 0 (no DC term), so this is also the expected variance about a tile's mean.
double fourier_fbm_variance(const FbmOptions& options);
/// The expected variance of fBm (sigma^2 = 1 per sample step, E[(B(x) - B(y))^2] = |x - y|^{2H}
/// in samples) about its own mean over an n x n tile of samples: (1/2) E|x - y|^{2H} over pairs
/// of the tile's samples (the mean over x of (B(x) - mean B)^2 is half the mean over pairs of
/// (B(x) - B(y))^2). Sums the lag multiplicities (n - |dx|)(n - |dy|): O(n^2).
double fbm_tile_variance(double hurst, int n);

/// Incremental Fourier synthesis of a surface with an arbitrary isotropic structure function
/// f~(r) (Kaplan & Kuo §VI: f~ substituted in eqs. 6-8), f~(0) = 0, f~(1) = 1 for sigma^2 = 1;
/// r^{2H} gives fBm. Output N x N, N a power of two.
Surface incremental_synthesis(int size, const std::function<double(double r)>& structure,
                            uint64_t seed);

/// Standard Fourier synthesis of a periodic n x n stationary Gaussian field with spectral
/// density `density(fx, fy)` (value^2 per (cycle/pixel)^2, fx, fy in cycles per pixel, e.g. a
/// kernel's power_spectrum times an impulse rate): DFT coefficient k scaled by
/// sqrt(density(k / n)) / n, so the variance is sum density / n^2 ~ its integral. n even.
Surface fourier_synthesis(int n, const std::function<double(double fx, double fy)>& density,
                        uint64_t seed);

}  // namespace impulse::synth
