// SPDX-License-Identifier: Apache-2.0
// The gradient of a kernel h (kernels/kernel.h): what the derivative channels of a frame sum
// over the impulses, df/dx = sum_k w_k grad h(x - x_k) (the derivative of Lewis 1986 eq. 2;
// docs/channels.md).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernels/kernels.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;

/// The Catmull–Rom cubic of Kernel::envelope and its derivative in the sample index x.
std::array<double, 2> catmull_rom(const SampledKernel& sk, double x) {
    const int n = sk.n;
    const int i = std::min(static_cast<int>(x), n - 2);
    const double t = x - i;
    auto v = [&](int j) {
        if (j < 0) j = -j;  // even extension at r = 0
        return j < n ? sk.values[size_t(j)] : 0.0;
    };
    const double p0 = v(i - 1), p1 = v(i), p2 = v(i + 1), p3 = v(i + 2);
    const double a = p2 - p0, b = 2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3, c = 3.0 * (p1 - p2) + p3 - p0;
    return {p1 + 0.5 * t * (a + t * (b + t * c)), 0.5 * (a + t * (2.0 * b + 3.0 * t * c))};
}

/// {e(q), de/dq} for q < 1, sharing the exponential or the cosine (the evaluator's inner work).
std::array<double, 2> envelope_pair(const Kernel& k, double q) {
    const KernelParams& p = k.params();
    switch (p.type) {
        case KernelType::Gaussian: {
            const double rs = p.radius / p.sigma, e = std::exp(-0.5 * q * rs * rs);
            return {e, -0.5 * rs * rs * e};
        }
        case KernelType::Gabor: {
            const double c = kPi * k.gabor_a() * k.gabor_a() * p.radius * p.radius;
            const double e = std::exp(-c * q);
            return {e, -c * e};
        }
        default:
            return {k.envelope(q), k.envelope_derivative(q)};
    }
}

}  // namespace

double Kernel::envelope_derivative(double q) const {
    if (!(q < 1.0)) return 0.0;
    const double R = m_params.radius;
    switch (m_params.type) {
        case KernelType::Cosine: {
            // e = (1 + cos(pi r)) / 2, r = sqrt(q): de/dq = -(pi / 4) sin(pi r) / r.
            const double r = std::sqrt(q);
            return r < 1e-8 ? -kPi * kPi / 4.0 : -0.25 * kPi * std::sin(kPi * r) / r;
        }
        case KernelType::Gaussian: {
            const double rs = R / m_params.sigma;
            return -0.5 * rs * rs * std::exp(-0.5 * q * rs * rs);
        }
        case KernelType::Gabor: {
            const double c = kPi * m_gabor_a * m_gabor_a * R * R;
            return -c * std::exp(-c * q);
        }
        case KernelType::Sampled: {
            const SampledKernel& sk = *m_params.sampled;
            if (!sk.radial || !(q > 0.0)) return 0.0;
            const double r = std::sqrt(q);
            // x = r (n - 1): de/dq = de/dx (n - 1) / (2 r).
            return catmull_rom(sk, r * (sk.n - 1))[1] * (sk.n - 1) / (2.0 * r);
        }
    }
    return 0.0;
}

std::array<double, 3> Kernel::value_gradient(double dx, double dy, double theta) const {
    const double o = m_params.orientation + theta;
    const double c = std::cos(o), s = std::sin(o);
    const auto [h, hu, hv] = frame_value_gradient(c * dx + s * dy, -s * dx + c * dy);
    // Back from the kernel's frame: u = c dx + s dy, v = -s dx + c dy.
    return {h, hu * c - hv * s, hu * s + hv * c};
}

std::array<double, 3> Kernel::frame_value_gradient(double u, double v) const {
    const double R = m_params.radius, a = m_params.aspect;
    double h = 0.0, hu = 0.0, hv = 0.0;  // h and its derivatives in the kernel's frame
    if (is_grid()) {
        const SampledKernel& sk = *m_params.sampled;
        const double va = a * v;
        const double gx = (u + R) / (2.0 * R) * (sk.n - 1), gy = (va + R) / (2.0 * R) * (sk.n - 1);
        if (!(gx >= 0.0) || !(gy >= 0.0) || gx > sk.n - 1 || gy > sk.n - 1 ||
            u * u + va * va >= R * R)
            return {0.0, 0.0, 0.0};
        const int i = std::min(static_cast<int>(gx), sk.n - 2);
        const int j = std::min(static_cast<int>(gy), sk.n - 2);
        const double fa = gx - i, fb = gy - j, per_unit = (sk.n - 1) / (2.0 * R);
        const double* r0 = sk.values.data() + size_t(j) * sk.n;
        const double* r1 = r0 + sk.n;
        h = (1 - fb) * ((1 - fa) * r0[i] + fa * r0[i + 1]) + fb * ((1 - fa) * r1[i] + fa * r1[i + 1]);
        hu = ((1 - fb) * (r0[i + 1] - r0[i]) + fb * (r1[i + 1] - r1[i])) * per_unit;
        hv = a * ((1 - fa) * (r1[i] - r0[i]) + fa * (r1[i + 1] - r0[i + 1])) * per_unit;
    } else {
        const double q = (u * u + a * a * v * v) / (R * R);
        if (!(q < 1.0)) return {0.0, 0.0, 0.0};
        // q = (u^2 + a^2 v^2) / R^2: dq/du = 2 u / R^2, dq/dv = 2 a^2 v / R^2.
        const auto [e, de] = envelope_pair(*this, q);
        h = e;
        hu = de * 2.0 * u / (R * R);
        hv = de * 2.0 * a * a * v / (R * R);
        if (has_carrier()) {
            // h = e cos(2 pi f u + phi) (Lagae et al. 2009 eq. 1): the product rule.
            const double ph = 2.0 * kPi * m_params.frequency * u + m_params.phase;
            const double cp = std::cos(ph), sp = std::sin(ph);
            hu = hu * cp - h * 2.0 * kPi * m_params.frequency * sp;
            hv *= cp;
            h *= cp;
        }
    }
    return {h, hu, hv};
}

}  // namespace impulse::kernels
