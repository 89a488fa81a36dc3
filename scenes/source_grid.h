// SPDX-License-Identifier: Apache-2.0
#pragma once
// A square grid of samples spanning a tile of texture space, read bilinearly (internal to
// impulse::scenes): the realised field of the fbm and subdivision layer sources. Outside the
// tile the grid repeats (periodic fields) or is mirrored at its edges (fields that are not
// periodic, which stay continuous that way).

#include <cmath>
#include <cstdint>
#include <memory>
#include <mutex>
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

/// A mip pyramid of a SampleGrid for perspective views: level l + 1 is level l filtered and
/// halved ([1 2 1] / 4 about a sample for corner grids, offset 0; [1 3 3 1] / 8 between two for
/// centred ones, offset 0.5), with the grid's fold, down to one sample, the tile's mean. A pixel
/// reads the level whose blur matches its footprint across, blended with the next (trilinear),
/// with Gaussian-weighted taps along the major axis (docs/perspective.md §3.3), faded to the mean
/// by the level's remaining sd (§6).
struct GridPyramid {
    std::vector<SampleGrid> levels;
    std::vector<double> variance;     ///< level l's blur, bilinear read included, level-0 cells^2
    std::vector<double> sd_fraction;  ///< rms of level l over rms of level 0

    explicit GridPyramid(const SampleGrid& grid);
    /// Adds the filtered field at each pixel's texture point minus (dx, dy) to `out`.
    void add(const PixelFootprints& pixels, double dx, double dy, numeric::Frame& out) const;
    /// The field at (X, Y) (texture units / level-0 cell) filtered by a Gaussian of variance
    /// var_major along (ex, ey) and var_minor across (level-0 cells^2), faded below `cutoff`.
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
