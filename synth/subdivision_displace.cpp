// SPDX-License-Identifier: Apache-2.0
// Correlated displacements for generalized stochastic subdivision (docs/subdivision.md
// "Correlated displacements"). The paper displaces each new node independently, so two new
// nodes of a level are correlated only through the observations they share:
// Cov(x^_k(p), x^_k'(q)) = a_k^T A(p - q) a_k', not R. Giving the displacements the missing
// covariance
//     C_kk'(D) = R(s (D + d_k - d_k')) - sum_{m, m'} a_km a_k'm' R(s (D + o_km - o_k'm'))
// (d_k the class's target offset, o_km its observations) makes the new nodes' covariance R
// again. C is stationary on the lattice of cells, so u = beta * w with beta the spectral
// square root of C (a K x K Hermitian matrix per frequency) and w the nodes' keyed normals:
// still local, still keyed by (seed, level, node). C(0) is the eq. 7 variance.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <numbers>

#include "synth/subdivision.h"

namespace impulse::synth {
namespace {

/// Largest filter radius J in cells and the relative size below which a tap is dropped.
constexpr int kMaxRadius = 4;
constexpr double kTapFloor = 1e-3;

using Cd = std::complex<double>;

/// A (2E + 1)^dims array of integer offsets in [-E, E], 1-D when dims = 1.
struct Box {
    int e = 0, dims = 1;
    int side() const { return 2 * e + 1; }
    size_t size() const { return dims == 1 ? size_t(side()) : size_t(side()) * side(); }
    size_t at(int x, int y) const {
        return dims == 1 ? size_t(x + e) : size_t(y + e) * side() + size_t(x + e);
    }
};

}  // namespace

DisplacementFilter displacement_filter(const Acf& acf, int dims, double s,
                                       const std::vector<ClassCoefficients>& cls) {
    const int K = static_cast<int>(cls.size());
    const int M = dims == 1 ? 256 : 32;  // DFT grid, cells per axis (C is negligible beyond M/2)
    const int My = dims == 1 ? 1 : M;
    int reach = 0;
    for (const auto& c : cls)
        for (const auto& [cx, ry] : c.offsets)
            reach = std::max({reach, std::abs(cx), std::abs(ry)});
    const Box w{2 * reach, dims};    // differences of two observation offsets
    const Box t{M / 2 + w.e, dims};  // R(s v) tabulated on the cell lattice
    std::vector<double> rtab(t.size());
    for (int y = dims == 1 ? 0 : -t.e; y <= (dims == 1 ? 0 : t.e); ++y)
        for (int x = -t.e; x <= t.e; ++x) rtab[t.at(x, y)] = acf.R(s * x, s * y);
    // C_kk'(D) at DFT index (D mod M), D in [-M/2, M/2).
    std::vector<std::vector<double>> C(size_t(K * K), std::vector<double>(size_t(M) * My));
    for (int k = 0; k < K; ++k)
        for (int k2 = 0; k2 < K; ++k2) {
            std::vector<double> W(w.size(), 0.0);  // sum of a_km a_k'm' over o_km - o_k'm' = d
            for (size_t m = 0; m < cls[k].a.size(); ++m)
                for (size_t m2 = 0; m2 < cls[k2].a.size(); ++m2)
                    W[w.at(cls[k].offsets[m].first - cls[k2].offsets[m2].first,
                           cls[k].offsets[m].second - cls[k2].offsets[m2].second)] +=
                        cls[k].a[m] * cls[k2].a[m2];
            const double dx = 0.5 * (cls[k].tx2 - cls[k2].tx2),
                         dy = 0.5 * (cls[k].ty2 - cls[k2].ty2);
            auto& out = C[size_t(k * K + k2)];
            for (int y = (dims == 1 ? 0 : -M / 2); y < (dims == 1 ? 1 : M / 2); ++y)
                for (int x = -M / 2; x < M / 2; ++x) {
                    double v = acf.R(s * (x + dx), s * (y + dy));
                    for (int ey = (dims == 1 ? 0 : -w.e); ey <= (dims == 1 ? 0 : w.e); ++ey)
                        for (int ex = -w.e; ex <= w.e; ++ex)
                            v -= W[w.at(ex, ey)] * rtab[t.at(x + ex, y + ey)];
                    out[size_t((y + My) % My) * M + size_t((x + M) % M)] = v;
                }
        }
    // Per frequency: S(f) = sum_D C(D) e^{-2 pi i f.D / M}, Hermitian K x K; B = S^{1/2}.
    const double tau = 2 * std::numbers::pi / M;
    const size_t F = size_t(M) * My;
    std::vector<Cd> tw(static_cast<size_t>(M));  // e^{-2 pi i n / M}
    for (int n = 0; n < M; ++n) tw[size_t(n)] = std::polar(1.0, -tau * n);
    std::vector<Eigen::MatrixXcd> B(F);
    for (size_t f = 0; f < F; ++f) {
        const int fx = int(f % M), fy = int(f / M);
        Eigen::MatrixXcd S = Eigen::MatrixXcd::Zero(K, K);
        for (size_t d = 0; d < F; ++d) {
            const Cd e = tw[size_t((fx * int(d % M) + fy * int(d / M)) % M)];
            for (int k = 0; k < K * K; ++k) S(k / K, k % K) += C[size_t(k)][d] * e;
        }
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(S);
        const Eigen::VectorXd lam = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
        B[f] = es.eigenvectors() * lam.asDiagonal() * es.eigenvectors().adjoint();
    }
    // beta(j) = (1 / M^d) sum_f B(f) e^{+2 pi i f.j / M} for |j| <= kMaxRadius.
    const Box jb{kMaxRadius, dims};
    std::vector<double> full(size_t(K * K) * jb.size(), 0.0);
    double peak = 0;
    for (int jy = (dims == 1 ? 0 : -jb.e); jy <= (dims == 1 ? 0 : jb.e); ++jy)
        for (int jx = -jb.e; jx <= jb.e; ++jx)
            for (int k = 0; k < K * K; ++k) {
                Cd sum = 0;
                for (size_t f = 0; f < F; ++f)
                    sum += B[f](k / K, k % K) *
                           std::conj(tw[size_t(((int(f % M) * jx + int(f / M) * jy) % M + M) % M)]);
                const double v = sum.real() / double(F);
                full[size_t(k) * jb.size() + jb.at(jx, jy)] = v;
                peak = std::max(peak, std::abs(v));
            }
    // The smallest radius holding every tap above kTapFloor of the largest.
    DisplacementFilter out;
    for (int jy = (dims == 1 ? 0 : -jb.e); jy <= (dims == 1 ? 0 : jb.e); ++jy)
        for (int jx = -jb.e; jx <= jb.e; ++jx)
            for (int k = 0; k < K * K; ++k)
                if (std::abs(full[size_t(k) * jb.size() + jb.at(jx, jy)]) > kTapFloor * peak)
                    out.radius = std::max({out.radius, std::abs(jx), std::abs(jy)});
    const Box ob{out.radius, dims};
    out.beta.assign(size_t(K * K) * ob.size(), 0.0);
    for (int jy = (dims == 1 ? 0 : -ob.e); jy <= (dims == 1 ? 0 : ob.e); ++jy)
        for (int jx = -ob.e; jx <= ob.e; ++jx)
            for (int k = 0; k < K * K; ++k)
                out.beta[size_t(k) * ob.size() + ob.at(jx, jy)] =
                    full[size_t(k) * jb.size() + jb.at(jx, jy)];
    // Each class keeps exactly its eq. 7 variance (truncation and clamping lose a little).
    for (int k = 0; k < K; ++k) {
        double sum2 = 0;
        for (size_t q = 0; q < size_t(K) * ob.size(); ++q)
            sum2 += std::pow(out.beta[size_t(k * K) * ob.size() + q], 2);
        const double scale = sum2 > 0 ? std::sqrt(cls[k].variance / sum2) : 0.0;
        for (size_t q = 0; q < size_t(K) * ob.size(); ++q)
            out.beta[size_t(k * K) * ob.size() + q] *= scale;
    }
    return out;
}

}  // namespace impulse::synth
