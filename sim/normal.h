// SPDX-License-Identifier: Apache-2.0
#pragma once
// The normal amplitude of an impulse by Box–Muller, sqrt(-2 ln u) cos(2 pi v) (internal to
// impulse::sim), from our own ln and cos made of + - * / and sqrt only. IEEE 754 rounds each of
// these correctly, so with FMA contraction off (the project's -ffp-contract=off) the value is
// the same on every x86-64 CPU and with every C library, unlike libm's log and cos, whose
// variant is chosen by CPU at run time and whose last bit is not promised (design.md §4: same
// scene and seed, same bytes). The scalar function (sim/normal.cpp) and the AVX2 one
// (sim/normal_avx2.cpp) do the same operations in the same order: the same bits.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace impulse::sim::detail {

/// sqrt(-2 ln u) cos(2 pi v) for u in (0, 1] (a normal double: any Philox uniform) and v in
/// [0, 1]; u = 1 gives 0. Relative error below 16 units of roundoff (1.8e-15; derived and
/// checked in tests/sim/test_normal.cpp), so its float is the float nearest the exact value or,
/// within that of a halfway point, the neighbour.
double normal_from_uniforms(double u, double v);

/// out[j] = float(normal_from_uniforms(u[j], v[j])) for j < n, four lanes per AVX2 register
/// (sim/normal_avx2.cpp, compiled with -mavx2; call only when cpu_has_avx2()). The same bits.
void normals_from_uniforms_avx2(size_t n, const double* u, const double* v, float* out);
/// The same before the rounding to float: out[j] = normal_from_uniforms(u[j], v[j]) (tests).
void normals_from_uniforms_avx2(size_t n, const double* u, const double* v, double* out);

/// Many normal amplitudes computed together (AVX2 on a CPU that has it, else the scalar
/// function: the same bits): pairs (u, v) queued with `add`, written by `run`. The arrays are
/// kept for the next batch.
class NormalBatch {
public:
    void clear() { m_u.clear(), m_v.clear(); }
    size_t size() const { return m_u.size(); }
    void add(double u, double v) { m_u.push_back(u), m_v.push_back(v); }
    /// out[j] = float(normal_from_uniforms(u, v)) of the pair added j-th, for every pair.
    void run(float* out) const;

private:
    std::vector<double> m_u, m_v;
};

/// Coefficients shared by both builds.
namespace normal_poly {

/// ln 2 split as fdlibm does (e_log.c): kLn2Hi has 32 significant bits, so e * kLn2Hi is exact
/// for every binary exponent e of a double.
inline constexpr double kLn2Hi = 6.93147180369123816490e-01;
inline constexpr double kLn2Lo = 1.90821492927058770002e-10;
/// Bits of 1, of sqrt(1/2) rounded (0.70710678118654757) and the mantissa's mask.
inline constexpr uint64_t kOneBits = 0x3FF0000000000000ull;
inline constexpr uint64_t kSqrtHalfBits = 0x3FE6A09E667F3BCDull;
inline constexpr uint64_t kMantissaBits = 0x000FFFFFFFFFFFFFull;

/// ln m = 2 atanh(s), s = (m - 1) / (m + 1) = f / (2 + f) with f = m - 1: the series
/// 2 s + 2 s z Q(z), z = s^2, Q(z) = sum_j z^j / (2 j + 3). For m in [sqrt(1/2), sqrt(2)],
/// |s| <= 3 - 2 sqrt(2) = 0.1716 and z <= 0.02944; the first term left out, z^9 / 21 relative
/// to 2 s, is below 2.4e-17.
inline constexpr double kLogQ[] = {1.0 / 3,  1.0 / 5,  1.0 / 7,  1.0 / 9, 1.0 / 11,
                                   1.0 / 13, 1.0 / 15, 1.0 / 17, 1.0 / 19};

/// sin(2 pi d) = d P(d^2) for d in [-1/4, 1/4], the Taylor series: the coefficient n is
/// (-1)^n (2 pi)^(2n+1) / (2n+1)! (rounded from 50 digits). Its first term left out,
/// (pi/2)^23 / 23!, is below 1.3e-18.
inline constexpr double kSin[] = {6.283185307179586,     -41.34170224039976,   81.60524927607506,
                                  -76.70585975306139,    42.058693944897655,   -15.09464257682299,
                                  3.819952584848282,     -0.7181223017785006,  0.10422916220813984,
                                  -0.012031585942120627, 0.0011309237482517963};

/// Q(z) of kLogQ and P(z) of kSin by Estrin's scheme (Knuth, TAOCP vol. 2, 4.6.4): pairs
/// c_2i + c_2i+1 z, combined with z^2, z^4, z^8, so the chain of dependent operations is about
/// half Horner's. A template over the lane type (double in sim/normal.cpp, four lanes in
/// sim/normal_avx2.cpp, each instantiating only its own) so both builds do the same operations
/// in the same order; T needs + and * and construction from a double.
template <typename T>
T log_series(T z) {
    const T z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
    const T p01 = T(kLogQ[0]) + T(kLogQ[1]) * z, p23 = T(kLogQ[2]) + T(kLogQ[3]) * z;
    const T p45 = T(kLogQ[4]) + T(kLogQ[5]) * z, p67 = T(kLogQ[6]) + T(kLogQ[7]) * z;
    return (p01 + p23 * z2) + (p45 + p67 * z2) * z4 + T(kLogQ[8]) * z8;
}
template <typename T>
T sin_series(T z) {
    const T z2 = z * z, z4 = z2 * z2, z8 = z4 * z4;
    const T p01 = T(kSin[0]) + T(kSin[1]) * z, p23 = T(kSin[2]) + T(kSin[3]) * z;
    const T p45 = T(kSin[4]) + T(kSin[5]) * z, p67 = T(kSin[6]) + T(kSin[7]) * z;
    const T p89 = T(kSin[8]) + T(kSin[9]) * z;
    return (p01 + p23 * z2) + (p45 + p67 * z2) * z4 + (p89 + T(kSin[10]) * z2) * z8;
}

}  // namespace normal_poly

}  // namespace impulse::sim::detail
