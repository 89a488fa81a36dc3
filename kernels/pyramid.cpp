// SPDX-License-Identifier: Apache-2.0
// Band-limited kernel pyramid (Lewis 1986 §3.1): the kernel low-passed by Gaussian pixel filters
// at half-octave scales, with the tables the perspective evaluator reads.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>

#include <tbb/parallel_for.h>

#include "numeric/fft.h"
#include "kernels/kernels.h"
#include "kernels/quadrature.h"
#include "numeric/errors.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kRadialSamples = 257;   // profile samples over [0, R_l] (Catmull–Rom in r)
constexpr int kTableSize = 2049;      // q-table of a radial level
constexpr int kLineSize = 513;        // line (Abel) tables of a radial level
constexpr int kMaxGridHalf = 128;     // grid levels: at most 257 x 257 samples
constexpr double kSupportSigmas = 4;  // support of level l: R + 4 sigma_l
// Axial tables (RadialLevelTables::axial). The perspective evaluator blurs a level along the
// footprint's major axis by less than R_l / 4 (beyond, its line form takes over) on top of at
// most the level's own sigma_l <= R_l / 4 when it blends the level with the next one:
// sqrt(2) / 4 = 0.354 of R_l at most. Linear interpolation in the variance between slices errs
// by about (dvar)^2 / 32 |d^4h/du^4|: 5e-4 of the cosine kernel's peak with 8 steps. The samples:
// bilinear interpolation errs by d^2 / 8 |h''|, 6e-4 of the peak across (d = R_l / 32), less
// along (the blur smooths it).
constexpr int kAxialSlices = 9;
constexpr double kAxialMaxSd = 0.375;  // of R_l
constexpr int kAxialAlong = 49, kAxialAcross = 33;
constexpr int kAxialNodes = 256;  // midpoint rule along u over [-R_l, R_l]

/// e^-x I0(x) for x >= 0 to about 1e-15 relative: the power series sum (x^2/4)^k / (k!)^2 up to
/// x = 20 (terms peak near 1e7 there, so rounding keeps ~15 digits), Hankel's asymptotic
/// series 1/sqrt(2 pi x) sum ((2k-1)!!)^2 / (k! (8x)^k) beyond (smallest term < 1e-17).
double i0e(double x) {
    if (x <= 20.0) {
        const double y = 0.25 * x * x;
        double term = 1.0, sum = 1.0;
        for (int k = 1; k < 200; ++k) {
            term *= y / (double(k) * k);
            sum += term;
            if (term < 1e-17 * sum) break;
        }
        return sum * std::exp(-x);
    }
    double term = 1.0, sum = 1.0;
    for (int k = 1; k < 40; ++k) {
        const double next = term * (2.0 * k - 1.0) * (2.0 * k - 1.0) / (8.0 * k * x);
        if (next > term) break;  // the asymptotic series starts to diverge
        term = next;
        sum += term;
        if (term < 1e-17) break;
    }
    return sum / std::sqrt(2.0 * kPi * x);
}

/// The radial kernel h(r) of a radial base.
double radial_value(const Kernel& k, double r) {
    const double R = k.radius();
    return k.envelope(r * r / (R * R));
}

/// (h * g_s)(r) for a radial kernel: the angular integral of the 2-D convolution in closed form,
/// int_0^2pi exp(r p cos(phi) / s^2) dphi = 2 pi I0(r p / s^2).
double radial_low_pass_at(const Kernel& base, double s, double r) {
    const double R = base.radius();
    const double a = std::max(0.0, r - 8.0 * s), b = std::min(R, r + 8.0 * s);
    if (!(a < b)) return 0.0;
    // Panels no wider than s/2 (the Gaussian) nor R/16 (the kernel's own shape; 16-point rule).
    const int panels =
        std::max(1, static_cast<int>(std::ceil((b - a) / std::min(0.5 * s, R / 16.0))));
    const double inv_s2 = 1.0 / (s * s);
    return detail::integrate(
        [&](double p) {
            const double d = r - p;
            return radial_value(base, p) * p * inv_s2 * std::exp(-0.5 * d * d * inv_s2) *
                   i0e(r * p * inv_s2);
        },
        a, b, panels);
}

/// The kernel in its own frame (orientation 0), for sampling grids.
Kernel unrotated(const Kernel& k) {
    KernelParams p = k.params();
    p.orientation = 0.0;
    return Kernel(p);
}

/// Spacing that resolves the unfiltered kernel on a grid (narrow axis R / aspect, carrier).
double base_spacing(const Kernel& k) {
    const auto& p = k.params();
    double d = std::min(p.radius / 48.0, p.radius / (16.0 * p.aspect));
    if (k.has_carrier() && p.frequency > 0.0) d = std::min(d, 1.0 / (10.0 * p.frequency));
    if (k.is_grid()) d = std::min(d, 2.0 * p.radius / (p.sampled->n - 1));
    return std::max(d, p.radius / kMaxGridHalf);
}

/// The unfiltered kernel on the grid x_i = -R + i d, i = 0 .. 2m (d = R / m), row-major.
std::vector<double> sample_grid(const Kernel& k0, int m) {
    const double R = k0.radius(), d = R / m;
    const int n = 2 * m + 1;
    std::vector<double> v(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) v[size_t(j) * n + i] = k0.evaluate(-R + i * d, -R + j * d);
    return v;
}

Kernel grid_low_pass(const Kernel& base, double s) {
    const Kernel k0 = unrotated(base);
    const double R = base.radius(), Rl = R + kSupportSigmas * s;
    // Fine samples of h (spacing db), then the separable Gaussian sum onto the level's grid
    // (spacing dl, coarser once the filter is wide: h_l is smooth at scale s).
    const int mb = std::clamp(static_cast<int>(std::ceil(R / base_spacing(base))), 8, kMaxGridHalf);
    const double db = R / mb;
    const int nb = 2 * mb + 1;
    const std::vector<double> h = sample_grid(k0, mb);
    const int ml =
        std::clamp(static_cast<int>(std::ceil(Rl / std::max(db, s / 6.0))), 8, kMaxGridHalf);
    const double dl = Rl / ml;
    const int nl = 2 * ml + 1;
    // Weights: the Gaussian sampled at the input nodes, normalised by its sum over the whole
    // (unbounded) lattice so the discrete filter keeps the integral even when s ~ db; nodes
    // outside [-R, R] carry h = 0 and are left out of the product only.
    std::vector<double> w(size_t(nl) * nb);
    for (int o = 0; o < nl; ++o) {
        const double xo = -Rl + o * dl;
        const double c = (xo + R) / db;  // output point in input-lattice units
        // Beyond s = 2 db the lattice sum equals sqrt(2 pi) s / db to double precision.
        double norm = std::sqrt(2.0 * kPi) * s / db;
        if (s < 2.0 * db) {
            norm = 0.0;
            for (int i = static_cast<int>(std::floor(c - 12.0 * s / db)) - 1;
                 i <= static_cast<int>(std::ceil(c + 12.0 * s / db)) + 1; ++i) {
                const double d = (c - i) * db;
                norm += std::exp(-0.5 * d * d / (s * s));
            }
        }
        for (int i = 0; i < nb; ++i) {
            const double d = xo - (-R + i * db);
            w[size_t(o) * nb + i] = std::exp(-0.5 * d * d / (s * s)) / norm;
        }
    }
    std::vector<double> a(size_t(nl) * nb);  // a[j_in][x_out]
    for (int j = 0; j < nb; ++j)
        for (int o = 0; o < nl; ++o) {
            double sum = 0.0;
            const double* wr = &w[size_t(o) * nb];
            const double* hr = &h[size_t(j) * nb];
            for (int i = 0; i < nb; ++i) sum += wr[i] * hr[i];
            a[size_t(j) * nl + o] = sum;
        }
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = false;
    sk->n = nl;
    sk->values.assign(size_t(nl) * nl, 0.0);
    for (int oy = 0; oy < nl; ++oy) {
        const double* wr = &w[size_t(oy) * nb];
        for (int ox = 0; ox < nl; ++ox) {
            double sum = 0.0;
            for (int j = 0; j < nb; ++j) sum += wr[j] * a[size_t(j) * nl + ox];
            sk->values[size_t(oy) * nl + ox] = sum;
        }
    }
    KernelParams p;
    p.type = KernelType::Sampled;
    p.radius = Rl;
    p.orientation = base.params().orientation;
    p.sampled = std::move(sk);
    return Kernel(p);
}

Kernel radial_low_pass(const Kernel& base, double s) {
    const double Rl = base.radius() + kSupportSigmas * s;
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = true;
    sk->n = kRadialSamples;
    sk->values.resize(kRadialSamples);
    // The samples are independent quadratures (the level's whole cost, ~5 ms each, ~20 levels
    // a pyramid): side by side, each the same bits as alone.
    tbb::parallel_for(0, kRadialSamples, [&](int i) {
        sk->values[size_t(i)] = radial_low_pass_at(base, s, Rl * i / (kRadialSamples - 1));
    });
    KernelParams p;
    p.type = KernelType::Sampled;
    p.radius = Rl;
    p.sampled = std::move(sk);
    return Kernel(p);
}

/// Largest sigma with ||h - h * g_sigma|| <= tol ||h||, from the DFT of the kernel sampled on
/// a grid padded twice (|H|^2 (1 - G)^2 summed over frequencies; bisection in log sigma).
double derive_sigma0(const Kernel& base, double tol) {
    const Kernel k0 = unrotated(base);
    const double R = base.radius();
    const int m = std::clamp(static_cast<int>(std::ceil(R / base_spacing(base))), 16, kMaxGridHalf);
    const double d = R / m;
    const int n = 2 * m + 1;
    const std::vector<double> h = sample_grid(k0, m);
    int N = 16;
    while (N < 2 * n) N *= 2;
    numeric::RealFft2d fft(N, N, numeric::FftPlans::Forward);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) fft.real()[size_t(j) * N + i] = h[size_t(j) * n + i];
    fft.forward();
    const int hc = fft.half_cols();
    std::vector<double> p2(size_t(N) * hc), k2(size_t(N) * hc);
    double total = 0.0;
    for (int ky = 0; ky < N; ++ky)
        for (int kx = 0; kx < hc; ++kx) {
            const double fy = (ky <= N / 2 ? ky : ky - N) / (N * d), fx = kx / (N * d);
            // Half spectrum: columns 1 .. N/2-1 stand for two frequencies.
            const double mult = (kx == 0 || kx == N / 2) ? 1.0 : 2.0;
            const double a = std::norm(fft.spectrum()[size_t(ky) * hc + kx]) * mult;
            p2[size_t(ky) * hc + kx] = a;
            k2[size_t(ky) * hc + kx] = fx * fx + fy * fy;
            total += a;
        }
    auto rel = [&](double s) {
        double e = 0.0;
        for (size_t i = 0; i < p2.size(); ++i) {
            const double g = 1.0 - std::exp(-2.0 * kPi * kPi * s * s * k2[i]);
            e += p2[i] * g * g;
        }
        return std::sqrt(e / total);
    };
    double lo = 1e-3 * R, hi = 0.25 * R;
    if (rel(hi) <= tol) return hi;
    if (rel(lo) > tol) return lo;
    for (int it = 0; it < 40; ++it) {
        const double mid = std::sqrt(lo * hi);
        (rel(mid) <= tol ? lo : hi) = mid;
        if (hi / lo < 1.001) break;
    }
    return lo;
}

/// The axial tables of a radial level: per row v_j, the level at the midpoints of kAxialNodes
/// steps of ds = 2 R_l / kAxialNodes along u, summed with Gaussian weights (the smallest blur,
/// sd = kAxialMaxSd R_l / sqrt(8), spans 17 steps: the midpoint rule is exact to ~1e-8 there).
void axial_tables(const Kernel& k, RadialLevelTables& t) {
    const double Rl = k.radius();
    const int nu = kAxialAlong, nv = kAxialAcross, ns = kAxialSlices, nn = kAxialNodes;
    t.axial_nu = nu, t.axial_nv = nv;
    t.axial_var_max = (kAxialMaxSd * Rl) * (kAxialMaxSd * Rl);
    t.axial.assign(size_t(ns) * nv * nu, 0.0f);
    t.axial_extent.resize(size_t(ns));
    const double ds = 2.0 * Rl / nn;
    auto h_at = [&](double u, double v) {
        const double r = std::sqrt(u * u + v * v);
        return r < Rl ? radial_value(k, r) : 0.0;
    };
    // h_l at (s_m, v_j), node-major: the sums below run over the rows j innermost (vectorised;
    // a sum over the nodes would be a serial reduction)
    std::vector<double> h(size_t(nv) * nn);
    for (int m = 0; m < nn; ++m)
        for (int j = 0; j < nv; ++j)
            h[size_t(m) * nv + j] = h_at(-Rl + (m + 0.5) * ds, Rl * j / (nv - 1));
    std::vector<double> col(static_cast<size_t>(nv));
    for (int s = 0; s < ns; ++s) {
        const double var = t.axial_var_max * s / (ns - 1), sd = std::sqrt(var);
        const double extent = Rl + 3.0 * sd;
        t.axial_extent[size_t(s)] = static_cast<float>(extent);
        float* slice = t.axial.data() + size_t(s) * nv * nu;
        // rows j < nv - 1 and columns i < nu - 1: the last ones stay 0
        for (int i = 0; i + 1 < nu; ++i) {
            const double u = extent * i / (nu - 1);
            if (s == 0) {
                for (int j = 0; j + 1 < nv; ++j)
                    slice[size_t(j) * nu + i] = static_cast<float>(h_at(u, Rl * j / (nv - 1)));
                continue;
            }
            // nodes within 8 sd of u (the weight beyond is below 1e-14)
            const int m0 = std::max(0, static_cast<int>((u - 8.0 * sd + Rl) / ds));
            const int m1 = std::min(nn, static_cast<int>((u + 8.0 * sd + Rl) / ds) + 1);
            // Gaussian weights on the uniform nodes by their ratio recurrence (three exp per
            // column, not one per node): g_(m+1) = g_m r_m, r_(m+1) = r_m exp(-ds^2 / var).
            const double d0 = u - (-Rl + (m0 + 0.5) * ds);
            double g = ds / std::sqrt(2.0 * kPi * var) * std::exp(-0.5 * d0 * d0 / var);
            double ratio = std::exp((d0 * ds - 0.5 * ds * ds) / var);
            const double step = std::exp(-ds * ds / var);
            std::fill(col.begin(), col.end(), 0.0);
            for (int m = m0; m < m1; ++m, g *= ratio, ratio *= step) {
                const double* hm = h.data() + size_t(m) * nv;
                for (int j = 0; j < nv; ++j) col[size_t(j)] += g * hm[j];
            }
            for (int j = 0; j + 1 < nv; ++j)
                slice[size_t(j) * nu + i] = static_cast<float>(col[size_t(j)]);
        }
    }
}

RadialLevelTables radial_tables(const Kernel& k) {
    RadialLevelTables t;
    const double Rl = k.radius();
    t.table.resize(kTableSize);
    double peak = 0.0, lowest = 0.0;
    for (int i = 0; i < kTableSize; ++i) {
        const double v = k.envelope(std::min(i / double(kTableSize - 1), 1.0 - 1e-12));
        t.table[size_t(i)] = static_cast<float>(v);
        peak = std::max(peak, std::abs(v));
        lowest = std::min(lowest, v);
    }
    t.nonnegative = lowest >= -1e-4 * peak;
    t.line_mass.resize(kLineSize);
    t.line_var.resize(kLineSize);
    t.line_k4.resize(kLineSize);
    for (int i = 0; i < kLineSize; ++i) {
        const double v = Rl * std::sqrt(i / double(kLineSize - 1));
        const double S = std::sqrt(std::max(0.0, Rl * Rl - v * v));
        double P = 0.0, Q = 0.0, Q4 = 0.0;
        if (S > 0.0) {
            // One pass over the Gauss–Legendre nodes for the three moments of the chord.
            const int panels = 8;
            const double* xs = detail::gl_nodes();
            const double* ws = detail::gl_weights();
            const double hp = S / panels;
            for (int pnl = 0; pnl < panels; ++pnl)
                for (int g = 0; g < detail::kGlPoints; ++g) {
                    const double s = (pnl + 0.5 * (1.0 + xs[g])) * hp;
                    const double wh = 0.5 * hp * ws[g] * radial_value(k, std::sqrt(s * s + v * v));
                    P += wh, Q += wh * s * s, Q4 += wh * s * s * s * s;
                }
            P *= 2.0, Q *= 2.0, Q4 *= 2.0;
        }
        const bool mass = P > 1e-12 * peak * Rl;
        const double q = mass ? std::max(0.0, Q / P) : 0.0;
        t.line_mass[size_t(i)] = static_cast<float>(P);
        t.line_var[size_t(i)] = static_cast<float>(q);
        t.line_k4[size_t(i)] = static_cast<float>(mass ? Q4 / P - 3.0 * q * q : 0.0);
    }
    axial_tables(k, t);
    return t;
}

/// Bilinear sample of an n x n grid over [-R, R]^2 (0 outside the disc of radius R).
double grid_at(const std::vector<float>& g, int n, double R, double x, double y) {
    if (!(x * x + y * y < R * R)) return 0.0;
    const double to = (n - 1) / (2.0 * R);
    const double gx = std::clamp((x + R) * to, 0.0, n - 1.0),
                 gy = std::clamp((y + R) * to, 0.0, n - 1.0);
    const int i = std::min(static_cast<int>(gx), n - 2), j = std::min(static_cast<int>(gy), n - 2);
    const double fx = gx - i, fy = gy - j;
    const float* r0 = g.data() + size_t(j) * n + i;
    const double top = r0[0] + fx * (r0[1] - r0[0]), bot = r0[n] + fx * (r0[n + 1] - r0[n]);
    return top + fy * (bot - top);
}

/// The chords of a grid level across direction gamma: mass, mean, variance, fourth cumulant
/// (trapezoid sums at the grid spacing along each chord).
DirectionalLineTables directional_tables(const std::vector<float>& g, int n, double R,
                                         double gamma) {
    constexpr int kSamples = 129;
    DirectionalLineTables t;
    t.mass.resize(kSamples), t.mean.resize(kSamples), t.var.resize(kSamples);
    t.k4.resize(kSamples);
    const double ex = std::cos(gamma), ey = std::sin(gamma);
    const double ds = 2.0 * R / (n - 1);
    for (int i = 0; i < kSamples; ++i) {
        const double v = R * (2.0 * i / (kSamples - 1) - 1.0);
        const double half = std::sqrt(std::max(0.0, R * R - v * v));
        const int m = static_cast<int>(std::ceil(half / ds));
        double M[5] = {0, 0, 0, 0, 0};
        for (int k = -m; k <= m; ++k) {
            const double sv = k * ds;
            const double h = grid_at(g, n, R, sv * ex - v * ey, sv * ey + v * ex) * ds;
            M[0] += h, M[1] += h * sv, M[2] += h * sv * sv, M[3] += h * sv * sv * sv;
            M[4] += h * sv * sv * sv * sv;
        }
        const double P = M[0];
        const bool mass = std::abs(P) > 1e-12;
        const double mu = mass ? M[1] / P : 0.0;
        const double var = mass ? std::max(0.0, M[2] / P - mu * mu) : 0.0;
        const double c4 = mass ? M[4] / P - 4.0 * mu * M[3] / P + 6.0 * mu * mu * M[2] / P -
                                     3.0 * mu * mu * mu * mu
                               : 0.0;
        t.mass[size_t(i)] = static_cast<float>(P);
        t.mean[size_t(i)] = static_cast<float>(mu);
        t.var[size_t(i)] = static_cast<float>(var);
        t.k4[size_t(i)] = static_cast<float>(mass ? c4 - 3.0 * var * var : 0.0);
    }
    return t;
}

}  // namespace

bool is_radial(const Kernel& k) {
    return !k.has_carrier() && !k.is_grid() && k.params().aspect == 1.0;
}

Kernel low_pass(const Kernel& base, double sigma) {
    if (!(sigma > 0.0) || !std::isfinite(sigma)) {
        std::ostringstream s;
        s << "low_pass: sigma = " << sigma << ": must be a finite number > 0";
        throw ValueError(s.str());
    }
    return is_radial(base) ? radial_low_pass(base, sigma) : grid_low_pass(base, sigma);
}

KernelPyramid::KernelPyramid(const Kernel& base, const PyramidParams& params) {
    static std::atomic<uint64_t> next_serial{1};
    m_serial = next_serial.fetch_add(1, std::memory_order_relaxed);
    if (!(params.sigma0 >= 0.0) || !std::isfinite(params.sigma0))
        throw ValueError("pyramid: sigma0 must be >= 0 (0: derived)");
    if (!(params.level0_tolerance > 0.0 && params.level0_tolerance <= 0.5))
        throw ValueError("pyramid: level0_tolerance must be in (0, 0.5]");
    if (!(params.min_sd_fraction > 0.0 && params.min_sd_fraction < 1.0))
        throw ValueError("pyramid: min_sd_fraction must be in (0, 1)");
    if (params.max_levels < 2) throw ValueError("pyramid: max_levels must be >= 2");
    m_radial = is_radial(base);
    const double s0 =
        params.sigma0 > 0.0 ? params.sigma0 : derive_sigma0(base, params.level0_tolerance);
    const double v0 = base.integral_sq();
    m_levels.push_back(base);
    m_sigma.push_back(s0);
    m_sd.push_back(1.0);
    for (int l = 1; l < params.max_levels; ++l) {
        const double s = s0 * std::exp2(0.5 * l);
        if (base.radius() + kSupportSigmas * s > kMaxKernelRadius) break;  // low_pass: R + 4 sigma
        m_levels.push_back(low_pass(base, s));
        m_sigma.push_back(s);
        m_sd.push_back(std::sqrt(std::max(0.0, m_levels.back().integral_sq() / v0)));
        if (m_sd.back() < params.min_sd_fraction) break;
    }
    if (m_radial) {
        for (const Kernel& k : m_levels) m_tables.push_back(radial_tables(k));
    } else {
        // Level 0 on a grid too (the perspective evaluator reads grids only).
        const Kernel k0 = unrotated(base);
        const int m = std::clamp(static_cast<int>(std::ceil(base.radius() / base_spacing(base))), 8,
                                 kMaxGridHalf);
        const std::vector<double> g0 = sample_grid(k0, m);
        m_grids.emplace_back(g0.begin(), g0.end());
        m_grid_n.push_back(2 * m + 1);
        for (size_t l = 1; l < m_levels.size(); ++l) {
            m_grids.push_back(m_levels[l].grid_values());
            m_grid_n.push_back(m_levels[l].params().sampled->n);
        }
        // Chords across directions for the perspective far field: a quarter turn in eighths
        // of pi when every level is point-symmetric (h(-x) = h(x): the chords across gamma
        // and gamma + pi are mirror images), else sixteen over a whole turn.
        bool symmetric = true;
        for (size_t l = 0; l < m_grids.size() && symmetric; ++l) {
            const auto& g = m_grids[l];
            const int n = m_grid_n[l];
            float peak = 0.0f;
            for (float v : g) peak = std::max(peak, std::abs(v));
            for (size_t k = 0; k < g.size() && symmetric; ++k)
                symmetric = std::abs(g[k] - g[g.size() - 1 - k]) <= 1e-5f * peak;
            (void)n;
        }
        m_direction_bins = symmetric ? 8 : 16;
        m_direction_period = symmetric ? kPi : 2.0 * kPi;
        m_directional.resize(m_grids.size() * size_t(m_direction_bins));
        for (size_t l = 0; l < m_grids.size(); ++l)
            for (int b = 0; b < m_direction_bins; ++b)
                m_directional[l * size_t(m_direction_bins) + size_t(b)] =
                    directional_tables(m_grids[l], m_grid_n[l], radius(int(l)),
                                       b * m_direction_period / m_direction_bins);
    }
    // Sign of each level (the line form and the far field need chords of one sign).
    for (int l = 0; l < levels(); ++l) {
        double peak = 0.0, lowest = 0.0;
        if (m_radial) {
            m_nonnegative.push_back(m_tables[size_t(l)].nonnegative);
            continue;
        }
        for (float v : m_grids[size_t(l)])
            peak = std::max(peak, double(std::abs(v))), lowest = std::min(lowest, double(v));
        m_nonnegative.push_back(lowest >= -1e-4 * peak);
    }
}

double KernelPyramid::sd_fraction(double sigma) const {
    if (!(sigma > m_sigma.front())) return 1.0;
    const size_t L = m_sigma.size() - 1;
    if (sigma >= m_sigma[L]) return m_sd[L] * m_sigma[L] / sigma;
    const double x = 2.0 * std::log2(sigma / m_sigma.front());
    const size_t l = std::min(static_cast<size_t>(x), L - 1);
    const double w = x - static_cast<double>(l);
    const double a = std::max(m_sd[l], 1e-300), b = std::max(m_sd[l + 1], 1e-300);
    return std::exp((1.0 - w) * std::log(a) + w * std::log(b));
}

KernelPyramid::Blend KernelPyramid::select(double sigma, bool blend) const {
    const int L = levels() - 1;
    if (!(sigma > m_sigma.front())) return {0, 0, 0.0};
    if (sigma >= m_sigma[size_t(L)]) return {L, L, 0.0};
    const double x = 2.0 * std::log2(sigma / m_sigma.front());
    const int l = std::min(static_cast<int>(x), L - 1);
    const double w = x - l;
    if (!blend) return w < 0.5 ? Blend{l, l, 0.0} : Blend{l + 1, l + 1, 0.0};
    return {l, l + 1, w};
}

double KernelPyramid::probe_spacing(int l) const {
    const double s0 = m_sigma.front();
    if (l == 0) return 2.0 * s0;
    const double s = m_sigma[size_t(l)];
    return 2.0 * std::sqrt(s0 * s0 + s * s);
}

}  // namespace impulse::kernels
