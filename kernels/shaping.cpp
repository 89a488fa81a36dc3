// SPDX-License-Identifier: Apache-2.0
// Distribution shaping g = F_y^-1(F_x(.)) (Lewis 1986 §4) and the spectrum pre-correction of
// §4.1 by ITAM (Shields, Deodatis & Bocchini 2011).

#include <math.h>  // ::j0 (POSIX): ~30x faster than std::cyl_bessel_j, within 5e-13 of it

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "kernels/kernels.h"
#include "kernels/quadrature.h"
#include "numeric/errors.h"
#include "numeric/gaussian.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;
using numeric::normal_cdf;
using numeric::normal_pdf;
using numeric::normal_quantile;

[[noreturn]] void bad(const char* key, double value, const std::string& what) {
    std::ostringstream s;
    s << "marginal." << key << " = " << value << ": " << what;
    throw ValueError(s.str());
}

void require_finite(const char* key, double value) {
    if (!std::isfinite(value)) bad(key, value, "must be a finite number");
}

void require_positive(const char* key, double value) {
    require_finite(key, value);
    if (!(value > 0.0)) bad(key, value, "must be > 0");
}

// ---------------------------------------------------------------------------------------------
// Student's t, through the regularized incomplete beta function (Numerical Recipes §6.4)

/// Continued fraction of I_x(a, b) by the modified Lentz method.
double beta_cf(double a, double b, double x) {
    const double tiny = 1e-300;
    const double qab = a + b, qap = a + 1.0, qam = a - 1.0;
    double c = 1.0, d = 1.0 - qab * x / qap;
    if (std::abs(d) < tiny) d = tiny;
    d = 1.0 / d;
    double h = d;
    for (int m = 1; m <= 500; ++m) {
        const int m2 = 2 * m;
        double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < tiny) d = tiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        h *= d * c;
        aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
        d = 1.0 + aa * d;
        if (std::abs(d) < tiny) d = tiny;
        c = 1.0 + aa / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-16) break;
    }
    return h;
}

/// I_x(a, b) with y = 1 - x given separately (precision near x = 1).
double incomplete_beta(double a, double b, double x, double y) {
    if (x <= 0.0) return 0.0;
    if (y <= 0.0) return 1.0;
    const double lbt =
        std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log(y);
    if (x < (a + 1.0) / (a + b + 2.0)) return std::exp(lbt) * beta_cf(a, b, x) / a;
    return 1.0 - std::exp(lbt) * beta_cf(b, a, y) / b;
}

/// P(T > t) for t >= 0, T standard Student-t with nu degrees of freedom.
double t_tail(double t, double nu) {
    const double t2 = t * t;
    return 0.5 * incomplete_beta(0.5 * nu, 0.5, nu / (nu + t2), t2 / (nu + t2));
}

double t_pdf(double t, double nu) {
    const double lc =
        std::lgamma(0.5 * (nu + 1.0)) - std::lgamma(0.5 * nu) - 0.5 * std::log(nu * kPi);
    return std::exp(lc - 0.5 * (nu + 1.0) * std::log1p(t * t / nu));
}

/// t >= 0 with P(T > t) = p, p in (0, 0.5]: safeguarded Newton on log P(T > t).
double t_upper_quantile(double p, double nu) {
    p = std::max(p, 1e-300);
    if (p >= 0.5) return 0.0;
    double lo = 0.0, hi = 1.0;
    while (t_tail(hi, nu) > p && hi < 1e300) lo = hi, hi *= 2.0;
    double t = 0.5 * (lo + hi);
    const double lp = std::log(p);
    for (int it = 0; it < 200; ++it) {
        const double tail = t_tail(t, nu);
        const double f = std::log(tail) - lp;
        if (f > 0)
            lo = t;
        else
            hi = t;
        double next = t + f * tail / t_pdf(t, nu);  // f' = -pdf / tail
        if (!(next > lo && next < hi)) next = lo > 0 ? std::sqrt(lo * hi) : 0.5 * (lo + hi);
        if (std::abs(next - t) <= 1e-15 * t || hi - lo <= 1e-15 * hi) return next;
        t = next;
    }
    return t;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Target distributions

std::string_view to_string(MarginalType type) { return kMarginalTypeNames[static_cast<int>(type)]; }

std::optional<MarginalType> marginal_type_from_string(std::string_view name) {
    for (size_t i = 0; i < kMarginalTypeNames.size(); ++i)
        if (kMarginalTypeNames[i] == name) return static_cast<MarginalType>(i);
    return std::nullopt;
}

void validate(const MarginalParams& p) {
    switch (p.type) {
        case MarginalType::Uniform:
            require_finite("a", p.a);
            require_finite("b", p.b);
            if (!(p.b > p.a)) {
                std::ostringstream s;
                s << "must be > marginal.a = " << p.a;
                bad("b", p.b, s.str());
            }
            break;
        case MarginalType::Exponential:
            require_positive("rate", p.rate);
            break;
        case MarginalType::Laplace:
            require_finite("mu", p.mu);
            require_positive("scale", p.scale);
            break;
        case MarginalType::Lognormal:
            require_finite("mu", p.mu);
            require_positive("sigma", p.sigma);
            // exp(2 mu + 2 sigma^2) must stay finite for the variance and the series
            if (p.sigma > 8.0)
                bad("sigma", p.sigma, "must be <= 8 (the variance overflows beyond)");
            break;
        case MarginalType::StudentT:
            require_finite("mu", p.mu);
            require_positive("scale", p.scale);
            require_finite("nu", p.nu);
            if (!(p.nu > 2.0)) bad("nu", p.nu, "must be > 2 (a finite variance)");
            break;
        case MarginalType::Empirical: {
            const size_t n = p.samples ? p.samples->size() : 0;
            if (n < 2)
                throw ValueError("marginal.samples: expected at least 2 values, found " +
                                 std::to_string(n));
            double lo = (*p.samples)[0], hi = lo;
            for (size_t i = 0; i < n; ++i) {
                const double v = (*p.samples)[i];
                if (!std::isfinite(v)) {
                    std::ostringstream s;
                    s << "marginal.samples[" << i << "] = " << v << ": must be a finite number";
                    throw ValueError(s.str());
                }
                lo = std::min(lo, v), hi = std::max(hi, v);
            }
            if (!(hi > lo)) {
                std::ostringstream s;
                s << "marginal.samples: all " << n << " values equal " << lo
                  << ": a distribution needs a spread";
                throw ValueError(s.str());
            }
            break;
        }
    }
}

Distribution::Distribution(const MarginalParams& params) : m_params(params) {
    validate(params);
    const auto& p = m_params;
    switch (p.type) {
        case MarginalType::Uniform:
            m_mean = 0.5 * (p.a + p.b);
            m_variance = (p.b - p.a) * (p.b - p.a) / 12.0;
            break;
        case MarginalType::Exponential:
            m_mean = 1.0 / p.rate;
            m_variance = 1.0 / (p.rate * p.rate);
            break;
        case MarginalType::Laplace:
            m_mean = p.mu;
            m_variance = 2.0 * p.scale * p.scale;
            break;
        case MarginalType::Lognormal:
            m_mean = std::exp(p.mu + 0.5 * p.sigma * p.sigma);
            m_variance = std::expm1(p.sigma * p.sigma) * std::exp(2.0 * p.mu + p.sigma * p.sigma);
            break;
        case MarginalType::StudentT:
            m_mean = p.mu;
            m_variance = p.scale * p.scale * p.nu / (p.nu - 2.0);
            break;
        case MarginalType::Empirical: {
            m_sorted.assign(p.samples->begin(), p.samples->end());
            std::sort(m_sorted.begin(), m_sorted.end());
            // Moments of the piecewise-linear quantile function: on each of the n - 1 equal
            // probability segments y is uniform between consecutive order statistics.
            const size_t n = m_sorted.size();
            const double shift = m_sorted[n / 2];
            double m1 = 0.0, m2 = 0.0;
            for (size_t i = 0; i + 1 < n; ++i) {
                const double u = m_sorted[i] - shift, v = m_sorted[i + 1] - shift;
                m1 += 0.5 * (u + v);
                m2 += (u * u + u * v + v * v) / 3.0;
            }
            m1 /= double(n - 1), m2 /= double(n - 1);
            m_mean = shift + m1;
            m_variance = std::max(m2 - m1 * m1, 0.0);
            break;
        }
    }
}

double Distribution::cdf(double y) const {
    const auto& p = m_params;
    switch (p.type) {
        case MarginalType::Uniform:
            return std::clamp((y - p.a) / (p.b - p.a), 0.0, 1.0);
        case MarginalType::Exponential:
            return y <= 0.0 ? 0.0 : -std::expm1(-p.rate * y);
        case MarginalType::Laplace: {
            const double u = (y - p.mu) / p.scale;
            return u < 0.0 ? 0.5 * std::exp(u) : 1.0 - 0.5 * std::exp(-u);
        }
        case MarginalType::Lognormal:
            return y <= 0.0 ? 0.0 : normal_cdf((std::log(y) - p.mu) / p.sigma);
        case MarginalType::StudentT: {
            const double t = (y - p.mu) / p.scale;
            return t >= 0.0 ? 1.0 - t_tail(t, p.nu) : t_tail(-t, p.nu);
        }
        case MarginalType::Empirical: {
            const size_t n = m_sorted.size();
            if (y < m_sorted.front()) return 0.0;
            if (y >= m_sorted.back()) return 1.0;
            // last i with s_i <= y (then s_{i+1} > y): inverse of the type-7 interpolation
            const size_t i =
                size_t(std::upper_bound(m_sorted.begin(), m_sorted.end(), y) - m_sorted.begin()) -
                1;
            const double f = (y - m_sorted[i]) / (m_sorted[i + 1] - m_sorted[i]);
            return (double(i) + f) / double(n - 1);
        }
    }
    return 0.0;
}

double Distribution::quantile(double pr, double qr) const {
    const auto& p = m_params;
    const bool lower = pr <= qr;  // work with the smaller of p, q: full precision in both tails
    switch (p.type) {
        case MarginalType::Uniform:
            return lower ? p.a + (p.b - p.a) * pr : p.b - (p.b - p.a) * qr;
        case MarginalType::Exponential:
            return (lower ? -std::log1p(-pr) : -std::log(std::max(qr, 1e-300))) / p.rate;
        case MarginalType::Laplace:
            return lower ? p.mu + p.scale * std::log(2.0 * std::max(pr, 1e-300))
                         : p.mu - p.scale * std::log(2.0 * std::max(qr, 1e-300));
        case MarginalType::Lognormal:
            return std::exp(p.mu + p.sigma * normal_quantile(pr, qr));
        case MarginalType::StudentT:
            return lower ? p.mu - p.scale * t_upper_quantile(pr, p.nu)
                         : p.mu + p.scale * t_upper_quantile(qr, p.nu);
        case MarginalType::Empirical: {
            const size_t n = m_sorted.size();
            const double h = lower ? std::max(pr, 0.0) * double(n - 1)
                                   : double(n - 1) - std::max(qr, 0.0) * double(n - 1);
            const size_t i = std::min(static_cast<size_t>(std::max(h, 0.0)), n - 2);
            const double f = std::clamp(h - double(i), 0.0, 1.0);
            return m_sorted[i] + f * (m_sorted[i + 1] - m_sorted[i]);
        }
    }
    return 0.0;
}

// ---------------------------------------------------------------------------------------------
// The transfer g

MarginalTransform::MarginalTransform(const MarginalParams& target, double source_mean,
                                     double source_sd)
    : m_target(target),
      m_source(SourceCdf::Gaussian),
      m_source_mean(source_mean),
      m_source_sd(source_sd) {
    if (!std::isfinite(source_mean)) {
        std::ostringstream s;
        s << "marginal: layer mean = " << source_mean << ": must be a finite number";
        throw ValueError(s.str());
    }
    if (!(source_sd > 0.0) || !std::isfinite(source_sd)) {
        std::ostringstream s;
        s << "marginal: layer standard deviation = " << source_sd
          << ": must be > 0 (a constant layer cannot be shaped)";
        throw ValueError(s.str());
    }
    build_table(source_mean - kHalfWidthSd * source_sd, source_mean + kHalfWidthSd * source_sd);
}

MarginalTransform::MarginalTransform(const MarginalParams& target, double source_mean,
                                     std::shared_ptr<const ShotNoiseCdf> cdf)
    : m_target(target),
      m_source(SourceCdf::ShotNoise),
      m_source_mean(source_mean),
      m_source_sd(cdf ? cdf->sd() : 0.0),
      m_shot_noise(std::move(cdf)) {
    if (!std::isfinite(source_mean)) {
        std::ostringstream s;
        s << "marginal: layer mean = " << source_mean << ": must be a finite number";
        throw ValueError(s.str());
    }
    if (!m_shot_noise) throw ValueError("marginal: no shot-noise law given");
    build_table(source_mean - kHalfWidthSd * m_source_sd, source_mean + kHalfWidthSd * m_source_sd);
}

MarginalTransform::MarginalTransform(const MarginalParams& target,
                                     std::span<const float> calibration)
    : m_target(target), m_source(SourceCdf::Empirical) {
    auto sorted = std::make_shared<std::vector<float>>(calibration.begin(), calibration.end());
    for (float v : *sorted)
        if (!std::isfinite(v))
            throw ValueError("marginal: calibration sample has a non-finite value");
    if (sorted->size() < 2)
        throw ValueError("marginal: calibration sample needs at least 2 values, found " +
                         std::to_string(sorted->size()));
    std::sort(sorted->begin(), sorted->end());
    if (!(sorted->back() > sorted->front()))
        throw ValueError(
            "marginal: calibration sample is constant: a constant layer cannot be shaped");
    double s1 = 0.0, s2 = 0.0;
    const double shift = (*sorted)[sorted->size() / 2];
    for (float v : *sorted) s1 += v - shift, s2 += (v - shift) * (v - shift);
    const double n = double(sorted->size());
    m_source_mean = shift + s1 / n;
    m_source_sd = std::sqrt(std::max(s2 / n - (s1 / n) * (s1 / n), 0.0));
    m_calibration = sorted;
    build_table(sorted->front(), sorted->back());
}

std::pair<double, double> MarginalTransform::source_cdf(double x) const {
    if (m_source == SourceCdf::Gaussian) {
        const double z = (x - m_source_mean) / m_source_sd;
        return {normal_cdf(z), normal_cdf(-z)};
    }
    if (m_source == SourceCdf::ShotNoise) return (*m_shot_noise)(x - m_source_mean);
    // Mid-rank CDF: ties (an atom, e.g. pixels no impulse reaches) share the middle of their
    // step; floored at half a sample in each tail.
    const auto& s = *m_calibration;
    const double n = double(s.size());
    const float xf = static_cast<float>(x);
    const double lo = double(std::lower_bound(s.begin(), s.end(), xf) - s.begin());
    const double hi = double(std::upper_bound(s.begin(), s.end(), xf) - s.begin());
    const double p = std::max((lo + hi) / (2.0 * n), 0.5 / n);
    const double q = std::max((2.0 * n - lo - hi) / (2.0 * n), 0.5 / n);
    return {p, q};
}

void MarginalTransform::build_table(double x0, double x1) {
    m_x0 = x0;
    m_step = (x1 - x0) / (kTableSize - 1);
    m_inv_step = 1.0 / m_step;
    m_table.resize(kTableSize);
    for (int i = 0; i < kTableSize; ++i) {
        const double x = i + 1 == kTableSize ? x1 : x0 + i * m_step;
        const auto [p, q] = source_cdf(x);
        float y = static_cast<float>(m_target.quantile(p, q));
        if (i > 0) y = std::max(y, m_table[i - 1]);  // monotone whatever the rounding
        m_table[i] = y;
    }
}

float MarginalTransform::operator()(float x) const {
    const double t = (double(x) - m_x0) * m_inv_step;
    if (!(t > 0.0)) return m_table.front();  // also NaN
    if (t >= kTableSize - 1) return m_table.back();
    const int i = static_cast<int>(t);
    const double f = t - i;
    return static_cast<float>(m_table[i] + f * (double(m_table[i + 1]) - m_table[i]));
}

void MarginalTransform::apply(std::span<float> values, double offset) const {
    for (float& v : values) v = (*this)(static_cast<float>(v + offset));
}

double MarginalTransform::exact(double x) const {
    const auto [p, q] = source_cdf(x);
    return m_target.quantile(p, q);
}

double MarginalTransform::standard(double z) const {
    z = std::clamp(z, -kHalfWidthSd, kHalfWidthSd);
    return m_target.quantile(normal_cdf(z), normal_cdf(-z));
}

// ---------------------------------------------------------------------------------------------
// Translation map

TranslationMap::TranslationMap(const MarginalTransform& g) {
    // Nodes of composite 16-point Gauss–Legendre on [-Z, Z] with the Gaussian weight folded in.
    const double Z = MarginalTransform::kHalfWidthSd;
    const int panels = 320;  // width 0.05: resolves He_n up to n = 256 (zero spacing ~0.14)
    const double h = 2.0 * Z / panels;
    const double* xs = detail::gl_nodes();
    const double* ws = detail::gl_weights();
    std::vector<double> z, w, gz;
    for (int p = 0; p < panels; ++p)
        for (int i = 0; i < detail::kGlPoints; ++i) {
            const double zz = -Z + (p + 0.5) * h + 0.5 * h * xs[i];
            z.push_back(zz);
            w.push_back(0.5 * h * ws[i] * normal_pdf(zz));
            gz.push_back(g.standard(zz));
        }
    // g is clamped beyond +-Z: constant tails of mass Phi(-Z) each.
    const double gp = g.standard(Z), gm = g.standard(-Z), tail = normal_cdf(-Z),
                 phiz = normal_pdf(Z);
    double mean = (gp + gm) * tail;
    for (size_t k = 0; k < z.size(); ++k) mean += w[k] * gz[k];
    double var = ((gp - mean) * (gp - mean) + (gm - mean) * (gm - mean)) * tail;
    for (size_t k = 0; k < z.size(); ++k) {
        gz[k] -= mean;
        var += w[k] * gz[k] * gz[k];
    }
    m_mean = mean;
    m_variance = var;
    m_b.assign(1, mean);
    // Orthonormal Hermite polynomials p_n = He_n / sqrt(n!) by their three-term recurrence, at
    // the nodes and at +-Z (for the tails: int_Z^inf p_n phi = p_{n-1}(Z) phi(Z) / sqrt(n)).
    std::vector<double> prev(z.size(), 0.0), cur(z.size(), 1.0);
    double prev_p = 0.0, cur_p = 1.0, prev_m = 0.0, cur_m = 1.0;
    double sum = 0.0;
    for (int n = 1; n <= kMaxTerms; ++n) {
        const double tails =
            ((gp - mean) * cur_p - (gm - mean) * cur_m) * phiz / std::sqrt(double(n));
        const double a = std::sqrt(double(n)), an = std::sqrt(double(n - 1));
        double bn = tails;
        for (size_t k = 0; k < z.size(); ++k) {
            const double next = (z[k] * cur[k] - an * prev[k]) / a;
            prev[k] = cur[k];
            cur[k] = next;
            bn += w[k] * gz[k] * next;
        }
        const double np = (Z * cur_p - an * prev_p) / a, nm = (-Z * cur_m - an * prev_m) / a;
        prev_p = cur_p, cur_p = np, prev_m = cur_m, cur_m = nm;
        m_b.push_back(bn);
        sum += bn * bn;
        if (sum >= var * (1.0 - 1e-13)) break;
    }
    m_remainder = std::max(var - sum, 0.0);
}

double TranslationMap::covariance(double rho) const {
    rho = std::clamp(rho, -1.0, 1.0);
    double s = m_remainder * rho;  // the series' tail, put at order N + 1
    for (size_t n = m_b.size() - 1; n >= 1; --n) s = (s + m_b[n] * m_b[n]) * rho;
    return s;
}

double TranslationMap::inverse(double r) const {
    if (r >= m_variance) return 1.0;
    if (r <= covariance(-1.0)) return -1.0;
    double lo = -1.0, hi = 1.0;  // R_Y increases on [-1, 1] for a monotone g
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        (covariance(mid) < r ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// ---------------------------------------------------------------------------------------------
// Spectrum pre-correction (ITAM)

namespace {

/// Radial grids and the discrete Hankel pair (trapezoid rule in k and r):
///   R(r_j) = 2 pi sum_i S(k_i) J0(2 pi k_i r_j) k_i dk',   S(k_i) = 2 pi sum_j R(r_j) J0(...) r_j
///   dr'.
/// r in [0, 8 L] (dr = L / 64), k in [0, 16 / L] (dk = 1 / (32 L)): the k step aliases at
/// r = 32 L, four times beyond the r range, and the r step at k = 64 / L, four times beyond
/// the k range (near the r grid's Nyquist frequency 32 / L the r sum is inaccurate). The integrands
/// x F(x) (F even) have a kink at 0 when extended evenly, which costs the trapezoid rule a
/// constant error h^2 F(0) / 12 (Euler–Maclaurin): a constant offset of R beyond the support
/// that transforms back into a spike. It is added back as a weight at x = 0.
struct HankelGrid {
    int nr = 8 * 64 + 1, nk = 16 * 32 + 1;
    std::vector<double> r, k, wr, wk, J;  // J[j * nk + i] = J0(2 pi k_i r_j)

    explicit HankelGrid(double L) {
        const double dr = L / 64.0, dk = 1.0 / (32.0 * L);
        for (int j = 0; j < nr; ++j) {
            r.push_back(j * dr);
            wr.push_back(2.0 * kPi * r.back() * dr * (j == nr - 1 ? 0.5 : 1.0));
        }
        for (int i = 0; i < nk; ++i) {
            k.push_back(i * dk);
            wk.push_back(2.0 * kPi * k.back() * dk * (i == nk - 1 ? 0.5 : 1.0));
        }
        wr[0] = 2.0 * kPi * dr * dr / 12.0;  // Euler–Maclaurin end correction (see above)
        wk[0] = 2.0 * kPi * dk * dk / 12.0;
        J.resize(size_t(nr) * nk);
        for (int j = 0; j < nr; ++j)
            for (int i = 0; i < nk; ++i) J[size_t(j) * nk + i] = ::j0(2.0 * kPi * k[i] * r[j]);
    }
    std::vector<double> to_r(const std::vector<double>& S) const {
        std::vector<double> R(nr, 0.0);
        for (int j = 0; j < nr; ++j) {
            const double* row = &J[size_t(j) * nk];
            double s = 0.0;
            for (int i = 0; i < nk; ++i) s += wk[i] * S[i] * row[i];
            R[j] = s;
        }
        return R;
    }
    std::vector<double> to_k(const std::vector<double>& R) const {
        std::vector<double> S(nk, 0.0);
        for (int j = 0; j < nr; ++j) {
            const double* row = &J[size_t(j) * nk];
            const double c = wr[j] * R[j];
            if (c == 0.0) continue;
            for (int i = 0; i < nk; ++i) S[i] += c * row[i];
        }
        return S;
    }
};

struct Errors {
    double l2 = 0.0, band = 0.0;
};

Errors spectrum_errors(const HankelGrid& G, const std::vector<double>& target,
                       const std::vector<double>& got) {
    const double peak = *std::max_element(target.begin(), target.end());
    double num = 0.0, den = 0.0;
    Errors e;
    for (int i = 0; i < G.nk; ++i) {
        num += G.wk[i] * (got[i] - target[i]) * (got[i] - target[i]);
        den += G.wk[i] * target[i] * target[i];
        if (target[i] >= 0.01 * peak) e.band = std::max(e.band, std::abs(got[i] / target[i] - 1.0));
    }
    e.l2 = std::sqrt(num / den);
    return e;
}

/// Spectrum of the translated field g(X) for a Gaussian X with spectrum shape S_G.
std::vector<double> translated_spectrum(const HankelGrid& G, const TranslationMap& map,
                                        const std::vector<double>& SG) {
    std::vector<double> R = G.to_r(SG);
    const double r0 = R[0];
    for (double& v : R) v = map.covariance(v / r0);
    return G.to_k(R);
}

/// Direct inversion rho_G(r) = R_Y^-1(R_T(r)): where S_G = H^-1[rho_G] goes negative, no
/// Gaussian spectrum maps exactly onto the target (Shields et al. 2011 §2). Measured on the
/// working band (beyond it the transforms' rounding dominates S_G).
void direct_inversion(const HankelGrid& G, const TranslationMap& map,
                      const std::vector<double>& RT, int last_active, double var,
                      PrecorrectionReport& rep) {
    const double lowest = map.covariance(-1.0);
    std::vector<double> rho(G.nr);
    int below = 0;
    for (int j = 0; j < G.nr; ++j) {
        if (RT[j] < lowest - 1e-12 * var) ++below;
        rho[j] = map.inverse(RT[j]);
    }
    const std::vector<double> Sd = G.to_k(rho);
    double neg = 0.0, all = 0.0;
    for (int i = 0; i <= last_active; ++i) {
        neg += G.wk[i] * std::max(-Sd[i], 0.0);
        all += G.wk[i] * std::abs(Sd[i]);
    }
    rep.negative_fraction = all > 0.0 ? neg / all : 0.0;
    rep.unreachable_fraction = double(below) / G.nr;
}

/// The corrected kernel h = H^-1[sign(H) sqrt(S_T C)] on the smallest support that keeps the
/// worst band within budget; returns its spectrum S_G (for the report).
std::vector<double> corrected_kernel(const HankelGrid& G, const TranslationMap& map,
                                     const std::vector<double>& ST,
                                     const std::vector<double>& sign,
                                     const std::vector<double>& best, double best_band,
                                     double integral_sq, const ItamOptions& opt,
                                     KernelParams& kernel) {
    std::vector<double> final_sg;
    // h = H^-1[sign(H) sqrt(S_G)] = H^-1[H sqrt(C)], scaled to the requested
    // int h^2 = int H^2 d^2k.
    std::vector<double> H(G.nk);
    for (int i = 0; i < G.nk; ++i) H[i] = sign[i] * std::sqrt(std::max(ST[i] * best[i], 0.0));
    std::vector<double> H2(G.nk);
    for (int i = 0; i < G.nk; ++i) H2[i] = H[i] * H[i];
    const double scale = std::sqrt(integral_sq / G.to_r(H2)[0]);
    std::vector<double> h = G.to_r(H);
    for (double& v : h) v *= scale;
    // The kernel needs a finite support: take the smallest radius, in steps of L / 4 from L,
    // whose truncation keeps the worst band within half the remaining budget (halfway from
    // ITAM's result to the tolerance; a tenth of the tolerance when ITAM missed it). The
    // corrected kernel has a ringing tail a few L long; the far tail is rounding noise.
    auto truncated_spectrum = [&](int cut) {
        std::vector<double> ht(G.nr, 0.0);
        std::copy(h.begin(), h.begin() + cut + 1, ht.begin());
        std::vector<double> s2 = G.to_k(ht);
        for (double& v : s2) v *= v;
        return s2;
    };
    const double allowed = best_band < opt.tolerance ? 0.5 * (best_band + opt.tolerance)
                                                         : best_band + 0.1 * opt.tolerance;
    int cut = G.nr - 1;
    for (int c = 64; c < G.nr - 1; c += 16) {
        const std::vector<double> s2 = truncated_spectrum(c);
        if (spectrum_errors(G, ST, translated_spectrum(G, map, s2)).band <= allowed) {
            cut = c;
            break;
        }
    }
    final_sg = truncated_spectrum(cut);
    double hh = 0.0;  // int h^2 of the truncated kernel, restored to the requested value
    for (int i = 0; i < G.nk; ++i) hh += G.wk[i] * final_sg[i];
    const double fix = std::sqrt(integral_sq / hh);
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = true;
    sk->n = cut + 1;
    for (int j = 0; j <= cut; ++j) sk->values.push_back(h[j] * fix);
    kernel = KernelParams{};
    kernel.type = KernelType::Sampled;
    kernel.radius = G.r[cut];
    kernel.sampled = sk;
    return final_sg;
}

/// The report's one line: converged, or how close ITAM came and why it could not reach.
std::string itam_message(const PrecorrectionReport& rep, const Errors& fin, int it,
                         const TranslationMap& map, const ItamOptions& opt) {
    std::ostringstream m;
    m.precision(3);
    if (opt.max_iterations == 0) {
        m << "shaped spectrum of the kernel as it is: worst band above 1 % of peak "
          << 100.0 * fin.band << " % off, relative L2 error " << fin.l2;
    } else if (rep.converged) {
        m << "ITAM converged in " << it << " iterations: worst band above 1 % of peak "
          << 100.0 * fin.band << " % off, relative L2 residual " << fin.l2;
    } else {
        m << "no Gaussian spectrum found whose shaped spectrum is within " << 100.0 * opt.tolerance
          << " % of the target above 1 % of its peak";
        if (rep.negative_fraction > 0.0 || rep.unreachable_fraction > 0.0) {
            m << " (";
            if (rep.negative_fraction > 0.0)
                m << "the direct inversion needs negative spectral values, "
                  << 100.0 * rep.negative_fraction << " % of its mass";
            if (rep.negative_fraction > 0.0 && rep.unreachable_fraction > 0.0) m << "; ";
            if (rep.unreachable_fraction > 0.0)
                m << "the target correlation falls below the reachable minimum "
                  << map.min_correlation();
            m << ")";
        }
        m << "; closest after " << it << " iterations: worst band " << 100.0 * fin.band
          << " % off, relative L2 residual " << fin.l2;
    }
    return m.str();
}

Precorrection run_itam(const HankelGrid& G, std::vector<double> ST, const std::vector<double>& sign,
                       double integral_sq, const MarginalTransform& g, const ItamOptions& opt,
                       const KernelParams* original) {
    const TranslationMap map(g);
    const double var = map.variance();
    // The shaped field's variance is the marginal's: only the shape of the target is used.
    const double r0 = G.to_r(ST)[0];
    if (!(r0 > 0.0) || !std::isfinite(r0))
        throw ValueError("precorrect: the target spectrum has no power on the frequency grid");
    for (double& v : ST) v *= var / r0;
    const std::vector<double> RT = G.to_r(ST);

    // The band ITAM works on: from k = 0 while the target is above kActive of its peak (an
    // order below the 1 % bands the report judges).
    const double kActive = 1e-3;
    const double peak = *std::max_element(ST.begin(), ST.end());
    int last_active = 0;
    while (last_active + 1 < G.nk && ST[last_active + 1] >= kActive * peak) ++last_active;

    PrecorrectionReport rep;
    direct_inversion(G, map, RT, last_active, var, rep);

    // ITAM: S_G <- S_G S_T / S_Y, starting from the target's own shape. S_G is carried as the
    // target times a correction C(k) = S_G / S_T (unit variance), updated on the working band
    // and held at its edge value beyond: there the higher-order terms of the translation
    // dominate S_Y and C barely matters, while a C that collapses there (it would, at every zero
    // of |H|^2) makes a steep edge that rings through the whole kernel. The clamp keeps one
    // step from overshooting. The best iterate by the worst band error is kept (the reported
    // criterion).
    std::vector<double> C(G.nk, 1.0), best = C, SG(G.nk);
    auto gaussian_spectrum = [&](const std::vector<double>& c) {
        for (int i = 0; i < G.nk; ++i) SG[i] = ST[i] * c[i];
        return translated_spectrum(G, map, SG);
    };
    std::vector<double> SY = gaussian_spectrum(C);
    Errors err = spectrum_errors(G, ST, SY), best_err = err;
    auto better = [](const Errors& a, const Errors& b) {
        return a.band < b.band || (a.band == b.band && a.l2 < b.l2);
    };
    int it = 0, since_best = 0;
    for (; it < opt.max_iterations && best_err.band > 0.5 * opt.tolerance && since_best < 25;
         ++it) {
        for (int i = 0; i <= last_active; ++i)
            C[i] *= std::clamp(ST[i] / std::max(SY[i], 1e-300), 0.25, 4.0);
        for (int i = last_active + 1; i < G.nk; ++i) C[i] = C[last_active];
        SY = gaussian_spectrum(C);
        err = spectrum_errors(G, ST, SY);
        if (better(err, best_err)) {
            best = C, best_err = err, since_best = 0;
        } else {
            ++since_best;
        }
    }
    rep.iterations = it;

    Precorrection out;
    std::vector<double> final_sg;
    if (opt.max_iterations == 0 && original) {
        out.kernel = *original;
        final_sg = ST;
    } else {
        final_sg = corrected_kernel(G, map, ST, sign, best, best_err.band, integral_sq, opt,
                                    out.kernel);
    }
    const std::vector<double> achieved = translated_spectrum(G, map, final_sg);
    const Errors fin = spectrum_errors(G, ST, achieved);
    rep.residual = fin.l2;
    rep.max_band_error = fin.band;
    rep.converged = fin.band <= opt.tolerance;
    rep.frequency = G.k;
    rep.target = ST;
    rep.achieved = achieved;

    rep.message = itam_message(rep, fin, it, map, opt);
    out.report = std::move(rep);
    return out;
}

}  // namespace

Precorrection precorrect_spectrum(const Kernel& kernel, const MarginalTransform& g,
                                  const ItamOptions& options) {
    if (kernel.has_carrier() || kernel.is_grid() || kernel.params().aspect != 1.0)
        throw ValueError(
            "precorrect: needs an isotropic kernel (cosine, gaussian or radial "
            "sampled, aspect 1), not " +
            std::string(kernel.has_carrier() ? "gabor"
                        : kernel.is_grid()   ? "a sampled grid"
                                             : "an elongated kernel (aspect > 1)"));
    if (!(options.tolerance > 0.0) || options.max_iterations < 0)
        throw ValueError("precorrect: tolerance must be > 0 and max_iterations >= 0");
    const double R = kernel.radius();
    const HankelGrid G(R);
    // H(k) = 2 pi int_0^R h(r) J0(2 pi k r) r dr by composite Gauss–Legendre: 64 panels of 16
    // points resolve J0 up to k R = 16 with 32 nodes per half period.
    const int panels = 64;
    std::vector<double> rn, hw;
    const double* xs = detail::gl_nodes();
    const double* ws = detail::gl_weights();
    for (int p = 0; p < panels; ++p)
        for (int i = 0; i < detail::kGlPoints; ++i) {
            const double hp = R / panels, r = (p + 0.5) * hp + 0.5 * hp * xs[i];
            rn.push_back(r);
            hw.push_back(2.0 * kPi * 0.5 * hp * ws[i] * r * kernel.evaluate(r, 0.0));
        }
    std::vector<double> ST(G.nk), sign(G.nk);
    for (int i = 0; i < G.nk; ++i) {
        double H = 0.0;
        for (size_t n = 0; n < rn.size(); ++n) H += hw[n] * ::j0(2.0 * kPi * G.k[i] * rn[n]);
        ST[i] = H * H;
        sign[i] = H < 0.0 ? -1.0 : 1.0;
    }
    return run_itam(G, std::move(ST), sign, kernel.integral_sq(), g, options, &kernel.params());
}

Precorrection precorrect_spectrum(const std::function<double(double)>& target, double length,
                                  const MarginalTransform& g, const ItamOptions& options) {
    if (!(length > 0.0) || !std::isfinite(length)) {
        std::ostringstream s;
        s << "precorrect: length = " << length << ": must be > 0";
        throw ValueError(s.str());
    }
    if (!(options.tolerance > 0.0) || options.max_iterations < 0)
        throw ValueError("precorrect: tolerance must be > 0 and max_iterations >= 0");
    const HankelGrid G(length);
    std::vector<double> ST(G.nk), sign(G.nk, 1.0);
    for (int i = 0; i < G.nk; ++i) {
        ST[i] = target(G.k[i]);
        if (!(ST[i] >= 0.0) || !std::isfinite(ST[i])) {
            std::ostringstream s;
            s << "precorrect: target spectrum at k = " << G.k[i] << " is " << ST[i]
              << ": must be finite and >= 0";
            throw ValueError(s.str());
        }
    }
    return run_itam(G, std::move(ST), sign, 1.0, g, options, nullptr);
}

}  // namespace impulse::kernels
