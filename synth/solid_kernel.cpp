// SPDX-License-Identifier: Apache-2.0
// A 2-D kernel's radial shape in 3-D and 4-D, with its integrals and 3-D spectrum
// (docs/solid.md "Kernels in 3-D").

#include <cmath>
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

}  // namespace impulse::synth
