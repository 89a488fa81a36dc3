// SPDX-License-Identifier: Apache-2.0
// The inner loops of sparse-convolution solid noise (synth/detail/solid_loops.h).

#include "synth/detail/solid_loops.h"

#include <cmath>
#include <numbers>
#include <utility>

#include "numeric/cpu.h"

#define IMPULSE_SOLID_LOOPS base
#include "synth/solid_loops.inc"
#undef IMPULSE_SOLID_LOOPS

namespace impulse::synth::detail {
namespace {

/// Any kernel: the envelope table (linear in q) or the polynomial, and the Gabor carrier.
template <int D>
void accumulate_generic(const LoopKernel& k, const Gathered<D>& g,
                        const std::array<const float*, D>& t, size_t n, float* acc) {
    for (size_t m = 0; m < g.a.size(); ++m) {
        for (size_t p = 0; p < n; ++p) {
            float q = 0.0f;
            for (int d = 0; d < D; ++d) {
                const float dd = t[d][p] - g.v[d][m];
                q += dd * dd;
            }
            if (!(q < 1.0f)) continue;
            float e;
            if (k.terms > 0) {
                const float x = 2.0f * q - 1.0f, x2 = 2.0f * x;
                float b1 = 0.0f, b2 = 0.0f;
                for (int j = k.terms - 1; j >= 1; --j) {
                    const float b0 = x2 * b1 - b2 + k.chebyshev[j];
                    b2 = b1;
                    b1 = b0;
                }
                e = x * b1 - b2 + k.chebyshev[0];
            } else {
                const float x = q * float(k.table_n - 1);
                const int i = std::min(static_cast<int>(x), k.table_n - 2);
                e = k.table[i] + (x - float(i)) * (k.table[i + 1] - k.table[i]);
            }
            if (k.carrier)
                e *= std::cos(2.0f * std::numbers::pi_v<float> * k.frequency * (t[0][p] - g.v[0][m]) +
                              k.phase);
            acc[p] += g.a[m] * e;
        }
    }
}

constexpr size_t kFewPoints = 8;  // below this many points per group, vectorise over impulses

}  // namespace

LoopKernel loop_kernel(const SolidKernel& kernel) {
    const kernels::Kernel& s = kernel.shape();
    LoopKernel k;
    if (s.envelope_table().empty()) {
        k.chebyshev = s.polynomial().coefficients.data();
        k.terms = static_cast<int>(s.polynomial().coefficients.size());
    } else {
        k.table = s.envelope_table().data();
        k.table_n = static_cast<int>(s.envelope_table().size());
    }
    if (s.has_carrier()) {
        k.carrier = true;
        k.frequency = static_cast<float>(s.params().frequency * s.radius());  // cycles per cell
        k.phase = static_cast<float>(s.params().phase);
    }
    return k;
}

template <int D>
void accumulate(const LoopKernel& k, const Gathered<D>& g, const std::array<const float*, D>& t,
                size_t n, float* acc) {
    if (k.terms > 0 && !k.carrier) {
        const bool few = n < kFewPoints;
        // The widest build the CPU runs: the same arithmetic per lane, more lanes.
        static const numeric::SimdPath path = numeric::simd_path();
        LoopFn<D> f;
        if constexpr (D == 3)
            f = path == numeric::SimdPath::Avx512 ? avx512::poly3(k.terms, few)
                : path == numeric::SimdPath::Avx2 ? avx2::poly3(k.terms, few)
                                                  : base::poly3(k.terms, few);
        else
            f = path == numeric::SimdPath::Avx512 ? avx512::poly4(k.terms, few)
                : path == numeric::SimdPath::Avx2 ? avx2::poly4(k.terms, few)
                                                  : base::poly4(k.terms, few);
        if (f) {
            f(k, g, t, n, acc);
            return;
        }
    }
    accumulate_generic<D>(k, g, t, n, acc);
}

BrickFn brick_loop(const LoopKernel& k) {
    if (k.terms <= 0 || k.carrier) return nullptr;
    static const numeric::SimdPath path = numeric::simd_path();
    return path == numeric::SimdPath::Avx512 ? avx512::brick3(k.terms)
           : path == numeric::SimdPath::Avx2 ? avx2::brick3(k.terms)
                                             : base::brick3(k.terms);
}

size_t loop_lanes() {
    static const numeric::SimdPath path = numeric::simd_path();
    return path == numeric::SimdPath::Avx512 ? 16 : path == numeric::SimdPath::Avx2 ? 8 : 4;
}

template void accumulate<3>(const LoopKernel&, const Gathered<3>&, const std::array<const float*, 3>&,
                            size_t, float*);
template void accumulate<4>(const LoopKernel&, const Gathered<4>&, const std::array<const float*, 4>&,
                            size_t, float*);

}  // namespace impulse::synth::detail
