// SPDX-License-Identifier: Apache-2.0
// A velocity sequence as a flow (sim.h "Velocity sequences"; docs/scenes.md "Velocity
// sequences"): frames of a sampled field, bilinear in space and linear or Catmull-Rom cubic in
// time. The divergence and curl are those of the interpolant itself, so d ln J/dt = div v
// (design.md §1) integrates the field the impulses actually move in.

#include <algorithm>
#include <cmath>

#include "numeric/errors.h"
#include "sim/frame_window.h"
#include "sim/sim.h"

namespace impulse::sim {
namespace {

/// Where a point falls on the grid: its cell (i0, j0), the weights (ax, ay) in it, and whether
/// the derivatives along i and j are those of the interpolant (false where the coordinate was
/// clamped or the point is outside: the field is constant that way).
struct GridPoint {
    size_t i0 = 0, j0 = 0;
    double ax = 0.0, ay = 0.0;
    bool di = true, dj = true;
    bool zero = false;  ///< Outside::Zero and outside the domain: the field is 0
};

class SequenceFlow final : public Flow {
public:
    explicit SequenceFlow(SequenceConfig c)
        : m_c(c), m_window(timing_of(c), checked_loader(c), c.read_ahead) {}

    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double* curl) const override {
        const TimeWeights tw = m_window.timing().weights_at(t);
        std::shared_ptr<const PlaneFrame> frames[4];
        for (int q = 0; q < tw.count; ++q) frames[q] = m_window.get(tw.frame[q]);
        const auto& A = m_c.to_index;
        const size_t w = size_t(m_c.width);
        for (size_t p = 0; p < n; ++p) {
            const GridPoint g = locate(x[p], y[p]);
            if (g.zero) continue;
            // v and its index-space derivatives, summed over the frames with their time weights
            double u[2] = {0, 0}, du_di[2] = {0, 0}, du_dj[2] = {0, 0};
            const size_t k00 = g.j0 * w + g.i0, k10 = k00 + 1, k01 = k00 + w, k11 = k01 + 1;
            for (int q = 0; q < tw.count; ++q) {
                const std::vector<float>* comp[2] = {&frames[q]->vx, &frames[q]->vy};
                for (int c = 0; c < 2; ++c) {
                    const std::vector<float>& v = *comp[c];
                    const double a = v[k00], b = v[k10], cc = v[k01], d = v[k11];
                    const double lo = a + g.ax * (b - a), hi = cc + g.ax * (d - cc);
                    u[c] += tw.weight[q] * (lo + g.ay * (hi - lo));
                    du_di[c] += tw.weight[q] * ((b - a) + g.ay * ((d - cc) - (b - a)));
                    du_dj[c] += tw.weight[q] * (hi - lo);
                }
            }
            vx[p] += u[0], vy[p] += u[1];
            if (!div && !curl) continue;
            for (int c = 0; c < 2; ++c) {
                if (!g.di) du_di[c] = 0.0;
                if (!g.dj) du_dj[c] = 0.0;
            }
            // chain rule through (i, j) = A (x, y) + b: d/dx = a00 d/di + a10 d/dj, etc.
            const double dvx_dx = A[0] * du_di[0] + A[2] * du_dj[0];
            const double dvx_dy = A[1] * du_di[0] + A[3] * du_dj[0];
            const double dvy_dx = A[0] * du_di[1] + A[2] * du_dj[1];
            const double dvy_dy = A[1] * du_di[1] + A[3] * du_dj[1];
            if (div) div[p] += dvx_dx + dvy_dy;
            if (curl) curl[p] += dvy_dx - dvx_dy;
        }
    }

    double max_speed(const Box&) const override {
        // Bilinear weights are convex; Catmull-Rom's absolute weights sum to at most 1.25.
        return m_window.timing().overshoot() * m_c.max_sample_speed;
    }
    void prepare_span(double t0, double t1) override { m_window.prepare_span(t0, t1); }
    double cache_bytes(const Box&) const override {
        return m_window.bytes(m_c.span_s, 2.0 * sizeof(float) * double(m_c.width) * double(m_c.height));
    }

private:
    static FrameTiming timing_of(const SequenceConfig& c) {
        return {c.first, c.last, c.start, c.rate, c.time};
    }
    /// The source's frame k, checked against the sequence's grid size.
    static FrameWindow<PlaneFrame>::Loader checked_loader(const SequenceConfig& c) {
        return [source = c.source, w = c.width, h = c.height](int64_t k) {
            PlaneFrame f = source->load(k);
            const size_t n = size_t(w) * size_t(h);
            if (f.width != w || f.height != h || f.vx.size() != n || f.vy.size() != n)
                throw ValueError("velocity sequence: frame " + std::to_string(k) + " holds " +
                                 std::to_string(f.width) + "x" + std::to_string(f.height) +
                                 " samples, expected " + std::to_string(w) + "x" + std::to_string(h));
            return f;
        };
    }

    GridPoint locate(double x, double y) const {
        const auto& A = m_c.to_index;
        const double fx = A[0] * x + A[1] * y + m_c.index_offset[0];
        const double fy = A[2] * x + A[3] * y + m_c.index_offset[1];
        const double wx = m_c.width - 1.0, wy = m_c.height - 1.0;
        GridPoint g;
        const bool out_x = !(fx >= 0.0 && fx <= wx), out_y = !(fy >= 0.0 && fy <= wy);
        if ((out_x || out_y) && m_c.outside == Outside::Zero) {
            g.zero = true;
            return g;
        }
        double cx = std::clamp(fx, 0.0, wx), cy = std::clamp(fy, 0.0, wy);
        if ((out_x || out_y) && m_c.outside == Outside::Nearest) {
            cx = std::round(cx), cy = std::round(cy);
            g.di = g.dj = false;
        }
        g.di = g.di && !out_x, g.dj = g.dj && !out_y;
        g.i0 = std::min(static_cast<size_t>(cx), size_t(m_c.width - 2));
        g.j0 = std::min(static_cast<size_t>(cy), size_t(m_c.height - 2));
        g.ax = cx - double(g.i0), g.ay = cy - double(g.j0);
        return g;
    }

    SequenceConfig m_c;
    FrameWindow<PlaneFrame> m_window;
};

}  // namespace

std::unique_ptr<Flow> make_sequence_flow(SequenceConfig c) {
    const auto& A = c.to_index;
    const double det = A[0] * A[3] - A[1] * A[2];
    bool finite = std::isfinite(c.start) && std::isfinite(c.rate) &&
                  std::isfinite(c.max_sample_speed) && std::isfinite(c.span_s);
    for (double a : A) finite = finite && std::isfinite(a);
    for (double b : c.index_offset) finite = finite && std::isfinite(b);
    if (!c.source || c.first > c.last || c.width < 2 || c.height < 2 || !finite ||
        !(std::abs(det) > 0.0) || !(c.max_sample_speed >= 0.0))
        throw ValueError("velocity sequence: expected a source, first <= last, a grid of 2x2 "
                         "samples or more, finite numbers and an invertible texture-to-grid map");
    return std::make_unique<SequenceFlow>(std::move(c));
}

double max_interpolated_divergence(const PlaneFrame& f, const std::array<double, 4>& A) {
    // On a cell, dvx/di = (b - a) + ay ((d - c) - (b - a)) is affine in ay and dvx/dj affine in
    // ax (likewise vy), so div = a00 dvx/di + a10 dvx/dj + a01 dvy/di + a11 dvy/dj is affine in
    // (ax, ay): its extremes are at the corners, where the one-sided differences apply.
    const size_t w = size_t(f.width), h = size_t(f.height);
    double m = 0.0;
    for (size_t j = 0; j + 1 < h; ++j)
        for (size_t i = 0; i + 1 < w; ++i) {
            const size_t k = j * w + i;
            for (int cy = 0; cy < 2; ++cy)
                for (int cx = 0; cx < 2; ++cx) {
                    const size_t row = k + size_t(cy) * w, col = k + size_t(cx);
                    const double dvx_di = double(f.vx[row + 1]) - f.vx[row];
                    const double dvy_di = double(f.vy[row + 1]) - f.vy[row];
                    const double dvx_dj = double(f.vx[col + w]) - f.vx[col];
                    const double dvy_dj = double(f.vy[col + w]) - f.vy[col];
                    const double d = A[0] * dvx_di + A[2] * dvx_dj + A[1] * dvy_di + A[3] * dvy_dj;
                    m = std::max(m, std::abs(d));
                }
        }
    return m;
}

}  // namespace impulse::sim
