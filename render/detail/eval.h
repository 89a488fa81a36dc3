// SPDX-License-Identifier: Apache-2.0
#pragma once
// The vectorised inner loops of the tiled evaluator (internal to impulse::render). The same
// source is compiled three times, for baseline x86-64, AVX2 and AVX-512; with FMA contraction
// off and every fused multiply-add written out (std::fma), each pixel's arithmetic is the same
// sequence of correctly rounded operations whatever the lane width, so the CPU that renders
// never changes a bit.

#include <cstddef>
#include <cstdint>

namespace impulse::render::detail {

/// The kernel as the inner loop sees it, in pixel units.
struct LoopKernel {
    float radius_px = 1;      ///< support radius in pixels
    float inv_r2 = 1;         ///< 1 / radius_px^2
    float aspect2 = 1;        ///< aspect^2
    float freq_cpp = 0;       ///< carrier frequency, cycles per pixel
    float phase_cycles = 0;   ///< carrier phase / (2 pi)
    bool general = false;     ///< rotated/elliptical or carrier: the general loop
    bool carrier = false;
    /// Isotropic Gaussian envelope exp(-gauss_g r^2) (gaussian, isotropic gabor): evaluated as a
    /// product of per-column and per-row factors (separable), a few operations per pixel.
    bool separable = false;
    float gauss_g = 0;
    /// Envelope table in q (q_i = i / (table_n - 1)), linear interpolation; used instead of the
    /// polynomial when non-null.
    const float* table = nullptr;
    int table_n = 0;
    /// 2-D grid kernel (samples over [-R, R]^2 in the kernel frame), bilinear; when non-null.
    const float* grid = nullptr;
    int grid_n = 0;
    float aspect = 1;
    const float* coeffs = nullptr;  ///< Chebyshev coefficients of the envelope in q
    int ncoeffs = 0;                ///< odd, 5 .. 41
    const float* mono = nullptr;    ///< the same polynomial in powers of q (Horner with fma),
    int nmono = 0;                  ///< when accurate enough; preferred when set
};

/// Prepared impulses in pixel coordinates (pixel i's centre is at i), structure of arrays.
struct LoopImpulses {
    const float* px = nullptr;
    const float* py = nullptr;
    const float* w = nullptr;
    const float* cos_t = nullptr;  ///< cos of total orientation
    const float* sin_t = nullptr;
};

/// Columns of slack on each side of a tile row: spans are rounded up to whole vectors (8 or 16
/// lanes) and may run into it (those pixels are discarded).
inline constexpr int kPad = 16;

/// Adds the impulses idx[0..n) to the tile covering pixels [tx0, tx0+tw) x [ty0, ty0+th);
/// `acc` holds th rows of tw + 2 kPad floats, pixel (x, y) at
/// acc[(y - ty0) * (tw + 2 kPad) + kPad + (x - tx0)]. Impulses are summed in the order given.
void eval_tile_base(const LoopKernel& k, const LoopImpulses& p, const uint32_t* idx, size_t n,
                    int tx0, int ty0, int tw, int th, float* acc);
void eval_tile_avx2(const LoopKernel& k, const LoopImpulses& p, const uint32_t* idx, size_t n,
                    int tx0, int ty0, int tw, int th, float* acc);
void eval_tile_avx512(const LoopKernel& k, const LoopImpulses& p, const uint32_t* idx, size_t n,
                      int tx0, int ty0, int tw, int th, float* acc);

}  // namespace impulse::render::detail
