// SPDX-License-Identifier: Apache-2.0
#pragma once
// A square grid of samples spanning a tile of texture space, read bilinearly (internal to
// impulse::scenes): the realised field of the fbm and subdivision layer sources. Outside the
// tile the grid repeats (periodic fields) or is mirrored at its edges (fields that are not
// periodic, which stay continuous that way).

#include <cmath>
#include <cstdint>
#include <vector>

#include "numeric/frame.h"

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

}  // namespace impulse::scenes::detail
