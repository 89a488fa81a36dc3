// SPDX-License-Identifier: Apache-2.0
// Composition of layers, per pixel: blend modes, the bicubic resampling of a domain warp, the
// orientation taken from a layer's sampled field, and the closed-form statistics of a blend.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "scenes/detail/compose.h"
#include "numeric/gaussian.h"
#include "numeric/spline.h"

namespace impulse::scenes::detail {
namespace {

/// The node x0 whose Catmull-Rom stencil (x0 - 1 .. x0 + 2 of `size` nodes) interpolates at
/// position f, and the fraction t; held inside the grid (callers size their grids so it never
/// has to be: the hold only guards the memory).
int stencil_cell(double f, int size, double& t) {
    double fl = std::floor(f);
    t = f - fl;
    if (fl < 1.0) fl = 1.0, t = 0.0;
    if (fl > size - 3.0) fl = size - 3.0, t = 1.0;
    return static_cast<int>(fl);
}

}  // namespace

double alpha_ramp(double lo, double hi, double v) {
    const double t = std::clamp((v - lo) / (hi - lo), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

void blend(Blend mode, double opacity, const std::optional<std::array<double, 2>>& alpha,
           const render::Frame& layer, render::Frame& running) {
    const size_t n = running.data.size();
    const float* l = layer.data.data();
    float* r = running.data.data();
    const double o = opacity;
    const bool full = opacity == 1.0;
    auto each = [&](auto&& op) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 16384),
                          [&](const tbb::blocked_range<size_t>& b) {
                              for (size_t p = b.begin(); p != b.end(); ++p) op(p);
                          });
    };
    // At opacity 1 the float operation itself, so a sum of layers keeps its bits.
    switch (mode) {
        case Blend::Add:
            if (full) return each([&](size_t p) { r[p] += l[p]; });
            return each([&](size_t p) { r[p] = static_cast<float>(r[p] + o * l[p]); });
        case Blend::Multiply:
            if (full) return each([&](size_t p) { r[p] *= l[p]; });
            return each(
                [&](size_t p) { r[p] = static_cast<float>(r[p] * ((1.0 - o) + o * l[p])); });
        case Blend::Max:
            if (full) return each([&](size_t p) { r[p] = std::max(r[p], l[p]); });
            return each([&](size_t p) {
                r[p] = static_cast<float>(r[p] + o * (std::max(r[p], l[p]) - r[p]));
            });
        case Blend::Min:
            if (full) return each([&](size_t p) { r[p] = std::min(r[p], l[p]); });
            return each([&](size_t p) {
                r[p] = static_cast<float>(r[p] + o * (std::min(r[p], l[p]) - r[p]));
            });
        case Blend::Over:
            if (!alpha)
                return each([&](size_t p) {
                    r[p] = static_cast<float>(double(r[p]) * (1.0 - o) + double(l[p]) * o);
                });
            return each([&](size_t p) {
                const double a = o * alpha_ramp((*alpha)[0], (*alpha)[1], l[p]);
                r[p] = static_cast<float>(double(r[p]) * (1.0 - a) + double(l[p]) * a);
            });
    }
}

void warp_resample(const render::Frame& src, int margin, const std::vector<float>& dx,
                   const std::vector<float>& dy, render::Frame& out) {
    const int W = src.width, H = src.height, w = out.width;
    tbb::parallel_for(tbb::blocked_range<int>(0, out.height, 8), [&](const tbb::blocked_range<int>& rows) {
        for (int j = rows.begin(); j != rows.end(); ++j)
            for (int i = 0; i < w; ++i) {
                const size_t p = size_t(j) * w + i;
                double tx, ty;
                const int x0 = stencil_cell(i + margin + double(dx[p]), W, tx);
                const int y0 = stencil_cell(j + margin + double(dy[p]), H, ty);
                double wx[4], wy[4], d[4], dd[4];
                numeric::catmull_rom(tx, wx, d, dd);
                numeric::catmull_rom(ty, wy, d, dd);
                double sum = 0.0;
                for (int b = 0; b < 4; ++b) {
                    const float* row = src.data.data() + size_t(y0 - 1 + b) * W + (x0 - 1);
                    sum += wy[b] * (wx[0] * row[0] + wx[1] * row[1] + wx[2] * row[2] + wx[3] * row[3]);
                }
                out.data[p] = static_cast<float>(sum);
            }
    });
}

void LatticeOrientation::set(render::Frame values, int64_t i0, int64_t j0, double spacing) {
    m_values = std::move(values);
    m_i0 = i0, m_j0 = j0, m_h = spacing;
}

void LatticeOrientation::angles(double, size_t n, const double* x, const double* y,
                                float* theta) const {
    const int W = m_values.width, H = m_values.height;
    for (size_t k = 0; k < n; ++k) {
        // Node (a, b) at ((i0 + a) h, (j0 + b) h).
        double tx, ty;
        const int a0 = stencil_cell(x[k] / m_h - double(m_i0), W, tx);
        const int b0 = stencil_cell(y[k] / m_h - double(m_j0), H, ty);
        double wx[4], dx[4], ddx[4], wy[4], dy[4], ddy[4];
        numeric::catmull_rom(tx, wx, dx, ddx);
        numeric::catmull_rom(ty, wy, dy, ddy);
        double gx = 0.0, gy = 0.0;
        for (int b = 0; b < 4; ++b) {
            const float* row = m_values.data.data() + size_t(b0 - 1 + b) * W + (a0 - 1);
            double rw = 0.0, rd = 0.0;
            for (int a = 0; a < 4; ++a) rw += wx[a] * row[a], rd += dx[a] * row[a];
            gx += wy[b] * rd;
            gy += dy[b] * rw;
        }
        double angle = (gx == 0.0 && gy == 0.0) ? 0.0 : std::atan2(gy, gx);
        if (m_level_lines) angle += 0.5 * std::numbers::pi;
        theta[k] = static_cast<float>(angle);
    }
}

namespace {

using numeric::normal_cdf;
using numeric::normal_pdf;

/// E[f(L)] over the layer's marginal: the target distribution of a shaped layer (midpoint rule
/// in probability, 4096 quantiles), else a Gaussian with the layer's mean and variance
/// (trapezoid rule over +- 8 sd, 3201 points).
template <class F>
double expect(const LayerConfig& layer, const Theory& lt, F&& f) {
    if (layer.marginal) {
        constexpr int kN = 4096;
        double sum = 0.0;
        for (int k = 0; k < kN; ++k) sum += f(layer.marginal->target().quantile((k + 0.5) / kN));
        return sum / kN;
    }
    const double sd = std::sqrt(lt.variance);
    if (!(sd > 0.0)) return f(lt.mean);
    constexpr int kN = 3200;
    constexpr double kZ = 8.0;
    const double dz = 2.0 * kZ / kN;
    double sum = 0.0;
    for (int k = 0; k <= kN; ++k) {
        const double z = -kZ + k * dz;
        sum += (k == 0 || k == kN ? 0.5 : 1.0) * normal_pdf(z) * f(lt.mean + sd * z);
    }
    return sum * dz;
}

}  // namespace

Theory blend_theory(const Theory& r, const LayerConfig& layer, const Theory& l, double o) {
    const double r2 = r.variance + r.mean * r.mean;  // E[R^2]
    auto result = [](double mean, double second) {
        return Theory{mean, std::max(0.0, second - mean * mean)};
    };
    switch (layer.compose.blend) {
        case Blend::Add: return {r.mean + o * l.mean, r.variance + o * o * l.variance};
        case Blend::Multiply: {
            // R ((1 - o) + o L), independent factors: E[XY] = E[X] E[Y], E[(XY)^2] = E[X^2] E[Y^2].
            const double m = (1.0 - o) + o * l.mean;
            return result(r.mean * m, r2 * (m * m + o * o * l.variance));
        }
        case Blend::Max:
        case Blend::Min: {
            // max(R, L) = R + (L - R)^+ and min(R, L) = R - (R - L)^+, D = +-(L - R) Gaussian
            // (Clark 1961): E[D^+] = mu Phi(a) + s phi(a), E[(D^+)^2] = (mu^2 + s^2) Phi(a) +
            // mu s phi(a), a = mu / s; Stein's lemma gives E[R D^+] = mu_R E[D^+] +
            // Cov(R, D) Phi(a), Cov(R, D) = -+ var R. The result is R +- o D^+.
            const double sign = layer.compose.blend == Blend::Max ? 1.0 : -1.0;
            const double mu = sign * (l.mean - r.mean), s = std::sqrt(r.variance + l.variance);
            double ep, ep2, erp;
            if (s > 0.0) {
                const double a = mu / s, Phi = normal_cdf(a), phi = normal_pdf(a);
                ep = mu * Phi + s * phi;
                ep2 = (mu * mu + s * s) * Phi + mu * s * phi;
                erp = r.mean * ep - sign * r.variance * Phi;
            } else {
                ep = std::max(mu, 0.0), ep2 = ep * ep, erp = r.mean * ep;
            }
            return result(r.mean + sign * o * ep, r2 + 2.0 * sign * o * erp + o * o * ep2);
        }
        case Blend::Over: {
            if (!layer.compose.alpha)
                return {(1.0 - o) * r.mean + o * l.mean,
                        (1.0 - o) * (1.0 - o) * r.variance + o * o * l.variance};
            // R (1 - A) + L A with A = o s(L) a function of L only, R independent of L.
            const double lo = (*layer.compose.alpha)[0], hi = (*layer.compose.alpha)[1];
            auto A = [&](double v) { return o * alpha_ramp(lo, hi, v); };
            const double ea = expect(layer, l, [&](double v) { return A(v); });
            const double ea2 = expect(layer, l, [&](double v) { return A(v) * A(v); });
            const double eal = expect(layer, l, [&](double v) { return A(v) * v; });
            const double ea2l = expect(layer, l, [&](double v) { return A(v) * A(v) * v; });
            const double ea2l2 = expect(layer, l, [&](double v) { return A(v) * A(v) * v * v; });
            const double mean = r.mean * (1.0 - ea) + eal;
            return result(mean, r2 * (1.0 - 2.0 * ea + ea2) + 2.0 * r.mean * (eal - ea2l) + ea2l2);
        }
    }
    return r;
}

}  // namespace impulse::scenes::detail
