// SPDX-License-Identifier: Apache-2.0
// Motion blur by stratified sub-steps (docs/motion_blur.md): a Gaussian on a straight path
// against its closed form (an erf along the motion, a Gaussian across it), and a blurred frame in
// a curl flow against the mean of many instantaneous sub-frames on the same time grid, each within
// the stated midpoint-rule bound; forcing one sub-step breaks the second.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "sim/sim.h"

using namespace impulse;

namespace {

constexpr double kSigma = 3.0;        // the test kernel: an untruncated Gaussian, peak 1
constexpr double kCurvature = 1.0 / (kSigma * kSigma);  // max |d^2 h / ds^2|, at its centre
constexpr double kReach = 8.0 * kSigma;                  // exp(-32): beyond it h is nothing

double gauss(double dx, double dy) { return std::exp(-(dx * dx + dy * dy) / (2 * kSigma * kSigma)); }

/// The travel between copies that keeps each impulse's blurred kernel within eps of its peak
/// (scenes::CameraConfig::shutter_at for this kernel).
double max_step(double eps) { return std::sqrt(24.0 * eps / kCurvature); }

/// sum_k w_k h(x - x_k) on a grid of points with spacing 1 over [x0, x0 + n) x [y0, y0 + n).
std::vector<double> field(const sim::Impulses& imp, double x0, double y0, int n) {
    std::vector<double> f(size_t(n) * n, 0.0);
    for (size_t k = 0; k < imp.size(); ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                f[size_t(j) * n + i] += imp.weight[k] * gauss(x0 + i - imp.x[k], y0 + j - imp.y[k]);
    return f;
}

/// sum over impulses within kReach + travel of each grid point of |w_k|: the stated bounds are
/// per impulse, in units of its weight.
std::vector<double> weight_near(const sim::Impulses& imp, double travel, double x0, double y0,
                                int n) {
    std::vector<double> f(size_t(n) * n, 0.0);
    for (size_t k = 0; k < imp.size(); ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i)
                if (std::hypot(x0 + i - imp.x[k], y0 + j - imp.y[k]) < kReach + travel)
                    f[size_t(j) * n + i] += std::abs(imp.weight[k]);
    return f;
}

sim::ProcessConfig process(double lifetime, sim::Envelope envelope, double intensity) {
    sim::ProcessConfig c;
    c.seed = 7;
    c.intensity = intensity;
    c.cell_size = kReach;
    c.lifetime_s = lifetime;
    c.envelope = envelope;
    return c;
}

}  // namespace

TEST_CASE("a Gaussian blurred along a straight path matches its erf closed form", "[sim][blur]") {
    // Uniform wind of 150 units/s at 30 fps, a 180-degree shutter centred on the frame: each
    // impulse travels 2.5 units = 0.83 sigma. Box envelope and a long life: weights stay a_k.
    const double vx = 120.0, vy = 90.0, fps = 30.0, eps = 1e-5;
    auto flow = std::shared_ptr<sim::Flow>(sim::make_uniform_flow(vx, vy));
    sim::ProcessConfig c = process(100.0, sim::Envelope::Box, 0.002);
    c.amplitude = sim::Amplitude::Sign;  // weights +-1: the bound is eps of a peak per impulse
    c.max_travel = 1e5;
    sim::LayerSimulator plain(c, flow, {fps, 0}, kReach), blurred(c, flow, {fps, 0}, kReach);
    const numeric::Region view(numeric::Box{0.0, 0.0, 96.0, 96.0});
    const int64_t frame = 12;
    sim::Shutter sh;
    sh.open_s = -0.25 / fps, sh.close_s = 0.25 / fps, sh.max_step = max_step(eps);
    sim::Impulses at_frame, copies;
    plain.impulses_at(frame, view, at_frame);
    blurred.impulses_at(frame, view, sh, copies);
    REQUIRE(at_frame.size() > 3);
    REQUIRE(copies.size() > 4 * at_frame.size());  // 2.5 / max_step(1e-5) = 54: 64 copies each

    // (1/S) int h(x - p_k - v s) ds over the shutter, with u along v and q across it.
    const double speed = std::hypot(vx, vy), ex = vx / speed, ey = vy / speed;
    const double a = speed * sh.open_s, b = speed * sh.close_s, r2s = std::sqrt(2.0) * kSigma;
    auto exact = [&](double x, double y) {
        double f = 0;
        for (size_t k = 0; k < at_frame.size(); ++k) {
            const double dx = x - at_frame.x[k], dy = y - at_frame.y[k];
            const double u = dx * ex + dy * ey, q = -dx * ey + dy * ex;
            f += at_frame.weight[k] * std::exp(-q * q / (2 * kSigma * kSigma)) * kSigma *
                 std::sqrt(std::numbers::pi / 2) / (b - a) *
                 (std::erf((u - a) / r2s) - std::erf((u - b) / r2s));
        }
        return f;
    };
    const int n = 64;
    const double x0 = 16, y0 = 16;
    const auto got = field(copies, x0, y0, n);
    const auto bound = weight_near(at_frame, b - a, x0, y0, n);
    double worst = 0, largest = 0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const size_t p = size_t(j) * n + i;
            const double err = std::abs(got[p] - exact(x0 + i, y0 + j));
            worst = std::max(worst, err / (eps * bound[p] + 1e-12));
            largest = std::max(largest, err);
        }
    // Checked by hand: with one copy per impulse (max_samples = 1) the worst ratio is ~1e3.
    INFO("largest error " << largest << " (peaks of 1); worst error / bound " << worst);
    CHECK(worst <= 1.0);
}

TEST_CASE("a blurred frame is the mean of instantaneous sub-frames on the same time grid",
          "[sim][blur]") {
    // Wind 240 units/s plus curl noise (RMS 60) at 30 fps, Hann lifetimes of 1 s, a full shutter:
    // 8 units (2.7 sigma) of travel in a frame. The reference is M = 16 frames at 16 x the frame
    // rate (substeps 16 and 1: the same time grid, so the same positions at the grid points), at
    // the centres of M strata of the shutter: the midpoint rule with M strata. Both sides are
    // within their midpoint bounds of the path integral, per impulse (units of its weight):
    // position eps (blurred, by construction) and (D / M)^2 max|h''| / 24 (reference), D <= the
    // largest speed times the shutter; envelope S^2 max|w''| / 24 for one copy, max|w''| =
    // 2 pi^2 / T^2 (Hann). Paths that bend within the shutter are not in the bound: the curl
    // noise's scale (40) is five times the travel.
    const double fps = 30.0, eps = 1e-3, S = 1.0 / fps;
    const int M = 16;
    auto make_flow = [] {
        auto f = std::make_shared<sim::FlowSum>();
        f->push(sim::make_uniform_flow(240.0, 0.0));
        f->push(sim::make_curl_noise_flow(5, 40.0, 60.0, std::nullopt));
        return f;
    };
    sim::ProcessConfig c = process(1.0, sim::Envelope::Hann, 0.01);
    c.substeps = M;
    sim::ProcessConfig fine = c;
    fine.substeps = 1;
    auto flow = make_flow();
    sim::LayerSimulator blurred(c, flow, {fps, 0}, kReach), forced(c, flow, {fps, 0}, kReach);
    sim::LayerSimulator sub(fine, make_flow(), {fps * M, 0}, kReach);
    const numeric::Region view(numeric::Box{0.0, 0.0, 96.0, 96.0});
    const int64_t frame = 40;
    sim::Shutter sh;
    sh.open_s = -0.5 * S - 0.5 * S / M, sh.close_s = sh.open_s + S, sh.max_step = max_step(eps);
    sim::Impulses copies, one_each, at;
    blurred.impulses_at(frame, view, sh, copies);
    sim::Shutter single = sh;
    single.max_samples = 1;
    forced.impulses_at(frame, view, single, one_each);

    const int n = 48;
    const double x0 = 24, y0 = 24;
    std::vector<double> mean(size_t(n) * n, 0.0), near(size_t(n) * n, 0.0);
    const double vmax = flow->max_speed(view.bounds().expanded(64.0)), D = vmax * S;
    for (int j = 0; j < M; ++j) {
        sub.impulses_at(frame * M - M / 2 + j, view, at);
        const auto f = field(at, x0, y0, n);
        for (size_t p = 0; p < f.size(); ++p) mean[p] += f[p] / M;
        if (j == M / 2) near = weight_near(at, D, x0, y0, n);
    }
    const double per_impulse =
        eps + (D / M) * (D / M) * kCurvature / 24.0 +
        S * S * 2.0 * std::numbers::pi * std::numbers::pi / (c.lifetime_s * c.lifetime_s) / 24.0;
    auto worst_ratio = [&](const sim::Impulses& imp) {
        const auto f = field(imp, x0, y0, n);
        double worst = 0;
        for (size_t p = 0; p < f.size(); ++p)
            worst = std::max(worst, std::abs(f[p] - mean[p]) / (per_impulse * near[p] + 1e-12));
        return worst;
    };
    const double blur_ratio = worst_ratio(copies), forced_ratio = worst_ratio(one_each);
    INFO("travel bound " << D << ", per-impulse bound " << per_impulse << ", copies "
                         << copies.size() << " vs " << one_each.size());
    INFO("worst error / bound: sub-stepped " << blur_ratio << ", one sub-step " << forced_ratio);
    CHECK(blur_ratio <= 1.0);
    CHECK(forced_ratio > 1.0);  // the mechanism switched off fails
}

TEST_CASE("a closed shutter gives the unblurred impulses bit for bit; a blurred frame does not "
          "depend on the frames before it", "[sim][blur]") {
    auto flow = std::make_shared<sim::FlowSum>();
    flow->push(sim::make_uniform_flow(50.0, 10.0));
    flow->push(sim::make_curl_noise_flow(5, 40.0, 30.0, std::nullopt));
    const sim::ProcessConfig c = process(1.0, sim::Envelope::Hann, 0.01);
    const numeric::Region view(numeric::Box{0.0, 0.0, 64.0, 64.0});
    sim::LayerSimulator a(c, flow, {24.0, 0}, kReach), b(c, flow, {24.0, 0}, kReach);
    sim::Impulses x, y;
    a.impulses_at(9, view, x);
    b.impulses_at(9, view, sim::Shutter{}, y);
    CHECK(x.x == y.x);
    CHECK(x.weight == y.weight);
    sim::Shutter sh;
    sh.open_s = -0.25 / 24.0, sh.close_s = 0.25 / 24.0, sh.max_step = 0.3;
    sim::LayerSimulator seq(c, flow, {24.0, 0}, kReach), alone(c, flow, {24.0, 0}, kReach);
    for (int f = 0; f <= 9; ++f) seq.impulses_at(f, view, sh, x);
    alone.impulses_at(9, view, sh, y);
    REQUIRE(x.size() > 100);
    CHECK(x.x == y.x);
    CHECK(x.y == y.y);
    CHECK(x.weight == y.weight);
    CHECK(x.theta == y.theta);
}
