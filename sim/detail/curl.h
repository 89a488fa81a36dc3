// SPDX-License-Identifier: Apache-2.0
#pragma once
// The inner loop of the curl-noise flow (internal to impulse::sim): the velocity and vorticity
// of a Catmull-Rom interpolated potential lattice at many points. The same source
// (sim/curl_loops.inc) is compiled twice, for baseline x86-64 and for AVX2; with FMA
// contraction off both round identically, so the CPU that integrates never changes a bit.

#include <cstddef>
#include <cstdint>

#include "numeric/rng.h"

namespace impulse::sim::detail {

/// Fills `out` with psi at the 4 x 4 lattice nodes (i0 + a, j0 + b), row b at out[4 b]: the
/// same values the cached lattice holds, for points whose stencil leaves the cache.
using CurlNodeFetch = void (*)(const void* context, int64_t i0, int64_t j0, double out[16]);

/// The potential psi on the lattice of nodes (i h_x, j h_y) as the inner loop sees it.
struct CurlLattice {
    const double* nodes = nullptr;     ///< psi at node (i, j): nodes[(j - j0) * width + i - i0]
    int64_t i0 = 0, j0 = 0;            ///< first cached node
    int64_t width = 0, height = 0;     ///< cached nodes per row and column (0: nothing cached)
    double inv_hx = 1, inv_hy = 1;     ///< 1 / node spacing, per texture unit
    CurlNodeFetch fetch = nullptr;     ///< nodes outside the cache
    const void* fetch_context = nullptr;
};

/// Adds v = amp (d psi/dy, -d psi/dx) to (vx, vy) and, when `curl` is not null,
/// curl v = -amp lap psi to curl, at the n points (x[i], y[i]); psi is the Catmull-Rom bicubic
/// interpolant of the lattice.
void curl_add_base(const CurlLattice& lattice, double amp, size_t n, const double* x,
                   const double* y, double* vx, double* vy, double* curl);
void curl_add_avx2(const CurlLattice& lattice, double amp, size_t n, const double* x,
                   const double* y, double* vx, double* vy, double* curl);

}  // namespace impulse::sim::detail
