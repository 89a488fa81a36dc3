// SPDX-License-Identifier: Apache-2.0
// The inner loops of sparse-convolution solid noise (synth/solid_loops.h).

#include "synth/solid_loops.h"

#include <cmath>
#include <numbers>
#include <utility>

namespace impulse::synth::detail {
namespace {

/// Clenshaw's recurrence for sum_j c_j T_j(2q - 1), N terms unrolled at compile time (a loop
/// over the terms would keep GCC from vectorising the point loop around it).
template <int N>
[[gnu::always_inline]] inline float chebyshev(float q, const float* c) {
    const float t = 2.0f * q - 1.0f, t2 = 2.0f * t;
    float b1 = 0.0f, b2 = 0.0f;
    for (int j = N - 1; j >= 1; --j) {  // constant trip count: fully unrolled
        const float b0 = t2 * b1 - b2 + c[j];
        b2 = b1;
        b1 = b0;
    }
    return t * b1 - b2 + c[0];
}

/// The vectorised loop: impulses outer, points inner (one accumulator per point).
template <int D, int N>
void accumulate_poly(const LoopKernel& k, const Gathered<D>& g, const std::array<const float*, D>& t,
                     size_t n, float* acc) {
    float c[N];
    for (int j = 0; j < N; ++j) c[j] = k.chebyshev[j];
    for (size_t m = 0; m < g.a.size(); ++m) {
        std::array<float, D> v;
        for (int d = 0; d < D; ++d) v[d] = g.v[d][m];
        const float a = g.a[m];
        for (size_t p = 0; p < n; ++p) {
            float q = 0.0f;
            for (int d = 0; d < D; ++d) {
                const float dd = t[d][p] - v[d];
                q += dd * dd;
            }
            const float qc = q < 1.0f ? q : 1.0f;
            const float e = chebyshev<N>(qc, c);
            acc[p] += q < 1.0f ? a * e : 0.0f;
        }
    }
}

/// Few points: per point, the terms vectorised over the impulses into scratch, then added in
/// impulse order (the same terms and the same order as accumulate_poly: the same bits).
template <int D, int N>
void accumulate_few(const LoopKernel& k, const Gathered<D>& g, const std::array<const float*, D>& t,
                    size_t n, float* acc) {
    float c[N];
    for (int j = 0; j < N; ++j) c[j] = k.chebyshev[j];
    thread_local std::vector<float> terms;
    const size_t m = g.a.size();
    terms.resize(m);
    float* term = terms.data();
    std::array<const float*, D> v;
    for (int d = 0; d < D; ++d) v[d] = g.v[d].data();
    const float* a = g.a.data();
    for (size_t p = 0; p < n; ++p) {
        std::array<float, D> x;
        for (int d = 0; d < D; ++d) x[d] = t[d][p];
        for (size_t j = 0; j < m; ++j) {
            float q = 0.0f;
            for (int d = 0; d < D; ++d) {
                const float dd = x[d] - v[d][j];
                q += dd * dd;
            }
            const float qc = q < 1.0f ? q : 1.0f;
            const float e = chebyshev<N>(qc, c);
            term[j] = q < 1.0f ? a[j] * e : 0.0f;
        }
        float s = acc[p];
        for (size_t j = 0; j < m; ++j) s += term[j];
        acc[p] = s;
    }
}

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

using Loop3 = void (*)(const LoopKernel&, const Gathered<3>&, const std::array<const float*, 3>&,
                       size_t, float*);
using Loop4 = void (*)(const LoopKernel&, const Gathered<4>&, const std::array<const float*, 4>&,
                       size_t, float*);
constexpr int kMaxTerms = 24;

template <int D, class Loop, size_t... I>
constexpr std::array<Loop, sizeof...(I)> loops(std::index_sequence<I...>) {
    return {&accumulate_poly<D, int(I) + 1>...};
}
template <int D, class Loop, size_t... I>
constexpr std::array<Loop, sizeof...(I)> few_loops(std::index_sequence<I...>) {
    return {&accumulate_few<D, int(I) + 1>...};
}
constexpr auto kLoops3 = loops<3, Loop3>(std::make_index_sequence<kMaxTerms>());
constexpr auto kLoops4 = loops<4, Loop4>(std::make_index_sequence<kMaxTerms>());
constexpr auto kFew3 = few_loops<3, Loop3>(std::make_index_sequence<kMaxTerms>());
constexpr auto kFew4 = few_loops<4, Loop4>(std::make_index_sequence<kMaxTerms>());
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
    if (k.terms > 0 && k.terms <= kMaxTerms && !k.carrier) {
        const bool few = n < kFewPoints;
        if constexpr (D == 3) (few ? kFew3 : kLoops3)[k.terms - 1](k, g, t, n, acc);
        else (few ? kFew4 : kLoops4)[k.terms - 1](k, g, t, n, acc);
        return;
    }
    accumulate_generic<D>(k, g, t, n, acc);
}

template void accumulate<3>(const LoopKernel&, const Gathered<3>&, const std::array<const float*, 3>&,
                            size_t, float*);
template void accumulate<4>(const LoopKernel&, const Gathered<4>&, const std::array<const float*, 4>&,
                            size_t, float*);

}  // namespace impulse::synth::detail
