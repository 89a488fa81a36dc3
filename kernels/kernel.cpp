// SPDX-License-Identifier: Apache-2.0
// Kernels of the shaped point process and their second-order statistics.

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>
#include <numbers>
#include <sstream>

#include <tbb/parallel_for.h>

#include "kernels/kernels.h"
#include "kernels/quadrature.h"
#include "numeric/errors.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;
// Gabor envelope parameter giving an envelope of exp(-pi a^2 R^2) = 1 % at the radius.
const double kGaborEdgeFactor = std::sqrt(std::log(100.0) / kPi);  // 1.2107

void require_positive(const char* key, double value) {
    if (!(value > 0.0) || !std::isfinite(value)) {
        std::ostringstream s;
        s << key << " = " << value << ": must be a finite number > 0";
        throw ValueError(s.str());
    }
}

void require_finite(const char* key, double value) {
    if (!std::isfinite(value)) {
        std::ostringstream s;
        s << key << " = " << value << ": must be a finite number";
        throw ValueError(s.str());
    }
}

/// Hankel transform of an isotropic function g(r) supported on [0, R]:
/// G(k) = 2 pi int_0^R g(r) J0(2 pi k r) r dr (the 2-D Fourier transform of a radial function).
template <class G>
double hankel(const G& g, double radius, double k) {
    // Enough panels to resolve J0's oscillation (period ~1/k) and the envelope.
    const int panels = 24 + static_cast<int>(std::ceil(4.0 * std::abs(k) * radius));
    return 2.0 * kPi *
           detail::integrate(
               [&](double r) {
                   // detail::bessel_j0: libstdc++'s cyl_bessel_j is ~1000x slower at large
                   // arguments (a scene's spectrum over a wide band took minutes).
                   const double j0 = k == 0.0 ? 1.0 : detail::bessel_j0(2.0 * kPi * k * r);
                   return g(r) * j0 * r;
               },
               0.0, radius, panels);
}

/// Integrals of h, h^2, h^4 of a grid kernel of radius R; `sample(u, v)` is its bilinear
/// interpolant masked to the disk (Kernel::grid_value).
template <class Sample>
std::array<double, 3> grid_integrals(const SampledKernel& sk, double R, const Sample& sample) {
    // Integrals of h, h^2, h^4 for the bilinear interpolant masked to the disk (what the
    // renderer evaluates). Inside the disk a cell holds a bilinear h, so h^4 is of degree <= 4 in
    // each variable and 3 x 3 Gauss-Legendre nodes integrate all three exactly; a cell the circle
    // crosses is sub-sampled 8 x 8 at midpoints (error O(spacing^2 / 64 h'')); a cell outside is
    // zero. (Sub-sampling every cell took seconds for a designed 513^2 grid under the sanitizers.)
    const int n = sk.n;
    const double d = 2.0 * R / (n - 1);
    const double g = std::sqrt(0.6) / 2;
    const double node[3] = {0.5 - g, 0.5, 0.5 + g}, weight[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
    constexpr int kSub = 8;
    double i1 = 0, i2 = 0, i4 = 0;
    auto add = [&](double h, double w) { i1 += w * h, i2 += w * h * h, i4 += w * h * h * h * h; };
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const double u0 = -R + i * d, v0 = -R + j * d;
            const double un = std::max({u0, -u0 - d, 0.0}), vn = std::max({v0, -v0 - d, 0.0});
            if (un * un + vn * vn >= R * R) continue;  // outside the disk
            const double uf = std::max(std::abs(u0), std::abs(u0 + d));
            const double vf = std::max(std::abs(v0), std::abs(v0 + d));
            if (uf * uf + vf * vf < R * R) {  // inside: exact
                const double* r0 = sk.values.data() + size_t(j) * n + i;
                const double* r1 = r0 + n;
                for (int b = 0; b < 3; ++b)
                    for (int a = 0; a < 3; ++a) {
                        const double x = node[a], y = node[b];
                        add((1 - y) * ((1 - x) * r0[0] + x * r0[1]) + y * ((1 - x) * r1[0] + x * r1[1]),
                            weight[a] * weight[b]);
                    }
                continue;
            }
            for (int b = 0; b < kSub; ++b)
                for (int a = 0; a < kSub; ++a)
                    add(sample(u0 + (a + 0.5) / kSub * d, v0 + (b + 0.5) / kSub * d),
                        1.0 / (kSub * kSub));
        }
    return {i1 * d * d, i2 * d * d, i4 * d * d};
}

}  // namespace

std::string_view to_string(KernelType type) {
    return type == KernelType::Sampled ? "sampled" : kKernelTypeNames[static_cast<int>(type)];
}

std::optional<KernelType> kernel_type_from_string(std::string_view name) {
    for (size_t i = 0; i < kKernelTypeNames.size(); ++i)
        if (kKernelTypeNames[i] == name) return static_cast<KernelType>(i);
    return std::nullopt;
}

void validate(const KernelParams& p) {
    require_positive("radius", p.radius);
    if (p.radius > kMaxKernelRadius || p.radius < kMinKernelRadius) {
        std::ostringstream s;
        s << "radius = " << p.radius << ": must be in [1e-6, 1e6] texture units";
        throw ValueError(s.str());
    }
    require_finite("orientation", p.orientation);
    require_finite("phase", p.phase);
    require_finite("aspect", p.aspect);
    if (!(p.aspect >= 1.0)) {
        std::ostringstream s;
        s << "aspect = " << p.aspect << ": must be >= 1 (extent along / across the orientation)";
        throw ValueError(s.str());
    }
    if (p.type == KernelType::Gaussian) {
        require_positive("sigma", p.sigma);
        if (p.radius / p.sigma > 1e3) {
            std::ostringstream s;
            s << "sigma = " << p.sigma << ": radius / sigma = " << p.radius / p.sigma
              << ", expected at most 1000 (the kernel would be zero almost everywhere)";
            throw ValueError(s.str());
        }
    }
    if (p.type == KernelType::Sampled) {
        if (!p.sampled || p.sampled->n < 4)
            throw ValueError("sampled kernel: expected at least 4 samples per axis");
        const size_t want = p.sampled->radial ? size_t(p.sampled->n)
                                              : size_t(p.sampled->n) * size_t(p.sampled->n);
        if (p.sampled->values.size() != want)
            throw ValueError("sampled kernel: expected " + std::to_string(want) + " values, found " +
                             std::to_string(p.sampled->values.size()));
        for (double v : p.sampled->values)
            if (!std::isfinite(v)) throw ValueError("sampled kernel: values must be finite");
    }
    if (p.type == KernelType::Gabor) {
        require_finite("frequency", p.frequency);
        if (p.frequency < 0.0) {
            std::ostringstream s;
            s << "frequency = " << p.frequency << ": must be >= 0 (cycles per unit)";
            throw ValueError(s.str());
        }
        if (p.frequency * p.radius > 1e4) {
            std::ostringstream s;
            s << "frequency = " << p.frequency << ": " << p.frequency * p.radius
              << " cycles across the kernel radius; expected at most 10000";
            throw ValueError(s.str());
        }
        require_finite("bandwidth", p.bandwidth);
        if (p.bandwidth < 0.0) {
            std::ostringstream s;
            s << "bandwidth = " << p.bandwidth << ": must be >= 0 (0 derives it from radius)";
            throw ValueError(s.str());
        }
    }
}

float EnvelopePolynomial::evaluate_monomial(float q) const {
    float p = monomial.back();
    for (size_t j = monomial.size() - 1; j-- > 0;) p = std::fma(p, q, monomial[j]);
    return p;
}

float EnvelopePolynomial::evaluate(float q) const {
    // Clenshaw's recurrence for sum c_j T_j(t), t = 2q - 1.
    const float t = 2.0f * q - 1.0f;
    const float t2 = 2.0f * t;
    float b1 = 0.0f, b2 = 0.0f;
    for (size_t j = coefficients.size() - 1; j >= 1; --j) {
        const float b0 = t2 * b1 - b2 + coefficients[j];
        b2 = b1;
        b1 = b0;
    }
    return t * b1 - b2 + coefficients[0];
}

struct Kernel::LazyOverlap {
    std::once_flag once;
    double value = 1.0;
};

Kernel::Kernel(const KernelParams& params)
    : m_params(params), m_overlap(std::make_shared<LazyOverlap>()) {
    validate(params);
    if (params.type == KernelType::Gabor)
        m_gabor_a = params.bandwidth > 0.0 ? params.bandwidth : kGaborEdgeFactor / params.radius;

    const double R = params.radius;
    const double inv_aspect = 1.0 / params.aspect;
    auto env_r = [this, R](double r) { return envelope(r * r / (R * R)); };
    auto env_pow = [&](int p) { return [&env_r, p](double r) { return std::pow(env_r(r), p); }; };

    // An elliptical kernel is the isotropic one with v scaled by 1/aspect: integrals scale by
    // 1/aspect. The Gabor carrier cos(2 pi f u + phi) averages as below (cos^2 = 1/2 + 1/2 cos 2x,
    // cos^4 = 3/8 + 1/2 cos 2x + 1/8 cos 4x); each cosine term is the envelope power's
    // transform at the harmonic (the integral of e(x) cos(2 pi k u + c) is cos(c) E(k)).
    if (is_grid()) {
        const std::array<double, 3> in = grid_integrals(
            *params.sampled, R, [this](double u, double v) { return grid_value(u, v); });
        m_integral = inv_aspect * in[0];
        m_integral_sq = inv_aspect * in[1];
        m_integral_4 = inv_aspect * in[2];
        m_grid.assign(params.sampled->values.begin(), params.sampled->values.end());
        return;
    }
    if (!has_carrier()) {
        m_integral = inv_aspect * hankel(env_r, R, 0.0);
        m_integral_sq = inv_aspect * hankel(env_pow(2), R, 0.0);
        m_integral_4 = inv_aspect * hankel(env_pow(4), R, 0.0);
    } else {
        const double f = params.frequency, phi = params.phase;
        m_integral = inv_aspect * std::cos(phi) * hankel(env_r, R, f);
        m_integral_sq = inv_aspect * (0.5 * hankel(env_pow(2), R, 0.0) +
                                      0.5 * std::cos(2 * phi) * hankel(env_pow(2), R, 2 * f));
        m_integral_4 = inv_aspect * (0.375 * hankel(env_pow(4), R, 0.0) +
                                     0.5 * std::cos(2 * phi) * hankel(env_pow(4), R, 2 * f) +
                                     0.125 * std::cos(4 * phi) * hankel(env_pow(4), R, 4 * f));
    }

    // Chebyshev fit of the envelope in q (interpolation at Chebyshev nodes), raising the degree
    // until the float evaluation is within 1e-6 of e(0) on a dense grid.
    const double e0 = envelope(0.0);
    for (int degree = 4;; degree += 2) {
        const int n = degree + 1;
        std::vector<double> fx(n);
        for (int i = 0; i < n; ++i) {
            const double t = std::cos(kPi * (i + 0.5) / n);
            fx[i] = envelope(0.5 * (t + 1.0) * (1.0 - 1e-12));
        }
        m_poly.coefficients.assign(n, 0.0f);
        for (int j = 0; j < n; ++j) {
            double c = 0.0;
            for (int i = 0; i < n; ++i) c += fx[i] * std::cos(kPi * j * (i + 0.5) / n);
            m_poly.coefficients[j] = static_cast<float>((j == 0 ? 1.0 : 2.0) * c / n);
        }
        double err = 0.0;
        for (int i = 0; i <= 4000; ++i) {
            const double q = i / 4000.0 * (1.0 - 1e-9);
            err = std::max(err, std::abs(m_poly.evaluate(static_cast<float>(q)) - envelope(q)));
        }
        m_poly.max_error = err;
        if (err < 1e-6 * std::abs(e0) || degree >= 40) break;
    }
    if (m_poly.max_error < 1e-6 * std::abs(e0)) {
        // Monomial form in q: T_j(2q - 1) expanded by T_{j+1} = 2 (2q - 1) T_j - T_{j-1} in
        // double, kept only if float Horner stays within the same error (cancellation between
        // large alternating coefficients rules it out for high degrees).
        const size_t n = m_poly.coefficients.size();
        std::vector<double> mono(n, 0.0), tm1(n, 0.0), t0(n, 0.0), t1(n, 0.0);
        t0[0] = 1.0;                 // T_0
        t1[0] = -1.0, t1[1] = 2.0;   // T_1 = 2q - 1
        mono[0] += m_poly.coefficients[0];
        if (n > 1)
            for (size_t k = 0; k < n; ++k) mono[k] += m_poly.coefficients[1] * t1[k];
        for (size_t j = 2; j < n; ++j) {
            std::vector<double> t2(n, 0.0);
            for (size_t k = 0; k < n; ++k) {
                t2[k] = -2.0 * t1[k] - t0[k];
                if (k > 0) t2[k] += 4.0 * t1[k - 1];
            }
            for (size_t k = 0; k < n; ++k) mono[k] += m_poly.coefficients[j] * t2[k];
            t0 = t1, t1 = t2;
        }
        m_poly.monomial.assign(mono.begin(), mono.end());
        double err = 0.0;
        for (int i = 0; i <= 4000; ++i) {
            const double q = i / 4000.0 * (1.0 - 1e-9);
            err = std::max(err, std::abs(m_poly.evaluate_monomial(static_cast<float>(q)) - envelope(q)));
        }
        if (!(err < 1e-6 * std::abs(e0))) m_poly.monomial.clear();
    }
    if (!(m_poly.max_error < 1e-6 * std::abs(e0))) {
        // The polynomial cannot follow this envelope (e.g. an oscillating sampled profile or
        // a Gaussian many sigmas wide): tabulate it in q for linear interpolation, doubling the
        // table until the error at the midpoints (where linear interpolation is worst,
        // ~ e''/8 spacing^2) is below the polynomial's promise, up to 2^20 intervals.
        for (size_t intervals = 4096;; intervals *= 2) {
            m_table.resize(intervals + 1);
            for (size_t i = 0; i <= intervals; ++i)
                m_table[i] = static_cast<float>(envelope(std::min(double(i) / intervals, 1.0 - 1e-12)));
            double err = 0.0;
            for (size_t i = 0; i < intervals; ++i) {
                const double q = (i + 0.5) / intervals;
                err = std::max(err, std::abs(0.5 * (double(m_table[i]) + m_table[i + 1]) - envelope(q)));
            }
            m_table_error = err;
            if (err < 1e-6 * std::abs(e0) || intervals >= (size_t(1) << 20)) break;
        }
    }
}

double Kernel::envelope(double q) const {
    if (!(q < 1.0)) return 0.0;
    const double R = m_params.radius;
    switch (m_params.type) {
        case KernelType::Cosine:
            return 0.5 + 0.5 * std::cos(kPi * std::sqrt(q));  // Lewis 1989 §4.1
        case KernelType::Gaussian:
        {
            const double rs = R / m_params.sigma;  // the ratio, so tiny sigmas cannot underflow
            return std::exp(-0.5 * q * rs * rs);
        }
        case KernelType::Gabor:
            return std::exp(-kPi * m_gabor_a * m_gabor_a * R * R * q);  // Lagae 2009 eq. 1
        case KernelType::Sampled: {
            const SampledKernel& sk = *m_params.sampled;
            if (!sk.radial) return 0.0;
            // Catmull–Rom in r; even extension at r = 0, zero beyond the last sample.
            const int n = sk.n;
            const double x = std::sqrt(q) * (n - 1);
            const int i = std::min(static_cast<int>(x), n - 2);
            const double t = x - i;
            auto v = [&](int j) {
                if (j < 0) j = -j;
                return j < n ? sk.values[j] : 0.0;
            };
            const double p0 = v(i - 1), p1 = v(i), p2 = v(i + 1), p3 = v(i + 2);
            return p1 + 0.5 * t * (p2 - p0 + t * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 +
                                                  t * (3.0 * (p1 - p2) + p3 - p0)));
        }
    }
    return 0.0;
}

double Kernel::grid_value(double u, double v) const {
    // Bilinear in the grid over [-R, R]^2; zero outside.
    const SampledKernel& sk = *m_params.sampled;
    const double R = m_params.radius;
    const double gx = (u + R) / (2.0 * R) * (sk.n - 1), gy = (v + R) / (2.0 * R) * (sk.n - 1);
    if (!(gx >= 0.0) || !(gy >= 0.0) || gx > sk.n - 1 || gy > sk.n - 1) return 0.0;
    if (u * u + v * v >= R * R) return 0.0;  // the support is the disk, as in the renderer
    const int i = std::min(static_cast<int>(gx), sk.n - 2), j = std::min(static_cast<int>(gy), sk.n - 2);
    const double a = gx - i, b = gy - j;
    const double* r0 = sk.values.data() + size_t(j) * sk.n;
    const double* r1 = r0 + sk.n;
    return (1 - b) * ((1 - a) * r0[i] + a * r0[i + 1]) + b * ((1 - a) * r1[i] + a * r1[i + 1]);
}

double Kernel::evaluate(double dx, double dy, double theta) const {
    const double o = m_params.orientation + theta;
    const double c = std::cos(o), s = std::sin(o);
    const double u = c * dx + s * dy, v = -s * dx + c * dy;
    const double R = m_params.radius;
    if (is_grid()) return grid_value(u, m_params.aspect * v);
    const double q = (u * u + m_params.aspect * m_params.aspect * v * v) / (R * R);
    double h = envelope(q);
    if (has_carrier() && h != 0.0)
        h *= std::cos(2.0 * kPi * m_params.frequency * u + m_params.phase);
    return h;
}

double Kernel::support_area() const { return kPi * m_params.radius * m_params.radius / m_params.aspect; }

double Kernel::envelope_transform(double k) const {
    const double R = m_params.radius;
    return hankel([this, R](double r) { return envelope(r * r / (R * R)); }, R, k);
}

double Kernel::power_spectrum(double kx, double ky) const {
    return spectrum_with(kx, ky, m_params.orientation,
                         [this](double k) { return envelope_transform(k); });
}

template <class Transform>
double Kernel::spectrum_with(double kx, double ky, double o, const Transform& transform) const {
    const double c = std::cos(o), s = std::sin(o);
    const double ku = c * kx + s * ky, kv = -s * kx + c * ky;
    const double a = m_params.aspect;
    // Transform of e(u, a v) at (ku, kv) is (1/a) E(sqrt(ku^2 + (kv/a)^2)).
    if (is_grid()) return grid_spectrum(ku, kv / a) / (a * a);
    auto E = [&](double u, double v) { return transform(std::sqrt(u * u + (v / a) * (v / a))) / a; };
    if (!has_carrier()) {
        const double e = E(ku, kv);
        return e * e;
    }
    // H = 1/2 e^{i phi} E(k - f u_hat) + 1/2 e^{-i phi} E(k + f u_hat), E real.
    const double f = m_params.frequency;
    const double A = E(ku - f, kv), B = E(ku + f, kv);
    return 0.25 * A * A + 0.25 * B * B + 0.5 * A * B * std::cos(2.0 * m_params.phase);
}

double Kernel::grid_spectrum(double ku, double kv) const {
    // FT of the bilinear interpolant: d^2 sinc^2(ku d) sinc^2(kv d) sum v_ij e^{-2 pi i k.x_ij},
    // in the kernel frame (the caller applies the aspect squeeze).
    const SampledKernel& sk = *m_params.sampled;
    const int n = sk.n;
    const double R = m_params.radius, d = 2.0 * R / (n - 1);
    auto sinc = [](double x) { return x == 0.0 ? 1.0 : std::sin(kPi * x) / (kPi * x); };
    double re = 0.0, im = 0.0;
    for (int j = 0; j < n; ++j) {
        const double y = -R + j * d;
        for (int i = 0; i < n; ++i) {
            const double x = -R + i * d;
            const double ph = -2.0 * kPi * (ku * x + kv * y);
            const double v = sk.values[size_t(j) * n + i];
            re += v * std::cos(ph);
            im += v * std::sin(ph);
        }
    }
    const double f = d * d * std::pow(sinc(ku * d) * sinc(kv * d), 2);
    return f * f * (re * re + im * im);
}

std::vector<double> Kernel::envelope_transform_table(double dk, int count, int first) const {
    // Projection-slice: the 2-D transform of the isotropic envelope along an axis is the 1-D
    // transform of its projection p(x) = 2 int_0^Y e((x^2 + y^2) / R^2) dy, Y = sqrt(R^2 - x^2),
    // so E(k) = 2 int_0^R p(x) cos(2 pi k x) dx. With x = R sin(phi) both integrands are smooth
    // up to the support's edge (Y = R cos(phi)), and Gauss-Legendre panels resolve the cosine
    // at the largest k; the cosines of k_j = (first + j) dk follow by the Chebyshev recurrence
    // at each node (one sincos a node, not a Bessel function a node and a frequency).
    const double R = m_params.radius;
    const double k_top = std::abs(first + count - 1.0) * dk;
    const int panels = 24 + static_cast<int>(std::ceil(4.0 * k_top * R));
    const double* xs = detail::gl_nodes();
    const double* ws = detail::gl_weights();
    const double half_pi = 0.5 * kPi, width = half_pi / panels;
    // Blocks of 8 panels side by side, each summed into its own row, then the rows in block
    // order: the same bits for any thread count.
    constexpr int kBlock = 8;
    const int blocks = (panels + kBlock - 1) / kBlock;
    std::vector<double> partial(size_t(blocks) * size_t(count), 0.0);
    tbb::parallel_for(0, blocks, [&](int blk) {
        double* out = partial.data() + size_t(blk) * size_t(count);
        for (int p = blk * kBlock; p < std::min(panels, (blk + 1) * kBlock); ++p)
            for (int i = 0; i < detail::kGlPoints; ++i) {
                const double phi = (p + 0.5) * width + 0.5 * width * xs[i];
                const double x = R * std::sin(phi), Y = R * std::cos(phi);
                double proj = 0.0;  // int_0^1 e((x^2 + Y^2 t^2) / R^2) dt, t by 16-point Gauss-Legendre
                for (int j = 0; j < detail::kGlPoints; ++j) {
                    const double t = 0.5 + 0.5 * xs[j];
                    proj += 0.5 * ws[j] * envelope((x * x + Y * Y * t * t) / (R * R));
                }
                // 2 (projection, 2 Y x the mean) x (dx = Y dphi) x the panel's weight
                const double w = 2.0 * (2.0 * Y * proj) * Y * 0.5 * width * ws[i];
                const double theta = 2.0 * kPi * dk * x;
                const double c1 = std::cos(theta);
                double prev = std::cos(theta * (first - 1)), cur = std::cos(theta * first);
                for (int j = 0; j < count; ++j) {
                    out[size_t(j)] += w * cur;
                    const double next = 2.0 * c1 * cur - prev;
                    prev = cur, cur = next;
                }
            }
    });
    std::vector<double> out(size_t(count), 0.0);
    for (int blk = 0; blk < blocks; ++blk)
        for (int j = 0; j < count; ++j) out[size_t(j)] += partial[size_t(blk) * size_t(count) + size_t(j)];
    return out;
}

std::vector<double> Kernel::power_spectrum_grid(double K, int n, double rotation) const {
    return std::move(power_spectrum_grids(K, n, {rotation}).front());
}

std::vector<std::vector<double>> Kernel::power_spectrum_grids(
    double K, int n, const std::vector<double>& rotations) const {
    const double dk = 2.0 * K / n;
    // The envelope's Hankel transform E(k), tabulated once over every radius the grid reaches
    // (a carrier shifts it by f, the aspect stretches it by a) and interpolated (cubic): a
    // quadrature per point would cost ~1e4 times more.
    const double reach = (std::sqrt(2.0) * K + m_params.frequency) * m_params.aspect;
    const int m = is_grid() ? 0 : 2048;
    // E at (i - 1) reach / m, i = 0 .. m + 2
    const std::vector<double> table = is_grid() ? std::vector<double>(3, 0.0)
                                                : envelope_transform_table(reach / m, m + 3, -1);
    auto transform = [&](double k) {  // cubic (Lagrange) through the four nearest samples
        const double x = k / reach * m;
        if (!(x <= m)) return 0.0;
        const int i = std::min(static_cast<int>(x), m - 1);
        const double t = x - i;
        const double* e = table.data() + i;  // e[0] = E at sample i - 1
        return e[0] * (-t * (t - 1) * (t - 2) / 6) + e[1] * ((t + 1) * (t - 1) * (t - 2) / 2) +
               e[2] * (-(t + 1) * t * (t - 2) / 2) + e[3] * ((t + 1) * t * (t - 1) / 6);
    };
    std::vector<std::vector<double>> grids(rotations.size());
    for (size_t r = 0; r < rotations.size(); ++r) {
        std::vector<double>& out = grids[r];
        out.resize(size_t(n) * n);
        // Rows side by side: every value is computed alone, the same for any thread count.
        tbb::parallel_for(0, n, [&](int j) {
            for (int i = 0; i < n; ++i)
                out[size_t(j) * n + i] =
                    spectrum_with(-K + (i + 0.5) * dk, -K + (j + 0.5) * dk,
                                  m_params.orientation + rotations[r], transform);
        });
    }
    return grids;
}

double Kernel::radial_power_spectrum(double k) const {
    if (!has_carrier() && m_params.aspect == 1.0 && !is_grid()) return power_spectrum(k, 0.0);
    // Angular average: the spectrum has period pi in angle (|H(k)| = |H(-k)| for real h).
    const int n = 180;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double a = kPi * (i + 0.5) / n;
        sum += power_spectrum(k * std::cos(a), k * std::sin(a));
    }
    return sum / n;
}

double Kernel::autocorrelation(double tx, double ty) const {
    // Polar quadrature over the support of h(x) in the kernel frame, with the elliptical
    // squeeze undone (v = w / aspect, Jacobian 1/aspect); h(x + tau) evaluated exactly.
    const double R = m_params.radius;
    const double a = m_params.aspect;
    const double o = m_params.orientation;
    const double c = std::cos(o), s = std::sin(o);
    const int angles = 720;
    const int panels = 48;
    const double* xs = detail::gl_nodes();
    const double* ws = detail::gl_weights();
    double sum = 0.0;
    for (int p = 0; p < panels; ++p) {
        const double r0 = R * p / panels, hr = R / panels;
        for (int i = 0; i < detail::kGlPoints; ++i) {
            const double r = r0 + 0.5 * hr * (1.0 + xs[i]);
            const double wr = 0.5 * hr * ws[i] * r;
            const double e = is_grid() ? 1.0 : envelope(r * r / (R * R));
            if (e == 0.0) continue;
            double ring = 0.0;
            for (int j = 0; j < angles; ++j) {
                const double ang = 2.0 * kPi * (j + 0.5) / angles;
                const double u = r * std::cos(ang), v = r * std::sin(ang) / a;
                double h = is_grid() ? grid_value(u, a * v) : e;
                if (has_carrier()) h *= std::cos(2.0 * kPi * m_params.frequency * u + m_params.phase);
                // back to texture coordinates
                const double x = c * u - s * v, y = s * u + c * v;
                ring += h * evaluate(x + tx, y + ty);
            }
            sum += wr * ring * (2.0 * kPi / angles);
        }
    }
    return sum / a;
}

double Kernel::scale_class_overlap() const {
    std::call_once(m_overlap->once, [this] {
        // The same polar quadrature as autocorrelation, over the support of h(x) (h(x / r),
        // r > 1, is wider, so the product vanishes outside it): sum h(x) h(x / r) and h(x)^2 on
        // the same nodes, so the ratio's quadrature errors largely cancel.
        const double R = m_params.radius, a = m_params.aspect, o = m_params.orientation;
        const double c = std::cos(o), s = std::sin(o), r = kScaleClassRatio;
        const int angles = 360, panels = 24;
        const double* xs = detail::gl_nodes();
        const double* ws = detail::gl_weights();
        double cross = 0.0, sq = 0.0;
        for (int p = 0; p < panels; ++p)
            for (int i = 0; i < detail::kGlPoints; ++i) {
                const double rho = R * (p + 0.5 * (1.0 + xs[i])) / panels;
                const double wr = 0.5 * (R / panels) * ws[i] * rho;
                for (int j = 0; j < angles; ++j) {
                    const double ang = 2.0 * kPi * (j + 0.5) / angles;
                    const double u = rho * std::cos(ang), v = rho * std::sin(ang) / a;
                    const double x = c * u - s * v, y = s * u + c * v;
                    const double h = evaluate(x, y);
                    cross += wr * h * evaluate(x / r, y / r);
                    sq += wr * h * h;
                }
            }
        m_overlap->value = sq > 0.0 ? cross / (r * sq) : 1.0;
    });
    return m_overlap->value;
}

KernelCurvature kernel_curvature(const Kernel& k) {
    const double R = k.radius(), d = R / 128.0;
    constexpr int kNodes = 97;
    constexpr double kDir[4][2] = {{1, 0}, {0, 1}, {0.70710678118654752, 0.70710678118654752},
                                   {0.70710678118654752, -0.70710678118654752}};
    KernelCurvature c;
    for (int j = 0; j < kNodes; ++j)
        for (int i = 0; i < kNodes; ++i) {
            const double x = R * (2.0 * i / (kNodes - 1) - 1.0);
            const double y = R * (2.0 * j / (kNodes - 1) - 1.0);
            if (std::hypot(x, y) > R - 2.0 * d) continue;
            const double h = k.evaluate(x, y);
            c.peak = std::max(c.peak, std::abs(h));
            for (const auto& e : kDir) {
                const double second = (k.evaluate(x + d * e[0], y + d * e[1]) - 2.0 * h +
                                       k.evaluate(x - d * e[0], y - d * e[1])) / (d * d);
                c.curvature = std::max(c.curvature, std::abs(second));
            }
        }
    return c;
}

}  // namespace impulse::kernels

