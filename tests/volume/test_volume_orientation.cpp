// SPDX-License-Identifier: Apache-2.0
// Oriented, stretched 3-D kernels (docs/volume.md "Orientation"): the vorticity orientation
// turns a kernel by the rotation the flow gives it, to the Heun integrator's stated error; the
// flow orientation lies along v; zero vorticity keeps the identity; the curl-noise flow's
// analytic curl against finite differences of its velocity. (Frames of an oriented, stretched
// cloud have the same bits for any frame range: tests/volume/test_volume_core.cpp.)

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "volume/volume.h"

using namespace impulse;

namespace {

/// Solid-body rotation about the vertical line through (cx, cy) at omega rad/s plus a wind w
/// along z: v = omega z^ x (x - c) + (0, 0, w), div v = 0, curl v = (0, 0, 2 omega) exactly.
/// Particles keep their distance from the axis, so one that reaches kView (plus the support)
/// is never further than kReach from it: that speed bounds the travel the birth region needs.
class SolidBody final : public volume::Flow3 {
public:
    SolidBody(double omega, double cx, double cy, double w) : m_o(omega), m_cx(cx), m_cy(cy), m_w(w) {}
    void add(double, size_t n, const double* x, const double* y, const double*, double* vx,
             double* vy, double* vz, double*, const volume::CurlOut3* curl) const override {
        for (size_t i = 0; i < n; ++i) {
            vx[i] += -m_o * (y[i] - m_cy);
            vy[i] += m_o * (x[i] - m_cx);
            vz[i] += m_w;
            if (curl) curl->z[i] += 2.0 * m_o;
        }
    }
    bool divergence_free() const override { return true; }
    double max_speed(const volume::Box3&) const override {
        constexpr double kReach = 25.5;  // hypot(18, 18): kView's corner, plus 6, from the axis
        return std::abs(m_o) * kReach + std::abs(m_w);
    }

private:
    double m_o, m_cx, m_cy, m_w;
};

volume::Process3 process(sim::OrientationMode mode) {
    volume::Process3 p;
    p.seed = 21;
    p.intensity = 1e-2;
    p.cell_size = 6.0;
    p.lifetime_s = 2.0;
    p.fps = 10.0;
    p.substeps = 1;
    p.orientation = mode;
    return p;
}

const volume::Box3 kView{0, 0, 0, 24, 24, 24};

/// The angle in (-pi, pi] congruent to a.
double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

}  // namespace

TEST_CASE("volume orientation: solid-body rotation turns each kernel by Omega t",
          "[volume][orientation]") {
    // omega = curl v = (0, 0, 2 Omega): dR/dt = [omega/2]_x R turns the axis about z at Omega,
    // so an impulse of age a has its axis at angle Omega a from x. Heun's step on du/dt = A u
    // (A = Omega J) multiplies by 1 + i phi - phi^2/2 (phi = Omega h): its angle is
    // atan2(phi, 1 - phi^2/2) = phi + phi^3/6 - phi^5/20 + ..., so each step (the first one
    // shorter, from the birth) leads by at most phi^3/6 <= phi (Omega h)^2 / 6 and the axis by
    // at most Omega^3 h^2 a / 6 after age a. Plus the axis's float storage, |du| <= sqrt(3)
    // 2^-24 ~ 1e-7 rad (band 1e-6).
    // Shown able to fail: the spin with omega in place of omega/2 (volume/process.cpp) turns
    // the axes by 2 Omega a and fails by up to 2 rad.
    const double omega = 1.0, h = 0.1;  // rad/s; one Heun step per frame at 10 fps
    auto flow = std::make_shared<SolidBody>(omega, 12.0, 12.0, 0.0);
    volume::Simulator3 sim(process(sim::OrientationMode::Vorticity), flow, 6.0);
    volume::Impulses3 imp;
    sim.impulses_at(25, kView, imp);  // t = 2.5 s: ages over the whole lifetime
    REQUIRE(imp.size() > 100);
    REQUIRE(imp.ax.size() == imp.size());
    double worst = 0.0, worst_ratio = 0.0, oldest = 0.0;
    for (size_t i = 0; i < imp.size(); ++i) {
        const double a = imp.age_s[i];
        const double err = std::abs(wrap(std::atan2(double(imp.ay[i]), double(imp.ax[i])) - omega * a));
        const double bound = omega * omega * omega * h * h * a / 6.0 + 1e-6;
        worst = std::max(worst, err), worst_ratio = std::max(worst_ratio, err / bound);
        oldest = std::max(oldest, a);
        CHECK(err <= bound);
        CHECK(std::abs(imp.az[i]) <= 1e-7);  // no tilt out of the plane
    }
    std::printf("[volume]   vorticity orientation, solid-body rotation: %zu impulses up to age "
                "%.2f s, largest angle error %.2e rad, %.3f of the stated Heun bound\n",
                imp.size(), oldest, worst, worst_ratio);
    CHECK(oldest > 1.5);  // some have turned by over 1.5 rad
}

TEST_CASE("volume orientation: zero vorticity keeps the identity, fixed has no axes, random "
          "ones are uniform",
          "[volume][orientation]") {
    // A uniform wind and a uniform divergence have curl 0: the axis stays x exactly (the Heun
    // increments are exact zeros).
    auto sum = std::make_shared<volume::FlowSum3>();
    sum->push(volume::make_uniform_flow3({3.0, -1.0, 2.0}));
    sum->push(volume::make_divergent_flow3({12, 12, 12}, 0.1));
    volume::Simulator3 sim(process(sim::OrientationMode::Vorticity), sum, 6.0);
    volume::Impulses3 imp;
    sim.impulses_at(25, kView, imp);
    REQUIRE(imp.size() > 100);
    for (size_t i = 0; i < imp.size(); ++i) {
        CHECK(imp.ax[i] == 1.0f);
        CHECK(imp.ay[i] == 0.0f);
        CHECK(imp.az[i] == 0.0f);
    }
    // Fixed carries no axes (the kernel's own, x).
    volume::Simulator3 fixed(process(sim::OrientationMode::Fixed), sum, 6.0);
    fixed.impulses_at(25, kView, imp);
    CHECK(imp.ax.empty());
    // Random: uniform on the sphere, so each |component| has mean 1/2 (sd 1/sqrt(12)): the
    // mean over n impulses within 5 sd / sqrt(n) of 1/2; and an axis is its impulse's, kept
    // for life: the same impulse (same position, weight) has the same axis a frame later when
    // there is no flow.
    volume::Simulator3 rnd(process(sim::OrientationMode::Random), nullptr, 6.0);
    rnd.impulses_at(25, kView, imp);
    REQUIRE(imp.size() > 100);
    double m[3] = {0, 0, 0};
    for (size_t i = 0; i < imp.size(); ++i) {
        CHECK(std::abs(double(imp.ax[i]) * imp.ax[i] + double(imp.ay[i]) * imp.ay[i] +
                       double(imp.az[i]) * imp.az[i] - 1.0) < 1e-6);
        m[0] += std::abs(imp.ax[i]) / double(imp.size());
        m[1] += std::abs(imp.ay[i]) / double(imp.size());
        m[2] += std::abs(imp.az[i]) / double(imp.size());
    }
    const double band = 5.0 / std::sqrt(12.0 * double(imp.size()));
    for (double v : m) CHECK(std::abs(v - 0.5) < band);
    volume::Impulses3 later;
    rnd.impulses_at(26, kView, later);
    size_t same = 0;
    for (size_t i = 0; i < imp.size(); ++i)
        for (size_t j = 0; j < later.size(); ++j)
            if (later.x[j] == imp.x[i] && later.y[j] == imp.y[i] && later.z[j] == imp.z[i]) {
                same += later.ax[j] == imp.ax[i] && later.ay[j] == imp.ay[i] && later.az[j] == imp.az[i];
                break;
            }
    CHECK(same > imp.size() / 2);  // most live on into the next frame, each with its axis
}

TEST_CASE("volume orientation: flow orientation lies along v", "[volume][orientation]") {
    // The rotation plus a wind w = 1.5 along z: |v| >= 1.5 everywhere, so the direction is
    // defined; the axis is v / |v| at the impulse at the frame time, stored as float: angle
    // <= sqrt(3) 2^-24 ~ 1e-7 (band 1e-6). Shown able to fail: with the axes left at x (no
    // flow_axes in volume/process.cpp) the angles are up to ~90 degrees.
    const double t = 2.5;
    auto flow = std::make_shared<SolidBody>(0.7, 12.0, 12.0, 1.5);
    volume::Simulator3 sim(process(sim::OrientationMode::Flow), flow, 6.0);
    volume::Impulses3 imp;
    sim.impulses_at(25, kView, imp);
    REQUIRE(imp.size() > 100);
    double worst = 0.0;
    for (size_t i = 0; i < imp.size(); ++i) {
        double v[3] = {0, 0, 0};
        flow->add(t, 1, &imp.x[i], &imp.y[i], &imp.z[i], &v[0], &v[1], &v[2], nullptr, nullptr);
        const double u[3] = {imp.ax[i], imp.ay[i], imp.az[i]};
        const double cross[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                                 u[0] * v[1] - u[1] * v[0]};
        const double angle = std::atan2(std::sqrt(cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]),
                                        u[0] * v[0] + u[1] * v[1] + u[2] * v[2]);
        worst = std::max(worst, angle);
    }
    std::printf("[volume]   flow orientation, analytic flow: largest angle to v %.2e rad\n", worst);
    CHECK(worst < 1e-6);
    // No velocity, no direction: the kernel keeps its own axis, x.
    auto still = std::shared_ptr<volume::Flow3>(volume::make_uniform_flow3({0, 0, 0}));
    volume::Simulator3 calm(process(sim::OrientationMode::Flow), still, 6.0);
    calm.impulses_at(25, kView, imp);
    REQUIRE(imp.size() > 100);
    for (size_t i = 0; i < imp.size(); ++i) CHECK((imp.ax[i] == 1.0f && imp.ay[i] == 0.0f && imp.az[i] == 0.0f));
}

TEST_CASE("volume orientation: the curl-noise flow's curl is that of its velocity",
          "[volume][orientation][flows]") {
    // The analytic curl, grad(div psi) - lap psi, against central differences of v (h = 1e-3
    // voxels: truncation O(h^2 |d^3 v|), far below |omega| ~ speed / scale). Shown able to
    // fail: the Laplacian's sign flipped (grad_div + lap) gives errors of the size of omega.
    const double s = 16.0, speed = 3.0, h = 1e-3;
    auto flow = volume::make_curl_flow3(9, s, speed);
    flow->prepare({-50, -50, -50, 250, 250, 250});
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<double> U(0.0, 200.0);
    double err2 = 0.0, w2 = 0.0;
    for (int i = 0; i < 2000; ++i) {
        const double p[3] = {U(gen), U(gen), U(gen)};
        double v[3] = {0, 0, 0}, w[3] = {0, 0, 0};
        const volume::CurlOut3 out{&w[0], &w[1], &w[2]};
        flow->add(0.0, 1, &p[0], &p[1], &p[2], &v[0], &v[1], &v[2], nullptr, &out);
        double g[3][3];  // g[c][a] = d v_c / d x_a
        for (int a = 0; a < 3; ++a) {
            double q[2][3] = {{p[0], p[1], p[2]}, {p[0], p[1], p[2]}};
            q[0][a] -= h, q[1][a] += h;
            double u[2][3] = {};
            for (int k = 0; k < 2; ++k)
                flow->add(0.0, 1, &q[k][0], &q[k][1], &q[k][2], &u[k][0], &u[k][1], &u[k][2], nullptr);
            for (int c = 0; c < 3; ++c) g[c][a] = (u[1][c] - u[0][c]) / (2 * h);
        }
        const double fd[3] = {g[2][1] - g[1][2], g[0][2] - g[2][0], g[1][0] - g[0][1]};
        for (int c = 0; c < 3; ++c) err2 += (w[c] - fd[c]) * (w[c] - fd[c]), w2 += w[c] * w[c];
        // asking for the curl leaves the velocity's bits as they were
        double v0[3] = {0, 0, 0};
        flow->add(0.0, 1, &p[0], &p[1], &p[2], &v0[0], &v0[1], &v0[2], nullptr);
        CHECK((v0[0] == v[0] && v0[1] == v[1] && v0[2] == v[2]));
    }
    std::printf("[volume]   curl flow: RMS |omega| %.4f /s, RMS error against central differences %.2e\n",
                std::sqrt(w2 / 2000), std::sqrt(err2 / 2000));
    CHECK(std::sqrt(w2 / 2000) > 0.1 * speed / s);
    CHECK(std::sqrt(err2) < 1e-5 * std::sqrt(w2));
}
