// SPDX-License-Identifier: Apache-2.0
#pragma once
// A square grid of samples spanning a tile of texture space, read bilinearly (internal to
// impulse::scenes): the realised field of the fbm and subdivision layer sources. Outside the
// tile the grid repeats (periodic fields) or is mirrored at its edges (fields that are not
// periodic, which stay continuous that way).

#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "numeric/frame.h"
#include "scenes/source.h"

namespace impulse::scenes::detail {

struct SampleGrid {
    int n = 0;          ///< samples per side
    double cell = 1.0;  ///< texture units between samples
    /// Texture position of sample (0, 0) in cells: 0 puts sample (i, j) at (i, j) * cell, 0.5
    /// at the centre of cell (i, j), where the pixel centres of a view at one cell per pixel
    /// fall, so such a view reads the samples themselves.
    double offset = 0.0;
    bool periodic = false;
    std::vector<float> values;  ///< n x n, row-major
    /// What a footprint wider than the tile sees, the value a perspective view fades to: the
    /// samples' own mean (0 where the source removed it, as fbm does).
    double mean = 0.0;

    /// Bytes of the samples.
    double bytes() const { return 4.0 * double(n) * double(n); }

    /// Adds the bilinear interpolant at the pixel centres of `view` to `out`.
    void add(const numeric::View& v, numeric::Frame& out) const {
        for (int j = 0; j < v.height; ++j) {
            const double y = (v.y0 + (j + 0.5) * v.scale) / cell - offset;
            float* row = out.data.data() + size_t(j) * v.width;
            for (int i = 0; i < v.width; ++i)
                row[i] = static_cast<float>(row[i] + sample((v.x0 + (i + 0.5) * v.scale) / cell - offset, y));
        }
    }

    /// Grid index k folded into [0, n): wrapped (periodic) or mirrored at the edges.
    int64_t fold(int64_t k) const {
        if (periodic) return ((k % n) + n) % n;
        const int64_t p = 2 * (int64_t(n) - 1);
        if (p == 0) return 0;
        k = ((k % p) + p) % p;
        return k < n ? k : p - k;
    }
    /// The bilinear interpolant at grid coordinates (u, v) (samples at integers).
    double sample(double u, double v) const {
        const double fu = std::floor(u), fv = std::floor(v), a = u - fu, b = v - fv;
        const int64_t i0 = fold(int64_t(fu)), i1 = fold(int64_t(fu) + 1);
        const int64_t j0 = fold(int64_t(fv)), j1 = fold(int64_t(fv) + 1);
        const float* r0 = values.data() + size_t(j0) * n;
        const float* r1 = values.data() + size_t(j1) * n;
        return (1 - b) * ((1 - a) * r0[i0] + a * r0[i1]) + b * ((1 - a) * r1[i0] + a * r1[i1]);
    }
};

/// The largest b for which a grid read at p = a / b pixels per sample has its images summed
/// coherently (coherent_images); images b apart or more weigh under sinc^2(p b) ~ 1/(pi p b)^2.
inline constexpr int kMaxCoherentDenominator = 8;

/// The least b <= kMaxCoherentDenominator with p b whole (to 1e-9 relative), p pixels per
/// sample; nullopt when there is none (the pixel and sample lattices are incommensurate).
std::optional<int> lattice_denominator(double p);

/// A line of a grid's samples, e^{2 pi i kappa g} at kappa cycles per sample, read bilinearly at
/// the pixel centres g_q = (q + phi) / p (g in samples; p = a / b pixels per sample, phi the
/// phase of pixel 0 in pixels): its images kappa + j, weighted by the tent's transfer
/// sinc^2(kappa + j), land at pixel frequency nu when kappa + j = p (nu + r), r whole; images r = c
/// mod b are the same line of the tile and add with their phases (docs/scenes.md "Analysis of
/// source layers"):
///   A_c(nu) = sum_{r = c mod b} sinc^2(p (nu + r)) e^{2 pi i (nu + r) phi}
///           = (1 / (b p)) sum_k tri((k / b - phi) / p) e^{2 pi i k (nu + c) / b},
/// the second by Poisson summation (tri(x) = max(0, 1 - |x|) has the transform sinc^2), a finite
/// sum of about 2 a + 1 terms. Returns A_0..A_{b-1} (b <= kMaxCoherentDenominator).
std::array<std::complex<double>, kMaxCoherentDenominator> coherent_images(double nu, double p, int b,
                                                                          double phi);

/// A mip pyramid of a SampleGrid for perspective views: level l + 1 is level l filtered and
/// halved ([1 2 1] / 4 about a sample for corner grids, offset 0; [1 3 3 1] / 8 between two for
/// centred ones, offset 0.5), with the grid's fold, down to one sample, the tile's mean. A pixel
/// reads the level whose blur matches its footprint across, blended with the next (trilinear),
/// with Gaussian-weighted taps along the major axis (docs/perspective.md §3.3), faded to the
/// grid's own mean (SampleGrid::mean, what its top level holds) by the level's remaining sd (§6).
struct GridPyramid {
    std::vector<SampleGrid> levels;
    std::vector<double> variance;     ///< level l's blur, bilinear read included, level-0 cells^2
    std::vector<double> sd_fraction;  ///< sd of level l about the grid's mean over level 0's

    explicit GridPyramid(const SampleGrid& grid);
    /// Bytes a pyramid of an n x n grid holds at its peak: its levels (a copy of the grid and
    /// each halving, 4/3 of the grid) and, while the first halving is made, half the grid of
    /// rows filtered along x; at most 7/4 of the grid.
    static double bytes(int n);
    /// Adds the filtered field at each pixel's texture point minus (dx, dy) to `out`.
    void add(const PixelFootprints& pixels, double dx, double dy, numeric::Frame& out) const;
    /// The field at (X, Y) (texture units / level-0 cell) filtered by a Gaussian of variance
    /// var_major along (ex, ey) and var_minor across (level-0 cells^2), faded to the grid's
    /// mean below `cutoff`.
    double filtered(double X, double Y, double var_major, double var_minor, double ex, double ey,
                    double cutoff) const;

private:
    /// The continuous level for a footprint of these variances.
    double level_for(double var_minor, double var_major) const;
    /// Level l at (X, Y) with taps along (ex, ey) adding variance `extra` (none when <= 0).
    double level_value(int l, double X, double Y, double ex, double ey, double extra) const;
};

/// A grid source's pyramid, built on first use (a perspective frame) and then shared.
class LazyPyramid {
public:
    const GridPyramid& get(const SampleGrid& grid) const {
        std::call_once(m_once, [&] { m_pyramid = std::make_unique<const GridPyramid>(grid); });
        return *m_pyramid;
    }

private:
    mutable std::once_flag m_once;
    mutable std::unique_ptr<const GridPyramid> m_pyramid;
};

}  // namespace impulse::scenes::detail
