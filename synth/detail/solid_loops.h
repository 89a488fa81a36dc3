// SPDX-License-Identifier: Apache-2.0
#pragma once
// The inner loop of sparse-convolution solid noise (internal to impulse::synth): the impulses
// gathered for one cell against the points in it, the kernel looked up by squared distance
// (Lewis 1989 §4.1: no square root). Written so GCC vectorises over the points: each point
// keeps its own accumulator and adds the impulses in the gathered (canonical) order, so any
// vector width gives the same bits.

#include <array>
#include <cstddef>
#include <vector>

#include "synth/solid.h"

namespace impulse::synth::detail {

/// Impulses relative to one cell (cell units) and their amplitudes, structure of arrays.
template <int D>
struct Gathered {
    std::array<std::vector<float>, D> v;
    std::vector<float> a;
};

/// The kernel as the loop evaluates it, in cell units (R = 1, q = |d|^2).
struct LoopKernel {
    const float* chebyshev = nullptr;  ///< envelope's Chebyshev coefficients in T_j(2q - 1)
    int terms = 0;                     ///< their number; 0: use the table
    const float* table = nullptr;      ///< envelope at q_i = i / (table_n - 1)
    int table_n = 0;
    bool carrier = false;              ///< Gabor: times cos(2 pi f_cells d_1 + phase)
    float frequency = 0.0f, phase = 0.0f;
};

LoopKernel loop_kernel(const SolidKernel& kernel);

/// A loop over a group: acc[p] += sum_k a_k h(t(p) - v_k).
template <int D>
using LoopFn = void (*)(const LoopKernel&, const Gathered<D>&, const std::array<const float*, D>&,
                        size_t, float*);
/// The vectorised polynomial loops of a build (solid_loops.inc): nullptr beyond 24 terms; `few`:
/// the variant for groups of fewer than 8 points.
/// A loop over a brick of grid samples, the product of n[0] x n[1] x n[2] coordinates t[d]
/// along the axes (x fastest in acc; n[0] a multiple of 8, at most kBrickRow): the same sum and
/// the same bits as LoopFn at those points, q = ((dx^2 + dy^2) + dz^2) as there, with a row
/// (j, k) skipped when dy^2 + dz^2 >= 1 (then every q of the row is >= 1: its terms are 0).
using BrickFn = void (*)(const LoopKernel&, const Gathered<3>&, const std::array<const float*, 3>&,
                         const std::array<int, 3>&, float*);
constexpr int kBrickRow = 64;
namespace base {
LoopFn<3> poly3(int terms, bool few);
LoopFn<4> poly4(int terms, bool few);
BrickFn brick3(int terms);
}  // namespace base
namespace avx2 {
LoopFn<3> poly3(int terms, bool few);
LoopFn<4> poly4(int terms, bool few);
BrickFn brick3(int terms);
}  // namespace avx2
namespace avx512 {
LoopFn<3> poly3(int terms, bool few);
LoopFn<4> poly4(int terms, bool few);
BrickFn brick3(int terms);
}  // namespace avx512

/// Lanes of the widest loop this CPU runs (16, 8 or 4 floats): groups padded to a multiple
/// of it run no scalar remainder.
size_t loop_lanes();

/// The brick loop of the kernel for this CPU, or nullptr when the kernel has none (a table, a
/// carrier or more than 24 terms): use the points then.
BrickFn brick_loop(const LoopKernel& k);

/// acc[p] += sum_k a_k h(t(p) - v_k) for the n points t[d][p], in k order.
template <int D>
void accumulate(const LoopKernel& k, const Gathered<D>& g, const std::array<const float*, D>& t,
                size_t n, float* acc);

}  // namespace impulse::synth::detail
