// SPDX-License-Identifier: Apache-2.0
// A 3-D velocity sequence as a flow (volume/flow.h; docs/scenes.md "Velocity sequences"):
// trilinear in space, linear or Catmull-Rom cubic in time, with the divergence and curl of that
// interpolant, so d ln J/dt = div v (design.md §1) and the vorticity orientation integrate the
// field the impulses move in.

#include <algorithm>
#include <cmath>

#include "numeric/errors.h"
#include "sim/frame_window.h"
#include "volume/flow.h"

namespace impulse::volume {
namespace {

/// A point's cell on the grid, its weights in it, and which derivatives are the interpolant's
/// (false along an axis where the coordinate was clamped: the field is constant that way).
struct CellPoint {
    size_t i0[3] = {0, 0, 0};
    double a[3] = {0, 0, 0};
    bool d[3] = {true, true, true};
    bool zero = false;
};

class Sequence3 final : public Flow3 {
public:
    explicit Sequence3(Sequence3Config c)
        : m_c(c), m_window({c.first, c.last, c.start, c.rate, c.time}, checked(c), c.read_ahead) {}

    void add(double t, size_t n, const double* x, const double* y, const double* z, double* vx,
             double* vy, double* vz, double* div, const CurlOut3* curl) const override {
        const sim::TimeWeights tw = m_window.timing().weights_at(t);
        std::shared_ptr<const VolumeFrame> frames[4];
        for (int q = 0; q < tw.count; ++q) frames[q] = m_window.get(tw.frame[q]);
        const size_t W = size_t(m_c.size[0]), WH = W * size_t(m_c.size[1]);
        double* out[3] = {vx, vy, vz};
        for (size_t p = 0; p < n; ++p) {
            const CellPoint g = locate({x[p], y[p], z[p]});
            if (g.zero) continue;
            double u[3] = {0, 0, 0}, dudi[3] = {0, 0, 0};  // dudi[c]: d v_c / d index_c
            double grad[3][3] = {};  // with the curl wanted: grad[c][e] = d v_c / d index_e
            for (int corner = 0; corner < 8; ++corner) {
                const int b[3] = {corner & 1, (corner >> 1) & 1, (corner >> 2) & 1};
                double w = 1.0, dw[3];
                for (int c = 0; c < 3; ++c) w *= b[c] ? g.a[c] : 1.0 - g.a[c];
                for (int c = 0; c < 3; ++c) {  // d w / d index_c: the other two factors, signed
                    dw[c] = b[c] ? 1.0 : -1.0;
                    for (int e = 0; e < 3; ++e)
                        if (e != c) dw[c] *= b[e] ? g.a[e] : 1.0 - g.a[e];
                }
                const size_t k = (g.i0[2] + size_t(b[2])) * WH + (g.i0[1] + size_t(b[1])) * W + g.i0[0] + size_t(b[0]);
                for (int q = 0; q < tw.count; ++q)
                    for (int c = 0; c < 3; ++c) {
                        const double v = frames[q]->v[3 * k + size_t(c)];
                        u[c] += tw.weight[q] * w * v;
                        dudi[c] += tw.weight[q] * dw[c] * v;
                        if (curl)
                            for (int e = 0; e < 3; ++e) grad[c][e] += tw.weight[q] * dw[e] * v;
                    }
            }
            for (int c = 0; c < 3; ++c) out[c][p] += u[c];
            if (div)
                for (int c = 0; c < 3; ++c)  // d/dx_c = scale_c d/d index_c
                    if (g.d[c]) div[p] += m_c.scale[size_t(c)] * dudi[c];
            if (curl) {  // the same derivatives of the same interpolant as the divergence
                auto d = [&](int c, int e) { return g.d[e] ? m_c.scale[size_t(e)] * grad[c][e] : 0.0; };
                curl->x[p] += d(2, 1) - d(1, 2);
                curl->y[p] += d(0, 2) - d(2, 0);
                curl->z[p] += d(1, 0) - d(0, 1);
            }
        }
    }
    double max_speed(const Box3&) const override {
        return m_window.timing().overshoot() * m_c.max_sample_speed;
    }
    void prepare_span(double t0, double t1) override { m_window.prepare_span(t0, t1); }

private:
    static sim::FrameWindow<VolumeFrame>::Loader checked(const Sequence3Config& c) {
        return [load = c.load, size = c.size](int64_t k) {
            VolumeFrame f = load(k);
            if (f.size != size || f.v.size() != 3 * size_t(size[0]) * size_t(size[1]) * size_t(size[2]))
                throw ValueError("velocity sequence: frame " + std::to_string(k) +
                                 " is not the size of the first");
            return f;
        };
    }

    CellPoint locate(const std::array<double, 3>& X) const {
        CellPoint g;
        bool outside = false;
        double q[3];
        for (int c = 0; c < 3; ++c) {
            const double f = m_c.scale[size_t(c)] * X[size_t(c)] + m_c.offset[size_t(c)];
            const double hi = m_c.size[size_t(c)] - 1.0;
            const bool out = !(f >= 0.0 && f <= hi);
            outside = outside || out;
            q[c] = std::clamp(f, 0.0, hi);
            g.d[c] = !out;
        }
        if (outside && m_c.outside == sim::Outside::Zero) {
            g.zero = true;
            return g;
        }
        for (int c = 0; c < 3; ++c) {
            if (outside && m_c.outside == sim::Outside::Nearest) q[c] = std::round(q[c]), g.d[c] = false;
            g.i0[c] = std::min(static_cast<size_t>(q[c]), size_t(m_c.size[size_t(c)] - 2));
            g.a[c] = q[c] - double(g.i0[c]);
        }
        return g;
    }

    Sequence3Config m_c;
    sim::FrameWindow<VolumeFrame> m_window;
};

}  // namespace

std::unique_ptr<Flow3> make_sequence_flow3(Sequence3Config c) {
    bool ok = bool(c.load) && c.first <= c.last && std::isfinite(c.start) &&
              std::isfinite(c.rate) && std::isfinite(c.max_sample_speed) && c.max_sample_speed >= 0;
    for (int k = 0; k < 3; ++k)
        ok = ok && c.size[size_t(k)] >= 2 && std::isfinite(c.scale[size_t(k)]) &&
             c.scale[size_t(k)] != 0.0 && std::isfinite(c.offset[size_t(k)]);
    if (!ok)
        throw ValueError("velocity sequence: expected a loader, first <= last, a grid of 2x2x2 "
                         "samples or more and finite, non-zero scales");
    return std::make_unique<Sequence3>(std::move(c));
}

double max_interpolated_divergence3(const VolumeFrame& f, const std::array<double, 3>& s) {
    const size_t W = size_t(f.size[0]), H = size_t(f.size[1]), D = size_t(f.size[2]);
    auto at = [&](size_t i, size_t j, size_t k, int c) { return double(f.v[3 * ((k * H + j) * W + i) + size_t(c)]); };
    double m = 0.0;
    // at every sample, the one-sided differences towards each neighbouring cell's other corners
    for (size_t k = 0; k < D; ++k)
        for (size_t j = 0; j < H; ++j)
            for (size_t i = 0; i < W; ++i)
                for (int side = 0; side < 8; ++side) {
                    const size_t n[3] = {i, j, k}, N[3] = {W, H, D};
                    double d = 0.0;
                    bool ok = true;
                    size_t p[3] = {i, j, k};
                    for (int c = 0; c < 3; ++c) {
                        const bool up = (side >> c) & 1;
                        if ((up && n[c] + 1 >= N[c]) || (!up && n[c] == 0)) ok = false;
                    }
                    if (!ok) continue;
                    for (int c = 0; c < 3; ++c) {
                        const bool up = (side >> c) & 1;
                        size_t a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
                        if (up) b[c] += 1;
                        else a[c] -= 1;
                        d += s[size_t(c)] * (at(b[0], b[1], b[2], c) - at(a[0], a[1], a[2], c));
                    }
                    m = std::max(m, std::abs(d));
                }
    return m;
}

}  // namespace impulse::volume
