// SPDX-License-Identifier: Apache-2.0
// A 2-D kernel's radial shape in 3-D and 4-D, with its integrals and 3-D spectrum
// (docs/solid.md "Statistics").

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "kernels/quadrature.h"
#include "numeric/errors.h"
#include "synth/solid.h"

namespace impulse::synth {
namespace {

constexpr double kPi = std::numbers::pi;

/// 3-D Fourier transform of the radial function g(r) supported on [0, R]:
/// G(k) = 4 pi int_0^R g(r) sin(2 pi k r) / (2 pi k r) r^2 dr = (2 / k) int_0^R g(r) sin(2 pi k r) r dr.
template <class G>
double transform3(const G& g, double R, double k) {
    const int panels = 24 + static_cast<int>(std::ceil(4.0 * std::abs(k) * R));
    if (k == 0.0)
        return 4.0 * kPi * kernels::detail::integrate([&](double r) { return g(r) * r * r; }, 0.0, R, panels);
    return 2.0 / k *
           kernels::detail::integrate([&](double r) { return g(r) * std::sin(2.0 * kPi * k * r) * r; },
                                      0.0, R, panels);
}

}  // namespace

SolidKernel::SolidKernel(const kernels::KernelParams& params, int dims)
    : m_kernel(params), m_dims(dims) {
    if (dims != 3 && dims != 4) throw ValueError("dims = " + std::to_string(dims) + ": expected 3 or 4");
    if (m_kernel.is_grid())
        throw ValueError("kernel: a 2-D grid kernel has no 3-D form; expected a radial kernel");
    if (params.aspect != 1.0)
        throw ValueError("aspect = " + std::to_string(params.aspect) +
                         ": solid kernels are radial; give the anisotropy as a metric");
    if (dims == 4 && m_kernel.has_carrier())
        throw ValueError("kernel gabor: 3-D only (its 4-D statistics are not derived here)");
    const double R = radius();
    auto e = [this, R](double r) { return m_kernel.envelope(r * r / (R * R)); };
    auto e2 = [&e](double r) { return e(r) * e(r); };
    if (dims == 4) {
        // Surface of the unit 3-sphere: 2 pi^2.
        auto rad4 = [&](auto g) {
            return 2.0 * kPi * kPi *
                   kernels::detail::integrate([&](double r) { return g(r) * r * r * r; }, 0.0, R, 48);
        };
        m_integral = rad4(e);
        m_integral_sq = rad4(e2);
        return;
    }
    if (!m_kernel.has_carrier()) {
        m_integral = transform3(e, R, 0.0);
        m_integral_sq = transform3(e2, R, 0.0);
        return;
    }
    // Gabor: cos^2 = 1/2 + 1/2 cos(2 x); the integral of e(x) cos(2 pi k x_1 + c) is cos(c) E(k).
    const double f = params.frequency, phi = params.phase;
    m_integral = std::cos(phi) * transform3(e, R, f);
    m_integral_sq = 0.5 * transform3(e2, R, 0.0) + 0.5 * std::cos(2 * phi) * transform3(e2, R, 2 * f);
}

double SolidKernel::evaluate(const std::array<double, 4>& d) const {
    double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (m_dims == 4) r2 += d[3] * d[3];
    const double R = radius();
    double h = m_kernel.envelope(r2 / (R * R));
    if (m_kernel.has_carrier() && h != 0.0)
        h *= std::cos(2.0 * kPi * m_kernel.params().frequency * d[0] + m_kernel.params().phase);
    return h;
}

double SolidKernel::support_volume() const {
    const double R = radius();
    return m_dims == 3 ? 4.0 / 3.0 * kPi * R * R * R : 0.5 * kPi * kPi * R * R * R * R;
}

double SolidKernel::envelope_transform(double k) const {
    const double R = radius();
    return transform3([this, R](double r) { return m_kernel.envelope(r * r / (R * R)); }, R, k);
}

double SolidKernel::power_spectrum(double kx, double ky, double kz) const {
    if (m_dims != 3) throw ValueError("power_spectrum: 3-D kernels only");
    if (!m_kernel.has_carrier()) {
        const double E = envelope_transform(std::sqrt(kx * kx + ky * ky + kz * kz));
        return E * E;
    }
    // H = 1/2 e^{i phi} E(k - f x^) + 1/2 e^{-i phi} E(k + f x^), E real.
    const double f = m_kernel.params().frequency, t2 = ky * ky + kz * kz;
    const double A = envelope_transform(std::sqrt((kx - f) * (kx - f) + t2));
    const double B = envelope_transform(std::sqrt((kx + f) * (kx + f) + t2));
    return 0.25 * A * A + 0.25 * B * B + 0.5 * A * B * std::cos(2.0 * m_kernel.params().phase);
}

double SolidKernel::radial_power_spectrum(double k) const {
    if (!m_kernel.has_carrier()) return power_spectrum(k, 0.0, 0.0);
    // Average over the sphere: uniform in mu = cos(angle to the carrier axis), dmu / 2.
    return 0.5 * kernels::detail::integrate(
                     [&](double mu) {
                         return power_spectrum(k * mu, k * std::sqrt(std::max(0.0, 1.0 - mu * mu)), 0.0);
                     },
                     -1.0, 1.0, 8);
}

SolidSliceSpectrum::SolidSliceSpectrum(const SolidNoise& noise) {
    const SolidParams& p = noise.params();
    if (p.dims != 3) throw ValueError("slice spectrum: 3-D noise only (dims = 4 given)");
    if (p.metric != std::array<double, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1})
        throw ValueError("slice spectrum: the identity metric only");
    const double R = noise.kernel().radius();
    m_step = 1.0 / (64.0 * R);
    // Out to 24 / R (the carrier's 2 f beyond) and on until a whole 1/R of the table is below
    // 1e-12 of the peak; at most 2^16 points.
    const double f = noise.kernel().shape().has_carrier() ? noise.kernel().shape().params().frequency : 0.0;
    const size_t least = static_cast<size_t>(std::ceil((24.0 / R + 2.0 * f) / m_step));
    double peak = 0.0, recent = 0.0;
    for (size_t i = 0; i < (size_t(1) << 16); ++i) {
        const double v = noise.radial_power_spectrum(double(i) * m_step);
        m_s3.push_back(v);
        peak = std::max(peak, v);
        recent = i % 64 == 0 ? v : std::max(recent, v);
        if (i >= least && i % 64 == 63 && recent < 1e-12 * peak) break;
    }
    for (int i = 0; i < 3; ++i) m_s3.push_back(0.0);
}

double SolidSliceSpectrum::s3(double k) const {
    const double x = k / m_step;
    const size_t i = static_cast<size_t>(x);
    if (i + 2 >= m_s3.size()) return 0.0;
    const double t = x - double(i);
    const double p0 = i == 0 ? m_s3[1] : m_s3[i - 1];  // even in k
    const double p1 = m_s3[i], p2 = m_s3[i + 1], p3 = m_s3[i + 2];
    // 4-point Lagrange cubic: follows the quadratic nulls of |H|^2 between side lobes.
    const double v = -t * (t - 1) * (t - 2) / 6 * p0 + (t + 1) * (t - 1) * (t - 2) / 2 * p1 -
                     (t + 1) * t * (t - 2) / 2 * p2 + (t + 1) * t * (t - 1) / 6 * p3;
    return std::max(v, 0.0);
}

double SolidSliceSpectrum::operator()(double k) const {
    const double top = cutoff();
    if (std::abs(k) >= top) return 0.0;
    const double kz = std::sqrt(top * top - k * k);  // S vanishes beyond
    // S_2(k) = 2 int_0^kz S(sqrt(k^2 + u^2)) du; panels of 8 table steps.
    const int panels = std::max(8, static_cast<int>(std::ceil(kz / (8.0 * m_step))));
    return 2.0 * kernels::detail::integrate([&](double u) { return s3(std::sqrt(k * k + u * u)); },
                                            0.0, kz, panels);
}

kernels::KernelParams solid_designed_kernel(const kernels::KernelParams& designed, double density) {
    if (designed.type != kernels::KernelType::Sampled || !designed.sampled || !designed.sampled->radial)
        throw ValueError("solid_designed_kernel: expected a radial sampled (designed) kernel");
    const double R = designed.radius;
    const double lambda = density / (4.0 / 3.0 * kPi * R * R * R), ea2 = 1.0 / 3.0;
    kernels::KernelParams k = designed;
    auto scaled = std::make_shared<kernels::SampledKernel>(*designed.sampled);
    for (double& v : scaled->values) v /= std::sqrt(lambda * ea2);
    k.sampled = scaled;
    return k;
}

}  // namespace impulse::synth
