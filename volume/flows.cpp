// SPDX-License-Identifier: Apache-2.0
// 3-D flows: uniform wind, uniform divergence and curl noise (Bridson, Hourihan & Nordenstam
// 2007, "Curl-noise for procedural fluid flow": v = curl psi is divergence-free for any smooth
// vector potential psi).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "numeric/errors.h"
#include "numeric/rng.h"
#include "volume/flow.h"

namespace impulse::volume {

void FlowSum3::add(double t_s, size_t n, const double* x, const double* y, const double* z,
                   double* vx, double* vy, double* vz, double* div, const CurlOut3* curl) const {
    for (const auto& f : m_terms) f->add(t_s, n, x, y, z, vx, vy, vz, div, curl);
}
bool FlowSum3::divergence_free() const {
    return std::all_of(m_terms.begin(), m_terms.end(),
                       [](const auto& f) { return f->divergence_free(); });
}
double FlowSum3::max_speed(const Box3& region) const {
    double s = 0.0;
    for (const auto& f : m_terms) s += f->max_speed(region);
    return s;
}
void FlowSum3::prepare(const Box3& region) {
    for (auto& f : m_terms) f->prepare(region);
}
void FlowSum3::prepare_span(double t0_s, double t1_s) {
    for (auto& f : m_terms) f->prepare_span(t0_s, t1_s);
}

namespace {

class Uniform3 final : public Flow3 {
public:
    explicit Uniform3(const std::array<double, 3>& v) : m_v(v) {}
    void add(double, size_t n, const double*, const double*, const double*, double* vx,
             double* vy, double* vz, double*, const CurlOut3*) const override {
        for (size_t i = 0; i < n; ++i) vx[i] += m_v[0], vy[i] += m_v[1], vz[i] += m_v[2];
    }  // curl 0: nothing to add
    bool divergence_free() const override { return true; }
    double max_speed(const Box3&) const override {
        return std::sqrt(m_v[0] * m_v[0] + m_v[1] * m_v[1] + m_v[2] * m_v[2]);
    }

private:
    std::array<double, 3> m_v;
};

class Divergent3 final : public Flow3 {
public:
    Divergent3(const std::array<double, 3>& c, double rate, double pulse, double period)
        : m_c(c), m_rate(rate), m_pulse(pulse), m_period(period) {}
    double rate(double t) const {
        return m_pulse == 0.0 ? m_rate
                              : m_rate + m_pulse * std::sin(2.0 * std::numbers::pi * t / m_period);
    }
    // v = r (x - c) is a gradient (of r |x - c|^2 / 2): curl 0, nothing to add.
    void add(double t, size_t n, const double* x, const double* y, const double* z, double* vx,
             double* vy, double* vz, double* div, const CurlOut3*) const override {
        const double r = rate(t);
        for (size_t i = 0; i < n; ++i) {
            vx[i] += r * (x[i] - m_c[0]);
            vy[i] += r * (y[i] - m_c[1]);
            vz[i] += r * (z[i] - m_c[2]);
        }
        if (div)
            for (size_t i = 0; i < n; ++i) div[i] += 3.0 * r;  // d ln J / dt = div v
    }
    double max_speed(const Box3& b) const override {
        const double dx = std::max(std::abs(b.x0 - m_c[0]), std::abs(b.x1 - m_c[0]));
        const double dy = std::max(std::abs(b.y0 - m_c[1]), std::abs(b.y1 - m_c[1]));
        const double dz = std::max(std::abs(b.z0 - m_c[2]), std::abs(b.z1 - m_c[2]));
        return (std::abs(m_rate) + std::abs(m_pulse)) * std::sqrt(dx * dx + dy * dy + dz * dz);
    }

private:
    std::array<double, 3> m_c;
    double m_rate, m_pulse, m_period;
};

/// |v| / RMS speed bound of the curl flow, empirical: tests/volume/test_flows.cpp measures the
/// largest |v| over 10^5 random points and requires it below this.
constexpr double kSpeedBound = 3.5;

/// psi's impulses per cell of side s (a fixed count: the flow needs no Gaussian marginal).
constexpr int kCurlPerCell = 4;

/// The 4 impulses of a potential cell: position (cell units) and vector amplitude in [-1, 1]^3.
struct CurlCell {
    std::array<float, kCurlPerCell * 3> p, a;
};

class Curl3 final : public Flow3 {
public:
    Curl3(uint64_t seed, double scale, double speed) : m_rng(seed, 0x4355524Cu), m_s(scale), m_speed(std::abs(speed)) {
        // RMS speed: each component's gradient has per-axis variance g2 = lambda E[a^2]
        // (1/3) int |grad phi|^2 d^3x (Campbell), lambda = 4 / s^3, E[a^2] = 1/3; a curl
        // component is a difference of two independent such derivatives, so E|v|^2 = 6 g2.
        // int |grad phi|^2 = 144 pi s int_0^1 u^4 (1 - u^2)^4 du (phi = (1 - r^2/s^2)^3).
        double integral = 0.0;
        constexpr int kSteps = 4096;
        for (int i = 0; i < kSteps; ++i) {
            const double u = (i + 0.5) / kSteps, w = 1.0 - u * u;
            integral += u * u * u * u * w * w * w * w / kSteps;
        }
        const double grad2 = 144.0 * std::numbers::pi * scale * integral;
        const double g2 = kCurlPerCell / (scale * scale * scale) / 3.0 * grad2 / 3.0;
        m_gain = speed / std::sqrt(6.0 * g2);
    }
    bool divergence_free() const override { return true; }
    // Empirical bound (kSpeedBound RMS, see its comment): a particle that outruns the birth
    // margin only misses an impulse near the view's edge.
    double max_speed(const Box3&) const override { return kSpeedBound * m_speed; }
    void prepare(const Box3& region) override;
    void add(double t_s, size_t n, const double* x, const double* y, const double* z, double* vx,
             double* vy, double* vz, double* div, const CurlOut3* curl) const override;

private:
    CurlCell make_cell(int64_t cx, int64_t cy, int64_t cz) const;
    const CurlCell& cell(int64_t cx, int64_t cy, int64_t cz, CurlCell& scratch) const;

    numeric::CounterRng m_rng;
    double m_s, m_speed, m_gain = 1.0;
    // Cells of the prepared region (a pure function of the seed: any region gives the same).
    std::array<int64_t, 3> m_c0{}, m_n{};
    std::vector<CurlCell> m_cache;
};

CurlCell Curl3::make_cell(int64_t cx, int64_t cy, int64_t cz) const {
    CurlCell c;
    for (int k = 0; k < kCurlPerCell; ++k) {
        const auto r0 = m_rng.uniforms(cx, cy, cz, 2u * k);
        const auto r1 = m_rng.uniforms(cx, cy, cz, 2u * k + 1u);
        for (int j = 0; j < 3; ++j) c.p[3 * k + j] = static_cast<float>(r0[j]);
        c.a[3 * k + 0] = static_cast<float>(2.0 * r0[3] - 1.0);
        c.a[3 * k + 1] = static_cast<float>(2.0 * r1[0] - 1.0);
        c.a[3 * k + 2] = static_cast<float>(2.0 * r1[1] - 1.0);
    }
    return c;
}

void Curl3::prepare(const Box3& r) {
    const double s = m_s;
    const std::array<int64_t, 3> c0 = {int64_t(std::floor(r.x0 / s)) - 1,
                                       int64_t(std::floor(r.y0 / s)) - 1,
                                       int64_t(std::floor(r.z0 / s)) - 1};
    const std::array<int64_t, 3> c1 = {int64_t(std::floor(r.x1 / s)) + 1,
                                       int64_t(std::floor(r.y1 / s)) + 1,
                                       int64_t(std::floor(r.z1 / s)) + 1};
    const std::array<int64_t, 3> n = {c1[0] - c0[0] + 1, c1[1] - c0[1] + 1, c1[2] - c0[2] + 1};
    if (c0 == m_c0 && n == m_n) return;
    if (double(n[0]) * double(n[1]) * double(n[2]) > 1e7) {  // leave the cache empty: on the fly
        m_cache.clear(), m_n = {};
        return;
    }
    m_c0 = c0, m_n = n;
    m_cache.resize(size_t(n[0] * n[1] * n[2]));
    for (int64_t k = 0; k < n[2]; ++k)
        for (int64_t j = 0; j < n[1]; ++j)
            for (int64_t i = 0; i < n[0]; ++i)
                m_cache[size_t((k * n[1] + j) * n[0] + i)] = make_cell(c0[0] + i, c0[1] + j, c0[2] + k);
}

const CurlCell& Curl3::cell(int64_t cx, int64_t cy, int64_t cz, CurlCell& scratch) const {
    const int64_t i = cx - m_c0[0], j = cy - m_c0[1], k = cz - m_c0[2];
    if (i >= 0 && j >= 0 && k >= 0 && i < m_n[0] && j < m_n[1] && k < m_n[2])
        return m_cache[size_t((k * m_n[1] + j) * m_n[0] + i)];
    scratch = make_cell(cx, cy, cz);
    return scratch;
}

void Curl3::add(double, size_t n, const double* x, const double* y, const double* z, double* vx,
                double* vy, double* vz, double*, const CurlOut3* curl) const {
    CurlCell scratch;
    for (size_t i = 0; i < n; ++i) {
        // grad psi_c = sum_k a_kc phi'(q) 2 d / s^2 with phi'(q) = -3 (1 - q)^2, in cell units
        // (d / s); G[c][j] = d psi_c / d x_j times s.
        const double u[3] = {x[i] / m_s, y[i] / m_s, z[i] / m_s};
        const int64_t c[3] = {int64_t(std::floor(u[0])), int64_t(std::floor(u[1])),
                              int64_t(std::floor(u[2]))};
        double G[3][3] = {};
        // With the curl wanted: the Laplacian of each psi_c and the gradient of div psi, from
        // d2 phi / dd_j dd_l = 24 (1 - q) d_j d_l - 6 (1 - q)^2 delta_jl (cell units, times s^2).
        double lap[3] = {}, grad_div[3] = {};
        for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    const CurlCell& cc = cell(c[0] + dx, c[1] + dy, c[2] + dz, scratch);
                    for (int k = 0; k < kCurlPerCell; ++k) {
                        const double d[3] = {u[0] - (double(c[0] + dx) + cc.p[3 * k]),
                                             u[1] - (double(c[1] + dy) + cc.p[3 * k + 1]),
                                             u[2] - (double(c[2] + dz) + cc.p[3 * k + 2])};
                        const double q = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                        if (q >= 1.0) continue;
                        const double f = -6.0 * (1.0 - q) * (1.0 - q);
                        for (int cmp = 0; cmp < 3; ++cmp)
                            for (int j = 0; j < 3; ++j) G[cmp][j] += cc.a[3 * k + cmp] * f * d[j];
                        if (!curl) continue;
                        const double f2 = 24.0 * (1.0 - q);
                        const float* a = cc.a.data() + 3 * k;  // widened below
                        const double ad = double(a[0]) * d[0] + double(a[1]) * d[1] + double(a[2]) * d[2];
                        for (int j = 0; j < 3; ++j) {
                            lap[j] += double(a[j]) * (f2 * q + 3.0 * f);  // trace of the Hessian
                            grad_div[j] += f2 * ad * d[j] + f * double(a[j]);
                        }
                    }
                }
        const double g = m_gain / m_s;
        vx[i] += g * (G[2][1] - G[1][2]);  // d psi_z/dy - d psi_y/dz
        vy[i] += g * (G[0][2] - G[2][0]);  // d psi_x/dz - d psi_z/dx
        vz[i] += g * (G[1][0] - G[0][1]);  // d psi_y/dx - d psi_x/dy
        if (curl) {  // curl curl psi = grad(div psi) - lap psi, two derivatives: 1/s^2
            const double g2 = m_gain / (m_s * m_s);
            curl->x[i] += g2 * (grad_div[0] - lap[0]);
            curl->y[i] += g2 * (grad_div[1] - lap[1]);
            curl->z[i] += g2 * (grad_div[2] - lap[2]);
        }
    }
}

}  // namespace

std::unique_ptr<Flow3> make_uniform_flow3(const std::array<double, 3>& v) {
    return std::make_unique<Uniform3>(v);
}
std::unique_ptr<Flow3> make_divergent_flow3(const std::array<double, 3>& center, double rate,
                                            double pulse, double period_s) {
    if (pulse != 0.0 && !(period_s > 0.0))
        throw ValueError("divergent flow period = " + std::to_string(period_s) + ": expected > 0 with a pulse");
    return std::make_unique<Divergent3>(center, rate, pulse, period_s);
}
std::unique_ptr<Flow3> make_curl_flow3(uint64_t seed, double scale, double speed) {
    if (!(scale > 0.0) || !std::isfinite(scale))
        throw ValueError("curl flow scale = " + std::to_string(scale) + ": expected > 0");
    return std::make_unique<Curl3>(seed, scale, speed);
}

}  // namespace impulse::volume
