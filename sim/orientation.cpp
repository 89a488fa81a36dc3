// SPDX-License-Identifier: Apache-2.0
// Orientation fields theta(x, t): the kernel of every impulse is rotated by the field at its
// current position (Lewis 1986 §3.1: "the kernel can be varied as a function of the position of
// each point to produce a non-stationary noise ... rotating the kernel as a function of
// position").

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "sim/detail/angle.h"
#include "sim/sim.h"
#include "numeric/errors.h"

namespace impulse::sim {
namespace {

constexpr double kPi = std::numbers::pi;

class ConstantOrientation final : public OrientationField {
public:
    explicit ConstantOrientation(Keyframed a) : m_angle(std::move(a)) {}
    void angles(double t, size_t n, const double*, const double*, float* theta) const override {
        const float a = detail::theta_of(m_angle.value(t));
        std::fill(theta, theta + n, a);
    }

private:
    Keyframed m_angle;
};

class CentredOrientation final : public OrientationField {
public:
    CentredOrientation(Keyframed cx, Keyframed cy, double offset)
        : m_cx(std::move(cx)), m_cy(std::move(cy)), m_offset(offset) {}
    void angles(double t, size_t n, const double* x, const double* y, float* theta) const override {
        const double cx = m_cx.value(t), cy = m_cy.value(t);
        for (size_t i = 0; i < n; ++i) {
            const double dx = x[i] - cx, dy = y[i] - cy;
            const double a = (dx == 0.0 && dy == 0.0) ? 0.0 : std::atan2(dy, dx);
            theta[i] = static_cast<float>(a + m_offset);
        }
    }

private:
    Keyframed m_cx, m_cy;
    double m_offset;
};

class PolylineOrientation final : public OrientationField {
public:
    PolylineOrientation(std::vector<std::array<double, 2>> p, Keyframed smooth)
        : m_points(std::move(p)), m_smooth(std::move(smooth)) {
        if (m_points.size() < 2)
            throw ValueError("polyline orientation: expected at least 2 points");
        for (size_t i = 0; i + 1 < m_points.size(); ++i) {
            const double dx = m_points[i + 1][0] - m_points[i][0];
            const double dy = m_points[i + 1][1] - m_points[i][1];
            const double len2 = dx * dx + dy * dy;
            if (!(len2 > 0.0))
                throw ValueError("polyline orientation: consecutive points must differ");
            m_dir.push_back(std::atan2(dy, dx));
            m_len2.push_back(len2);
        }
        if (!(m_smooth.min() >= 0.0))
            throw ValueError("polyline orientation: smooth must be >= 0");
    }
    void angles(double t, size_t n, const double* x, const double* y, float* theta) const override {
        const size_t ns = m_dir.size();
        const double smooth = m_smooth.value(t);
        std::vector<double> d2(ns);
        for (size_t i = 0; i < n; ++i) {
            size_t best = 0;
            for (size_t s = 0; s < ns; ++s) {
                // squared distance to segment s
                const auto& a = m_points[s];
                const auto& b = m_points[s + 1];
                const double ex = b[0] - a[0], ey = b[1] - a[1];
                const double t =
                    std::clamp(((x[i] - a[0]) * ex + (y[i] - a[1]) * ey) / m_len2[s], 0.0, 1.0);
                const double px = a[0] + t * ex - x[i], py = a[1] + t * ey - y[i];
                d2[s] = px * px + py * py;
                if (d2[s] < d2[best]) best = s;
            }
            if (smooth <= 0.0) {
                theta[i] = static_cast<float>(m_dir[best]);
                continue;
            }
            // Average as doubled-angle vectors (an orientation and its opposite agree), keeping
            // the nearest segment's sense.
            double c = 0.0, s2 = 0.0;
            const double inv = 1.0 / (2.0 * smooth * smooth);
            for (size_t s = 0; s < ns; ++s) {
                const double w = std::exp(-(d2[s] - d2[best]) * inv);
                c += w * std::cos(2.0 * m_dir[s]);
                s2 += w * std::sin(2.0 * m_dir[s]);
            }
            double a = 0.5 * std::atan2(s2, c);
            // choose a or a + pi, whichever is closer to the nearest segment's direction
            const double diff = std::remainder(a - m_dir[best], 2.0 * kPi);
            if (std::abs(diff) > 0.5 * kPi) a += kPi;
            theta[i] = static_cast<float>(a);
        }
    }

private:
    std::vector<std::array<double, 2>> m_points;
    std::vector<double> m_dir, m_len2;
    Keyframed m_smooth;
};

class SineOrientation final : public OrientationField {
public:
    SineOrientation(Keyframed amp, Keyframed wl, Keyframed phase, Keyframed angle, double ox,
                    double oy)
        : m_amp(std::move(amp)), m_wl(std::move(wl)), m_phase(std::move(phase)),
          m_angle(std::move(angle)), m_ox(ox), m_oy(oy) {
        if (!(m_wl.min() > 0.0) || !std::isfinite(m_wl.max()))
            throw ValueError("sine orientation: wavelength must be > 0");
    }
    void angles(double t, size_t n, const double* x, const double* y, float* theta) const override {
        const double angle = m_angle.value(t), amp = m_amp.value(t), phase = m_phase.value(t);
        const double c = std::cos(angle), s = std::sin(angle);
        const double k = 2.0 * kPi / m_wl.value(t);
        for (size_t i = 0; i < n; ++i) {
            const double u = (x[i] - m_ox) * c + (y[i] - m_oy) * s;
            // dw/du of w = A sin(k u + phase)
            theta[i] = detail::theta_of(angle + std::atan(amp * k * std::cos(k * u + phase)));
        }
    }

private:
    Keyframed m_amp, m_wl, m_phase, m_angle;
    double m_ox, m_oy;
};

class GridOrientation final : public OrientationField {
public:
    explicit GridOrientation(OrientationGrid g) : m_g(std::move(g)) {
        const size_t n = size_t(m_g.width) * m_g.height;
        if (m_g.width < 1 || m_g.height < 1 || (m_g.channels != 1 && m_g.channels != 2) ||
            m_g.values.size() != n * m_g.channels || !(m_g.spacing > 0.0))
            throw ValueError(
                "orientation grid: expected width, height >= 1, 1 or 2 channels and "
                "width * height * channels values");
        for (size_t i = 0; i < m_g.values.size(); ++i)
            if (!std::isfinite(m_g.values[i])) {
                std::ostringstream s;
                const size_t p = i / m_g.channels;
                s << "orientation grid: expected finite values, found " << m_g.values[i]
                  << " at pixel (" << p % m_g.width << ", " << p / m_g.width << ")";
                throw ValueError(s.str());
            }
        m_vx.resize(n), m_vy.resize(n);
        for (size_t i = 0; i < n; ++i) {
            if (m_g.channels == 1) {
                m_vx[i] = std::cos(static_cast<double>(m_g.values[i]));
                m_vy[i] = std::sin(static_cast<double>(m_g.values[i]));
            } else {
                m_vx[i] = m_g.values[2 * i];
                m_vy[i] = m_g.values[2 * i + 1];
            }
        }
    }
    void angles(double, size_t n, const double* x, const double* y, float* theta) const override {
        const int w = m_g.width, h = m_g.height;
        for (size_t i = 0; i < n; ++i) {
            const double fx = std::clamp((x[i] - m_g.origin_x) / m_g.spacing - 0.5, 0.0, w - 1.0);
            const double fy = std::clamp((y[i] - m_g.origin_y) / m_g.spacing - 0.5, 0.0, h - 1.0);
            const int i0 = std::min(static_cast<int>(fx), w - 1),
                      j0 = std::min(static_cast<int>(fy), h - 1);
            const int i1 = std::min(i0 + 1, w - 1), j1 = std::min(j0 + 1, h - 1);
            const double ax = fx - i0, ay = fy - j0;
            auto lerp = [&](const std::vector<double>& v) {
                const double a = v[size_t(j0) * w + i0], b = v[size_t(j0) * w + i1];
                const double c = v[size_t(j1) * w + i0], d = v[size_t(j1) * w + i1];
                return (1.0 - ay) * (a + ax * (b - a)) + ay * (c + ax * (d - c));
            };
            const double vx = lerp(m_vx), vy = lerp(m_vy);
            theta[i] = static_cast<float>((vx == 0.0 && vy == 0.0) ? 0.0 : std::atan2(vy, vx));
        }
    }

private:
    OrientationGrid m_g;
    std::vector<double> m_vx, m_vy;
};

}  // namespace

std::shared_ptr<OrientationField> make_constant_orientation(Keyframed angle) {
    return std::make_shared<ConstantOrientation>(std::move(angle));
}
std::shared_ptr<OrientationField> make_radial_orientation(Keyframed cx, Keyframed cy) {
    return std::make_shared<CentredOrientation>(std::move(cx), std::move(cy), 0.0);
}
std::shared_ptr<OrientationField> make_circular_orientation(Keyframed cx, Keyframed cy,
                                                            bool clockwise) {
    return std::make_shared<CentredOrientation>(std::move(cx), std::move(cy),
                                                clockwise ? -0.5 * kPi : 0.5 * kPi);
}
std::shared_ptr<OrientationField> make_polyline_orientation(
    std::vector<std::array<double, 2>> points, Keyframed smooth) {
    return std::make_shared<PolylineOrientation>(std::move(points), std::move(smooth));
}
std::shared_ptr<OrientationField> make_sine_orientation(Keyframed amplitude, Keyframed wavelength,
                                                        Keyframed phase, Keyframed angle,
                                                        double ox, double oy) {
    return std::make_shared<SineOrientation>(std::move(amplitude), std::move(wavelength),
                                             std::move(phase), std::move(angle), ox, oy);
}
std::shared_ptr<OrientationField> make_grid_orientation(OrientationGrid grid) {
    return std::make_shared<GridOrientation>(std::move(grid));
}

}  // namespace impulse::sim
