// SPDX-License-Identifier: Apache-2.0
// Generalized stochastic subdivision (synth/subdivision.h, docs/subdivision.md): the
// coefficients against their closed forms (Lewis 1987 §4.1, §6.2), the measured
// autocorrelation against the construction's exact covariance and the specified R, creases,
// refinement, extension, singular and invalid autocorrelations.

#include <Eigen/Dense>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <string>

#include "synth/synth.h"
#include "numeric/errors.h"

using namespace impulse;
using namespace impulse::synth;

namespace {

GssOptions opts(int dims, int neighbors, double tolerance = 0, double debias = 0) {
    GssOptions o;
    o.dims = dims;
    o.max_neighbors = neighbors;
    o.tolerance = tolerance;
    o.debias = debias;
    return o;
}

/// Exact covariance of the periodic construction with `plan` on P (x P) nodes: level by level
/// x_fine = T x_coarse + U w (Lewis 1987 eq. 3, 9, 10; U the displacement filter, diagonal for
/// the paper's independent displacements), so C_fine = T C_coarse T^T + U U^T, from
/// independent top nodes of variance R(0).
Eigen::MatrixXd construction_cov(const Plan& plan, int P) {
    const int dims = plan.dims;
    int m = P / plan.top_spacing, my = dims == 1 ? 1 : m;
    Eigen::MatrixXd C = plan.variance * Eigen::MatrixXd::Identity(m * my, m * my);
    for (const LevelPlan& lv : plan.levels) {
        const int mf = 2 * m, mfy = dims == 1 ? 1 : 2 * my;
        Eigen::MatrixXd T = Eigen::MatrixXd::Zero(mf * mfy, m * my);
        // U maps the keyed normals of the new nodes (by fine row) to their displacements.
        Eigen::MatrixXd U = Eigen::MatrixXd::Zero(mf * mfy, mf * mfy);
        const int K = int(lv.classes.size()), J = lv.filter.radius, side = 2 * J + 1;
        for (int j = 0; j < mfy; ++j)
            for (int i = 0; i < mf; ++i) {
                const int row = j * mf + i;
                if (!(i & 1) && !(j & 1)) {
                    T(row, (j / 2) * m + i / 2) = 1;
                    continue;
                }
                const int k = dims == 1 ? 0 : ((i & 1) && (j & 1) ? 0 : ((i & 1) ? 1 : 2));
                const ClassCoefficients& c = lv.classes[size_t(k)];
                for (size_t q = 0; q < c.a.size(); ++q) {
                    const int cx = ((i / 2 + c.offsets[q].first) % m + m) % m;
                    const int cy = dims == 1 ? 0 : ((j / 2 + c.offsets[q].second) % my + my) % my;
                    T(row, cy * m + cx) += c.a[q];
                }
                if (J < 0) {  // independent displacements
                    U(row, row) = std::sqrt(c.variance);
                    continue;
                }
                const int box = dims == 1 ? side : side * side;
                for (int k2 = 0; k2 < K; ++k2)
                    for (int jy = (dims == 1 ? 0 : -J); jy <= (dims == 1 ? 0 : J); ++jy)
                        for (int jx = -J; jx <= J; ++jx) {
                            const int cx = ((i / 2 + jx) % m + m) % m;
                            const int cy = dims == 1 ? 0 : ((j / 2 + jy) % my + my) % my;
                            const auto& c2 = lv.classes[size_t(k2)];
                            const int col = (2 * cy + c2.ty2) * mf + 2 * cx + c2.tx2;
                            U(row, col) += lv.filter.beta[size_t(
                                (k * K + k2) * box + (dims == 1 ? 0 : (jy + J) * side) + jx + J)];
                        }
            }
        C = T * C * T.transpose() + U * U.transpose();
        m = mf, my = mfy;
    }
    return C;
}

/// Mean over the periodic field of x(p) x(p + lag): its expectation under covariance C and
/// the standard deviation of one field's value (Isserlis: Var sum x_i y_i = sum_ij C_ij
/// C_i'j' + C_ij' C_i'j, primes the shifted indices).
struct LagStat {
    double mean = 0, sd = 0;
};
LagStat lag_stat(const Eigen::MatrixXd& C, int P, int dims, int dx, int dy) {
    const int ny = dims == 1 ? 1 : P, n = P * ny;
    auto shift = [&](int p) {
        const int x = p % P, y = p / P;
        return ((y + dy) % ny) * P + (x + dx) % P;
    };
    LagStat s;
    double var = 0;
    for (int i = 0; i < n; ++i) {
        s.mean += C(i, shift(i));
        for (int j = 0; j < n; ++j)
            var += C(i, j) * C(shift(i), shift(j)) + C(i, shift(j)) * C(shift(i), j);
    }
    s.mean /= n;
    s.sd = std::sqrt(var) / n;
    return s;
}

double measured_lag(const Field& f, int P, int dims, int dx, int dy) {
    const int ny = dims == 1 ? 1 : P;
    double sum = 0;
    for (int y = 0; y < ny; ++y)
        for (int x = 0; x < P; ++x)
            sum += f.values[size_t(y) * P + x] * f.values[size_t((y + dy) % ny) * P + (x + dx) % P];
    return sum / (double(P) * ny);
}

struct AcfCheck {
    double worst_z = 0;       ///< max |measured - construction| / sampling sd over the lags
    double construction = 0;  ///< max |construction - specified R| over the lags
};

/// `seeds` periodic fields: the measured mean products against the construction's exact
/// expectation, in units of their sampling standard deviation.
AcfCheck check_acf(const Acf& acf, GssOptions o, int P, int seeds,
                   const std::vector<std::pair<int, int>>& lags) {
    const int dims = o.dims;
    std::vector<double> sum(lags.size(), 0.0);
    const Plan plan = synthesize(acf, o, 0, 0, P, dims == 1 ? 1 : P, true).plan;
    for (int s = 0; s < seeds; ++s) {
        o.seed = uint64_t(s);
        const Field f = synthesize(plan, o, 0, 0, P, dims == 1 ? 1 : P, true);
        for (size_t k = 0; k < lags.size(); ++k)
            sum[k] += measured_lag(f, P, dims, lags[k].first, lags[k].second);
    }
    const Eigen::MatrixXd C = construction_cov(plan, P);
    AcfCheck out;
    for (size_t k = 0; k < lags.size(); ++k) {
        const LagStat st = lag_stat(C, P, dims, lags[k].first, lags[k].second);
        const double meas = sum[k] / seeds;
        out.worst_z = std::max(out.worst_z, std::abs(meas - st.mean) / (st.sd / std::sqrt(seeds)));
        out.construction =
            std::max(out.construction, std::abs(st.mean - acf.R(lags[k].first, lags[k].second)));
    }
    return out;
}

}  // namespace

TEST_CASE("gss: markov puts equal weights R(1/2)/(R(0)+R(1)) on the two nearest nodes only",
          "[synth]") {
    // Lewis 1987 §4.1: "the solution for the Markovian autocorrelation function should reduce
    // to fractal subdivision". With 2N = 8 forced (tolerance 0) six coefficients must vanish.
    const double l = 10;
    const Acf acf = make_acf("markov", {{"length", "10"}});
    const Plan plan = plan_subdivision(acf, opts(1, 8), 64);
    REQUIRE(plan.levels.size() == 6);
    for (const LevelPlan& lv : plan.levels) {
        const ClassCoefficients& c = lv.classes[0];
        REQUIRE(c.a.size() == 8);
        const double s = 2.0 * lv.spacing;
        const double expect = std::exp(-s / 2 / l) / (1 + std::exp(-s / l));
        for (size_t k = 0; k < c.a.size(); ++k) {
            const int off = c.offsets[k].first;
            if (off == 0 || off == 1)
                CHECK(c.a[k] == Approx(expect).epsilon(1e-10));
            else
                CHECK(std::abs(c.a[k]) < 1e-10);  // solver rounding: cond(A) <~ 1e3
        }
        // eq. 7 with the two weights: R(0) - 2 a R(1/2).
        CHECK(c.variance == Approx(1 - 2 * expect * std::exp(-s / 2 / l)).epsilon(1e-10));
    }
}

TEST_CASE(
    "gss: a separable markov puts all the weight on the four nearest vertices, an "
    "isotropic one does not",
    "[synth]") {
    const double l = 6;
    const Plan sep =
        plan_subdivision(make_acf("markov", {{"length", "6"}, {"separable", "1"}}), opts(2, 4), 16);
    const Plan iso = plan_subdivision(make_acf("markov", {{"length", "6"}}), opts(2, 4), 16);
    for (size_t lvl = 0; lvl < sep.levels.size(); ++lvl) {
        const double s = 2.0 * sep.levels[lvl].spacing;
        const double w = std::exp(-s / 2 / l) / (1 + std::exp(-s / l));  // the 1-D weight
        for (const ClassCoefficients& c : sep.levels[lvl].classes) {
            // Face: w^2 on its four corners; edge: w on the edge's two ends (Lewis 1987 §6.2).
            for (size_t k = 0; k < c.a.size(); ++k) {
                const auto [cx, ry] = c.offsets[k];
                const bool near_x = c.tx2 ? (cx == 0 || cx == 1) : cx == 0;
                const bool near_y = c.ty2 ? (ry == 0 || ry == 1) : ry == 0;
                const double expect = near_x && near_y ? std::pow(w, c.tx2 + c.ty2) : 0.0;
                CHECK(c.a[k] == Approx(expect).margin(1e-10));
            }
        }
        // Isotropic exp(-r/l): the face coefficients beyond the four corners are not zero.
        const ClassCoefficients& f = iso.levels[lvl].classes[0];
        double outer = 0;
        for (size_t k = 0; k < f.a.size(); ++k) {
            const auto [cx, ry] = f.offsets[k];
            if (!((cx == 0 || cx == 1) && (ry == 0 || ry == 1)))
                outer = std::max(outer, std::abs(f.a[k]));
        }
        CHECK(outer > 1e-3);
    }
}

TEST_CASE(
    "gss: the measured autocorrelation is the construction's, and for markov the "
    "specified one, within the sampling band",
    "[synth]") {
    // Each check: mean of x(p) x(p + lag) over 1-D fields of 512 (2-D: 32 x 32) periodic
    // nodes and many seeds, against the exact covariance of the construction (propagated
    // level by level); 5 sampling standard deviations (Isserlis, from that covariance).
    const std::vector<std::pair<int, int>> lags1 = {{0, 0}, {1, 0}, {2, 0},  {3, 0},
                                                    {5, 0}, {8, 0}, {13, 0}, {21, 0}};
    SECTION("markov 1-D: exact (Markov property)") {
        const AcfCheck c =
            check_acf(make_acf("markov", {{"length", "8"}}), opts(1, 8, 1e-4), 512, 200, lags1);
        CHECK(c.worst_z < 5);
        // The only departure from R: the independent top nodes (|R(top)| <= 1e-3 R(0)).
        CHECK(c.construction < 2e-3);
    }
    SECTION("gaussian 1-D") {
        const AcfCheck c =
            check_acf(make_acf("gaussian", {{"length", "6"}}), opts(1, 8, 1e-4), 512, 200, lags1);
        CHECK(c.worst_z < 5);
        WARN("gaussian 1-D: construction - R up to " << c.construction);
        CHECK(c.construction < 0.01);  // correlated displacements (docs/subdivision.md)
    }
    SECTION("gaussian 1-D, the paper's independent displacements") {
        GssOptions o = opts(1, 8, 1e-4);
        o.correlated = false;
        const AcfCheck c = check_acf(make_acf("gaussian", {{"length", "6"}}), o, 512, 200, lags1);
        CHECK(c.worst_z < 5);
        WARN("gaussian 1-D, independent displacements: construction - R up to " << c.construction);
        CHECK(c.construction > 0.03);  // what the correlated displacements remove
    }
    SECTION("oscillatory markov 1-D (Lewis 1987 Table 1)") {
        const AcfCheck c =
            check_acf(make_acf("oscillatory_markov", {{"length", "16"}, {"omega", "0.5"}}),
                      opts(1, 8, 1e-4), 512, 200, lags1);
        CHECK(c.worst_z < 5);
        WARN("oscillatory markov 1-D: construction - R up to " << c.construction);
        CHECK(c.construction < 0.01);
    }
    SECTION("bandpass 1-D (a model defined by its spectrum, R by its inverse transform)") {
        // A ring of frequencies around f0 = 0.08 cycles a sample: R oscillates with period
        // ~12 samples, which the lags 3, 5, 8 and 13 see.
        const AcfCheck c = check_acf(make_acf("bandpass", {{"f0", "0.08"}, {"width", "0.02"}}),
                                     opts(1, 8, 1e-4), 512, 200, lags1);
        CHECK(c.worst_z < 5);
        WARN("bandpass 1-D: construction - R up to " << c.construction);
        CHECK(c.construction < 0.02);
    }
    SECTION("anisotropic 2-D (stretched markaussian)") {
        const std::vector<std::pair<int, int>> lags2 = {{0, 0}, {1, 0}, {0, 1}, {1, 1},
                                                        {3, 0}, {0, 3}, {2, 2}, {4, 1}};
        const AcfCheck c =
            check_acf(make_acf("markaussian", {{"length", "2"}, {"aspect", "3"}, {"angle", "30"}}),
                      opts(2, 4, 1e-4, 0.05), 32, 150, lags2);
        CHECK(c.worst_z < 5);
        WARN("anisotropic 2-D: construction - R up to " << c.construction);
        CHECK(c.construction < 0.2);
    }
}

TEST_CASE(
    "gss: 2-D fields measure the specified autocorrelation up to the construction's "
    "documented departure",
    "[synth]") {
    // Extendable 129^2 fields, 12 seeds: the mean of x(p) x(p + lag) against R. Band: 5
    // standard errors from the seeds' spread plus the departure of the 2-D construction from R
    // (docs/subdivision.md: 0.06 to 0.12 R(0) here, the displacement filter being truncated at
    // 4 cells).
    const std::vector<std::pair<int, int>> lags = {{0, 0}, {1, 0}, {0, 1}, {1, 1},
                                                   {3, 0}, {0, 3}, {2, 2}, {6, 0}};
    const std::vector<std::pair<std::string, std::vector<AcfParam>>> models = {
        {"markov", {{"length", "6"}}},
        {"gaussian", {{"length", "4"}}},
        {"expression", {{"expr", "exp(-abs(x)/12)*cos(0.6*x)*exp(-(y/12)^2)"}}},
        {"markaussian", {{"length", "3"}, {"aspect", "3"}, {"angle", "30"}}}};
    for (const auto& [model, params] : models) {
        const Acf acf = make_acf(model, params);
        GssOptions o = opts(2, 8, 1e-4, 0.05);
        const Plan plan = plan_subdivision(acf, o);
        const int n = 129, seeds = 12;
        std::vector<std::vector<double>> per(lags.size());
        for (int s = 0; s < seeds; ++s) {
            o.seed = uint64_t(s);
            const Field f = synthesize(plan, o, 0, 0, n, n);
            for (size_t k = 0; k < lags.size(); ++k) {
                const auto [dx, dy] = lags[k];
                double sum = 0;
                for (int y = 0; y + dy < n; ++y)
                    for (int x = 0; x + dx < n; ++x)
                        sum += f.values[size_t(y) * n + x] * f.values[size_t(y + dy) * n + x + dx];
                per[k].push_back(sum / (double(n - dx) * (n - dy)));
            }
        }
        double worst = 0;
        for (size_t k = 0; k < lags.size(); ++k) {
            double m = 0, m2 = 0;
            for (double v : per[k]) m += v, m2 += v * v;
            m /= seeds;
            const double se = std::sqrt((m2 / seeds - m * m) / (seeds - 1));
            const double err = std::abs(m - acf.R(lags[k].first, lags[k].second));
            worst = std::max(worst, err);
            CAPTURE(model, lags[k].first, lags[k].second, m, se);
            CHECK(err < 5 * se + 0.1 * acf.R(0, 0));
        }
        WARN(model << " 2-D: max |measured - R| = " << worst);
    }
}

TEST_CASE(
    "gss: no creases: second differences have the same statistics on every level's "
    "nodes",
    "[synth]") {
    // d_i = x_{i-1} - 2 x_i + x_{i+1}, E d^2 = 6 R(0) - 8 R(1) + 2 R(2) at every node of a
    // stationary field. Nodes grouped by the level that made them (trailing zero bits of i).
    auto spread = [](const Acf& acf, int neighbors, double& worst_z) {
        GssOptions o = opts(1, neighbors);
        std::vector<std::vector<double>> per_seed;
        const int seeds = 16, n = 32769, groups = 6;
        const Plan plan = plan_subdivision(acf, o);
        for (int s = 0; s < seeds; ++s) {
            o.seed = uint64_t(s);
            const Field f = synthesize(plan, o, 0, 0, n, 1);
            std::vector<double> sum(groups, 0.0), cnt(groups, 0.0);
            for (int i = 1; i + 1 < n; ++i) {
                const int g = std::min(__builtin_ctz(unsigned(i)), groups - 1);
                const double d = f.values[i - 1] - 2 * f.values[i] + f.values[i + 1];
                sum[g] += d * d, cnt[g] += 1;
            }
            for (int g = 0; g < groups; ++g) sum[g] /= cnt[g];
            per_seed.push_back(sum);
        }
        const double theory = 6 * acf.R(0, 0) - 8 * acf.R(1, 0) + 2 * acf.R(2, 0);
        double lo = 1e300, hi = 0;
        worst_z = 0;
        for (int g = 0; g < groups; ++g) {
            double m = 0, m2 = 0;
            for (const auto& v : per_seed) m += v[g], m2 += v[g] * v[g];
            m /= seeds;
            const double se = std::sqrt((m2 / seeds - m * m) / (seeds - 1));  // standard error
            worst_z = std::max(worst_z, std::abs(m - theory) / se);
            lo = std::min(lo, m), hi = std::max(hi, m);
        }
        return hi / lo - 1;
    };
    double z = 0;
    // Markov: the construction is exact, every level matches 6 R(0) - 8 R(1) + 2 R(2).
    const double markov = spread(make_acf("markov", {{"length", "12"}}), 8, z);
    CHECK(z < 5);
    CHECK(markov < 0.05);
    // Markaussian (a = 1.4): the midpoint of the two nearest nodes (Fournier et al., N = 1)
    // leaves creases, the 8-node Wiener estimate removes most of them.
    const Acf ma = make_acf("markaussian", {{"length", "12"}});
    const double fournier = spread(ma, 2, z);
    CHECK(z > 5);  // the test sees creases when the autocorrelation is ignored
    const double gss = spread(ma, 8, z);
    WARN("crease excess: markov " << markov << ", markaussian 2N = 2: " << fournier
                                  << ", 2N = 8: " << gss);
    CHECK(fournier > 0.2);
    CHECK(gss < fournier / 4);
}

TEST_CASE("gss: refined output keeps the coarse samples bit-exactly", "[synth]") {
    for (int dims : {1, 2}) {
        const int w = 9, h = dims == 1 ? 1 : 7, F = 4;
        std::vector<double> data(size_t(w) * h);
        for (size_t i = 0; i < data.size(); ++i)
            data[i] = double(float(std::sin(1.7 * double(i)) * 3 + 0.1 * double(i)));
        const Acf acf = make_acf("markaussian", {{"length", "6"}});
        const Field f = refine(data, w, h, F, acf, opts(dims, 8, 1e-4, 0.05));
        REQUIRE(f.width == (w - 1) * F + 1);
        REQUIRE(f.height == (h - 1) * F + 1);
        int differing_new = 0;
        for (int y = 0; y < f.height; ++y)
            for (int x = 0; x < f.width; ++x) {
                const double v = f.values[size_t(y) * f.width + x];
                if (x % F == 0 && y % F == 0)
                    CHECK(std::bit_cast<uint32_t>(float(v)) ==
                          std::bit_cast<uint32_t>(float(data[size_t(y / F) * w + x / F])));
                else
                    differing_new += std::isfinite(v);
            }
        CHECK(differing_new == f.width * f.height - w * h);
    }
}

TEST_CASE("gss: an extended region matches the original in the overlap", "[synth]") {
    const Acf acf = make_acf("gaussian", {{"length", "5"}});
    for (int dims : {1, 2}) {
        const GssOptions o = opts(dims, 8, 1e-4, 0.05);
        const Field a = synthesize(acf, o, 0, 0, 65, dims == 1 ? 1 : 65);
        const Field b = synthesize(acf, o, -40, dims == 1 ? 0 : 24, 129, dims == 1 ? 1 : 129);
        int compared = 0, equal = 0;
        for (int y = 0; y < a.height; ++y)
            for (int x = 0; x < a.width; ++x) {
                const int64_t bx = a.x0 + x - b.x0, by = a.y0 + y - b.y0;
                if (bx < 0 || by < 0 || bx >= b.width || by >= b.height) continue;
                ++compared;
                equal += a.values[size_t(y) * a.width + x] ==
                         b.values[size_t(by) * b.width + size_t(bx)];
            }
        CHECK(compared == (dims == 1 ? 65 : 65 * 41));
        CHECK(equal == compared);
    }
}

TEST_CASE("gss: singular autocorrelations are solved by the paper's remedies, never refused",
          "[synth]") {
    const Acf g = make_acf("gaussian", {{"length", "40"}});
    for (Singular s : {Singular::Reduce, Singular::PseudoInverse}) {
        GssOptions o = opts(2, 8, 0);
        o.singular = s;
        const Plan p = plan_subdivision(g, o);
        bool remedied = false;
        for (const LevelPlan& lv : p.levels)
            for (const ClassCoefficients& c : lv.classes) {
                CHECK(std::isfinite(c.variance));
                CHECK(c.variance >= 0);
                for (double a : c.a) CHECK(std::isfinite(a));
                remedied |= c.pseudo_inverse || c.neighbors < 8;
            }
        CHECK(remedied);  // the fine levels of a length-40 gaussian are numerically singular
        const Field f = synthesize(g, o, 0, 0, 65, 65);
        for (double v : f.values) REQUIRE(std::isfinite(v));
    }
}

TEST_CASE("gss: the neighbourhood size follows the error threshold", "[synth]") {
    const Plan m = plan_subdivision(make_acf("markov", {{"length", "8"}}), opts(1, 8, 1e-4));
    for (const LevelPlan& lv : m.levels) CHECK(lv.classes[0].neighbors == 2);
    const Plan g = plan_subdivision(make_acf("gaussian", {{"length", "8"}}), opts(1, 8, 1e-4));
    int largest = 0;
    for (const LevelPlan& lv : g.levels) largest = std::max(largest, lv.classes[0].neighbors);
    CHECK(largest > 2);
}

TEST_CASE("gss: refuses what is not non-negative definite and sizes subdivision cannot make",
          "[synth]") {
    const Acf bad = make_acf("expression", {{"expr", "max(0, 1 - (r/8)^2)"}});
    CHECK_THROWS_AS(plan_subdivision(bad, opts(1, 8, 1e-4)), ValueError);
    const Acf ok = make_acf("markov", {{"length", "4"}});
    CHECK_THROWS_WITH(synthesize(ok, opts(1, 4), 0, 0, 1000, 1),
                      Catch::Contains("2^k + 1 samples per axis"));
    CHECK_THROWS_WITH(synthesize(ok, opts(2, 4), 0, 0, 65, 65, true),
                      Catch::Contains("periodic output needs 2^k"));
    CHECK_THROWS_WITH(refine(std::vector<double>(9, 0.0), 9, 1, 3, ok, opts(1, 4)),
                      Catch::Contains("power of two"));
    CHECK_THROWS_WITH(make_acf("markov", {{"lenght", "4"}}), Catch::Contains("unknown key"));
}

TEST_CASE("gss: the eq. 15 estimate of data", "[synth]") {
    // A synthesized markov field sampled every 4th node: the estimate's R^(0) is the data's
    // variance, and the fitted model is a decreasing correlation.
    const Field f =
        synthesize(make_acf("markov", {{"length", "16"}}), opts(2, 4, 1e-4, 0.05), 0, 0, 257, 257);
    std::vector<double> d;
    for (int y = 0; y < 257; y += 4)
        for (int x = 0; x < 257; x += 4) d.push_back(f.values[size_t(y) * 257 + x]);
    const AcfEstimate e = estimate_acf(d, 65, 65, 4);
    double m = 0, v = 0;
    for (double x : d) m += x;
    m /= double(d.size());
    for (double x : d) v += (x - m) * (x - m);
    CHECK(e.variance == Approx(v / double(d.size())).epsilon(1e-12));
    CHECK(e.acf.R(0, 0) == Approx(e.variance));
    CHECK(e.acf.R(8, 0) < e.acf.R(4, 0));
    CHECK(e.summary.find("eq. 15") != std::string::npos);
}
