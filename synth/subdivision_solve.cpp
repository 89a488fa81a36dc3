// SPDX-License-Identifier: Apache-2.0
// The per-level coefficients of generalized stochastic subdivision: the normal equations
// R(target - m) = sum_k a_k R(m - k) (Lewis 1987 eq. 4; 2-D eq. 11, 12) by Cholesky, the
// estimation error (eq. 7), the neighbourhood size by an error threshold (§4.1), the remedies
// for singular autocorrelations (§4.3) and for the diagonal bias (§6.1). docs/subdivision.md.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "synth/subdivision.h"
#include "numeric/errors.h"

namespace impulse::synth {
namespace {

/// A neighbourhood matrix whose smallest eigenvalue is below this fraction of its largest is
/// singular (Lewis 1987 §4.3). Not rounding sets the bound: the nodes a level reads are the
/// construction's, whose covariance departs slightly from R, and the large alternating
/// coefficients of a worse-conditioned system amplify that departure into creases (1-D
/// oscillatory_gaussian l = 60, w = 0.3, 2N = 16: E d^2 on old nodes 22x the theory at 1e-10,
/// 1.04x at 1e-6; gaussian l = 12: 2.0x at 1e-10, 1.2x at 1e-6, 4x at 1e-4).
constexpr double kSingular = 1e-6;
/// An eigenvalue below -kNegative * (largest) of the covariance of a neighbourhood and its
/// target is a real negative one, not rounding (which is ~1e-15 of the largest).
constexpr double kNegative = 1e-8;

std::string num(double v) {
    std::ostringstream s;
    s.precision(6);
    s << v;
    return s.str();
}

struct Solved {
    ClassCoefficients c;
    bool singular = false;
};

/// Observation offsets of a class with half-width n: across a half-cell offset the
/// neighbourhood spans 1-n .. n (2n nodes), along a node's own line 1-n .. n-1 (2n - 1
/// nodes), so it is symmetric about the target (Lewis 1987 eq. 9, 10). 1-D: one row.
std::vector<std::pair<int, int>> class_offsets(int dims, int tx2, int ty2, int n) {
    const int x0 = 1 - n, x1 = tx2 ? n : n - 1;
    const int y0 = dims == 1 ? 0 : 1 - n, y1 = dims == 1 ? 0 : (ty2 ? n : n - 1);
    std::vector<std::pair<int, int>> o;
    for (int r = y0; r <= y1; ++r)
        for (int c = x0; c <= x1; ++c) o.push_back({c, r});
    return o;
}

Solved solve(const Acf& acf, double s, int tx2, int ty2,
             const std::vector<std::pair<int, int>>& offsets, bool allow_pinv) {
    const int n = static_cast<int>(offsets.size());
    const double r0 = acf.R(0, 0);
    Eigen::MatrixXd A(n, n);
    Eigen::VectorXd b(n);
    for (int p = 0; p < n; ++p) {
        const auto [cp, rp] = offsets[p];
        // eq. 4 right side: R(target - m), the target at (tx2 / 2, ty2 / 2) coarse cells.
        b(p) = acf.R(s * (0.5 * tx2 - cp), s * (0.5 * ty2 - rp));
        for (int q = 0; q < n; ++q) {
            const auto [cq, rq] = offsets[q];
            A(p, q) = acf.R(s * (cp - cq), s * (rp - rq));  // eq. 4 matrix R(m - k)
        }
    }
    // Non-negative definiteness (Lewis 1986 §2.2, 1987 §6.2): the covariance of the
    // neighbourhood with its target must have no negative eigenvalue.
    Eigen::MatrixXd M(n + 1, n + 1);
    M.topLeftCorner(n, n) = A;
    M.block(0, n, n, 1) = b;
    M.block(n, 0, 1, n) = b.transpose();
    M(n, n) = r0;
    const Eigen::VectorXd lm =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M, Eigen::EigenvaluesOnly).eigenvalues();
    if (!lm.allFinite() || lm(0) < -kNegative * lm(n))
        throw ValueError("autocorrelation " + acf.name +
                         " is not non-negative definite: at spacing " + num(s) +
                         " the covariance of " + std::to_string(n) +
                         " neighbours and their midpoint has eigenvalue " + num(lm(0)) +
                         " (R(0) = " + num(r0) + "); its spectrum is negative somewhere");
    const Eigen::VectorXd la =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues();
    Solved out;
    out.singular = !(la(0) > kSingular * la(n - 1));
    ClassCoefficients& c = out.c;
    c.tx2 = tx2, c.ty2 = ty2;
    c.offsets = offsets;
    Eigen::VectorXd a;
    if (!out.singular) {
        a = A.llt().solve(b);  // Cholesky: A is symmetric positive definite here
    } else {
        if (!allow_pinv) return out;
        // Moore–Penrose inverse (Lewis 1987 §4.3, after Deutsch): the minimum-norm solution
        // on the numerically non-singular subspace.
        Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
        cod.setThreshold(kSingular);
        cod.compute(A);
        a = cod.solve(b);
        c.pseudo_inverse = true;
    }
    c.a.assign(a.data(), a.data() + n);
    double v = r0 - a.dot(b);  // eq. 7
    // A singular system leaves R(0) - a.b at rounding level, possibly just below zero.
    if (v < 0) {
        if (v < -1e-6 * r0)
            throw ValueError("autocorrelation " + acf.name +
                             " is not non-negative definite: at spacing " + num(s) +
                             " the estimation error variance is " + num(v));
        v = 0;
    }
    c.variance = v;
    return out;
}

/// Largest |a_k| on the outer ring of the neighbourhood over the largest |a_k| (the diagonal
/// bias of Lewis 1987 §6.1 comes from truncating coefficients that are still significant).
double ring_ratio(const ClassCoefficients& c) {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    for (const auto& [cx, ry] : c.offsets)
        x0 = std::min(x0, cx), x1 = std::max(x1, cx), y0 = std::min(y0, ry), y1 = std::max(y1, ry);
    double ring = 0, all = 0;
    for (size_t k = 0; k < c.a.size(); ++k) {
        const auto [cx, ry] = c.offsets[k];
        all = std::max(all, std::abs(c.a[k]));
        if (cx == x0 || cx == x1 || ry == y0 || ry == y1) ring = std::max(ring, std::abs(c.a[k]));
    }
    return all > 0 ? ring / all : 0;
}

ClassCoefficients choose(const Acf& acf, const GssOptions& o, double s, int tx2, int ty2) {
    const double r0 = acf.R(0, 0);
    const bool pinv = o.singular == Singular::PseudoInverse;
    std::vector<ClassCoefficients> cands;
    for (int n = 1; n <= o.max_neighbors / 2; ++n) {
        Solved sv = solve(acf, s, tx2, ty2, class_offsets(o.dims, tx2, ty2, n), pinv);
        // Reduce: a larger neighbourhood contains this one, so it is singular too.
        if (sv.singular && !pinv) break;
        sv.c.neighbors = 2 * n;
        cands.push_back(std::move(sv.c));
    }
    if (cands.empty()) {  // even the two nearest nodes coincide numerically: pseudo-inverse
        cands.push_back(solve(acf, s, tx2, ty2, class_offsets(o.dims, tx2, ty2, 1), true).c);
        cands.back().neighbors = 2;
    }
    size_t pick = cands.size() - 1;
    if (o.tolerance > 0) {  // §4.1: the smallest N within the threshold of the best error
        double best = cands[0].variance;
        for (const auto& c : cands) best = std::min(best, c.variance);
        for (pick = 0; cands[pick].variance > best + o.tolerance * r0; ++pick) {
        }
    }
    if (o.dims == 2 && o.debias > 0)  // §6.1: grow until the outer coefficients are negligible
        while (pick + 1 < cands.size() && ring_ratio(cands[pick]) > o.debias) ++pick;
    return cands[pick];
}

/// The smallest power of two T such that |R| <= c R(0) at every lag >= T along the axes and
/// diagonals (scanned to 2^22 at 1/64 of the lag).
int auto_top(const Acf& acf, int dims, double c, int limit) {
    const double r0 = acf.R(0, 0);
    const double d = std::sqrt(0.5);
    const double dirs[4][2] = {{1, 0}, {0, 1}, {d, d}, {d, -d}};
    double last = 0;
    for (double t = 1; t <= double(limit); t += std::max(1.0, t / 64))
        for (int k = 0; k < (dims == 1 ? 1 : 4); ++k)
            if (std::abs(acf.R(t * dirs[k][0], t * dirs[k][1])) > c * r0) last = t;
    int top = 1;
    while (top < last && top < (1 << 20)) top *= 2;
    return top;
}

}  // namespace

int LevelPlan::max_n() const {
    int n = 1;
    for (const auto& c : classes) n = std::max(n, c.neighbors / 2);
    return n;
}

int auto_top_spacing(const Acf& acf, const GssOptions& options, int limit) {
    return auto_top(acf, options.dims, options.top_correlation, std::min(limit, 1 << 22));
}

void validate(const GssOptions& o) {
    if (o.dims != 1 && o.dims != 2)
        throw ValueError("--dim " + std::to_string(o.dims) + ": expected 1 or 2");
    if (o.max_neighbors < 2 || o.max_neighbors > 16 || o.max_neighbors % 2)
        throw ValueError("--neighbors " + std::to_string(o.max_neighbors) +
                         ": expected an even neighbourhood size 2N in 2 .. 16");
    if (!(o.tolerance >= 0 && o.tolerance < 1))
        throw ValueError("--tolerance " + num(o.tolerance) +
                         ": expected a fraction of R(0) in [0, 1)");
    if (!(o.debias >= 0 && o.debias < 1))
        throw ValueError("--debias " + num(o.debias) + ": expected a coefficient ratio in [0, 1)");
    if (o.top_spacing < 0 || (o.top_spacing & (o.top_spacing - 1)) || o.top_spacing > (1 << 20))
        throw ValueError("--top-spacing " + std::to_string(o.top_spacing) +
                         ": expected a power of two up to 2^20 (0: automatic)");
    if (!(o.top_correlation > 0 && o.top_correlation < 1))
        throw ValueError("top_correlation = " + num(o.top_correlation) + ": expected in (0, 1)");
}

ClassCoefficients solve_class(const Acf& acf, double s, int tx2, int ty2,
                              const std::vector<std::pair<int, int>>& offsets, Singular singular) {
    Solved sv = solve(acf, s, tx2, ty2, offsets, true);
    if (sv.singular && singular == Singular::Reduce) sv.c.pseudo_inverse = true;
    return sv.c;
}

Plan plan_subdivision(const Acf& acf, const GssOptions& o, int top) {
    validate(o);
    Plan plan;
    plan.dims = o.dims;
    plan.variance = acf.R(0, 0);
    if (!(plan.variance > 0) || !std::isfinite(plan.variance))
        throw ValueError("autocorrelation " + acf.name + ": R(0) = " + num(plan.variance) +
                         ": expected a finite variance > 0");
    if (top == 0) top = o.top_spacing ? o.top_spacing : auto_top_spacing(acf, o);
    plan.top_spacing = top;
    struct Cls {
        const char* name;
        int tx2, ty2;
    };
    const std::vector<Cls> classes =
        o.dims == 1 ? std::vector<Cls>{{"mid", 1, 0}}
                    : std::vector<Cls>{{"face", 1, 1}, {"edge_x", 1, 0}, {"edge_y", 0, 1}};
    for (int s = top; s >= 2; s /= 2) {
        LevelPlan level;
        level.spacing = s / 2;
        for (const auto& k : classes) {
            level.classes.push_back(choose(acf, o, s, k.tx2, k.ty2));
            level.classes.back().name = k.name;
        }
        level.filter.radius = -1;
        if (o.correlated) level.filter = displacement_filter(acf, o.dims, s, level.classes);
        plan.levels.push_back(std::move(level));
    }
    return plan;
}

std::string plan_json(const Plan& plan) {
    std::ostringstream j;
    j.precision(17);
    auto list = [&](const std::vector<double>& a) {
        j << "[";
        for (size_t i = 0; i < a.size(); ++i) j << (i ? ", " : "") << a[i];
        j << "]";
    };
    j << "{\"dims\": " << plan.dims << ", \"top_spacing\": " << plan.top_spacing
      << ", \"variance\": " << plan.variance << ",\n \"levels\": [";
    for (size_t l = 0; l < plan.levels.size(); ++l) {
        const LevelPlan& lv = plan.levels[l];
        j << (l ? ",\n  " : "\n  ") << "{\"spacing\": " << lv.spacing
          << ", \"displacement_radius\": " << lv.filter.radius;
        if (plan.dims == 1) {
            const ClassCoefficients& c = lv.classes[0];
            j << ", \"neighbors\": " << c.neighbors << ", \"coefficients\": ";
            list(c.a);
            j << ", \"variance\": " << c.variance
              << ", \"pseudo_inverse\": " << (c.pseudo_inverse ? "true" : "false") << "}";
            continue;
        }
        // 2-D: one entry per class; coefficients row-major over the offsets (c, r).
        for (const char* key : {"neighbors", "coefficients", "variance", "offsets"}) {
            j << ", \"" << key << "\": {";
            for (size_t k = 0; k < lv.classes.size(); ++k) {
                const ClassCoefficients& c = lv.classes[k];
                j << (k ? ", " : "") << "\"" << c.name << "\": ";
                if (key[0] == 'n') j << c.neighbors;
                if (key[0] == 'c') list(c.a);
                if (key[0] == 'v') j << c.variance;
                if (key[0] == 'o') {
                    j << "[";
                    for (size_t i = 0; i < c.offsets.size(); ++i)
                        j << (i ? ", " : "") << "[" << c.offsets[i].first << ", "
                          << c.offsets[i].second << "]";
                    j << "]";
                }
            }
            j << "}";
        }
        j << "}";
    }
    j << "\n ]}\n";
    return j.str();
}

}  // namespace impulse::synth
