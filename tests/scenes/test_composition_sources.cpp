// SPDX-License-Identifier: Apache-2.0
// Layers as sources for other layers (docs/scenes.md "Composition"): a still layer's field as
// the stream function of another layer's flow (divergence-free, RMS speed as asked, particles
// on its level lines, the Jacobian exactly 1), and a layer's field orienting another layer's
// kernels (the measured local orientation follows the source's gradient or level lines).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/detail/compose.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"
#include "numeric/spline.h"
#include "tests/structure_tensor.h"

namespace {

using namespace impulse;
using render::Frame;
constexpr double kPi = std::numbers::pi;

Frame render_text(const std::string& text, int64_t frame = 0) {
    return test::render_scene_text(text, frame, "sources.toml");
}

/// A still cosine layer of radius `radius` as a stream function.
struct Stream {
    scenes::LayerConfig layer;
    kernels::Kernel kernel;
    sim::StreamFunction psi;
    explicit Stream(double radius, const std::string& extra = "")
        : layer(scenes::load_scene_string("[[layer]]\nseed = 7\n" + extra +
                                              "\n[layer.kernel]\nradius = " + std::to_string(radius) + "\n",
                                          "psi.toml")
                    .layers[0]),
          kernel(layer.kernel) {
        psi.process = layer.process;
        psi.gain = layer.gain.value(0.0);
        psi.radius = layer.kernel.radius;
        const kernels::Kernel* k = &kernel;
        psi.kernel = [k](double dx, double dy, double th) { return k->evaluate(dx, dy, th); };
        const bool random = layer.process.orientation == sim::OrientationMode::Random;
        psi.semivariogram = [k, random](double tx, double ty) {
            return scenes::detail::sampled_semivariogram(*k, random, tx, ty);
        };
    }
    /// psi at (x, y), exactly: the impulses of the 3 x 3 cells around it.
    double exact(double x, double y) const {
        const double c = layer.process.cell_size;
        const int64_t cx = int64_t(std::floor(x / c)), cy = int64_t(std::floor(y / c));
        sim::CellImpulses cell;
        double v = 0.0;
        for (int64_t b = -1; b <= 1; ++b)
            for (int64_t a = -1; a <= 1; ++a) {
                sim::cell_impulses(layer.process, cx + a, cy + b, 0, cell);
                for (size_t k = 0; k < cell.x.size(); ++k)
                    v += cell.amplitude[k] * kernel.evaluate(x - cell.x[k], y - cell.y[k]);
            }
        return layer.gain.value(0.0) * v;
    }
};

struct Velocity {
    double vx = 0, vy = 0, div = 0, curl = 0;
};
using test::same_bits;

Velocity velocity(const sim::Flow& f, double x, double y) {
    Velocity v;
    f.add(0.0, 1, &x, &y, &v.vx, &v.vy, &v.div, &v.curl);
    return v;
}

}  // namespace

TEST_CASE("layer flow: the semivariogram quadrature agrees with the exact autocorrelation",
          "[scenes][compose][flow][slow]") {
    // sampled_semivariogram against C(0) - C(tau) from Kernel::autocorrelation, whose own
    // error is ~1e-6 C(0) for the cosine kernel and 1e-4 C(0) for kernels truncated with a jump
    // (the Gaussian here): allowed on top of 1e-3 of the value (the quadrature is far better,
    // 1e-6 and 2e-4 where measured).
    const kernels::Kernel iso(kernels::KernelParams{});  // cosine, radius 16
    kernels::KernelParams ep;
    ep.type = kernels::KernelType::Gaussian;
    ep.radius = 20.0, ep.sigma = 6.0, ep.aspect = 2.5, ep.orientation = 0.4;
    const kernels::Kernel ell(ep);
    auto exact = [](const kernels::Kernel& k, double tx, double ty) {
        return k.autocorrelation(0.0, 0.0) - k.autocorrelation(tx, ty);
    };
    for (const auto& [k, lag, slack] :
         {std::tuple{&iso, 2.0, 1e-6}, {&iso, 6.0, 1e-6}, {&ell, 2.5, 1e-4}, {&ell, 6.0, 1e-4}}) {
        const double want = exact(*k, lag, 0.5 * lag);
        const double got = scenes::detail::sampled_semivariogram(*k, false, lag, 0.5 * lag);
        INFO("lag " << lag << ": " << got << " vs " << want);
        CHECK(std::abs(got - want) < 1e-3 * want + slack * k->autocorrelation(0.0, 0.0));
    }
    // Averaged over rotations: against the mean over 72 exact rotations of the lag.
    double avg = 0;
    for (int m = 0; m < 72; ++m) {
        const double a = kPi * (m + 0.5) / 72;
        avg += exact(ell, 3.0 * std::cos(a), 3.0 * std::sin(a)) / 72;
    }
    CHECK(std::abs(scenes::detail::sampled_semivariogram(ell, true, 3.0, 0.0) - avg) <
          1e-3 * avg + 1e-4 * ell.autocorrelation(0.0, 0.0));
}

TEST_CASE("layer flow: divergence-free, curl as reported, RMS speed as asked",
          "[scenes][compose][flow][slow]") {
    const Stream s(16.0);
    auto flow = sim::make_stream_flow(s.psi, 25.0);
    const numeric::Box region{0.0, 0.0, 2048.0, 2048.0};
    flow->prepare(region);
    // Central differences at 1e-3 units (the field varies over ~R/4 = 4 units): truncation
    // ~1e-7 and rounding ~1e-12 / 1e-3 of the velocity scale, against derivatives of order
    // speed / R.
    // The interpolant's second derivatives jump across the lattice lines (spacing R / 8 = 2), so
    // the points keep 0.2 units from them.
    std::mt19937 rng(3);
    std::uniform_int_distribution<int> node(50, 970);
    std::uniform_real_distribution<double> frac(0.1, 0.9);
    const double d = 1e-3, h = 2.0;
    double div2 = 0, grad2 = 0, curl_err2 = 0, curl2 = 0;
    for (int i = 0; i < 2000; ++i) {
        const double x = h * (node(rng) + frac(rng)), y = h * (node(rng) + frac(rng));
        const Velocity px = velocity(*flow, x + d, y), mx = velocity(*flow, x - d, y);
        const Velocity py = velocity(*flow, x, y + d), my = velocity(*flow, x, y - d);
        const double dvx_dx = (px.vx - mx.vx) / (2 * d), dvy_dy = (py.vy - my.vy) / (2 * d);
        const double dvy_dx = (px.vy - mx.vy) / (2 * d), dvx_dy = (py.vx - my.vx) / (2 * d);
        const Velocity c = velocity(*flow, x, y);
        CHECK(c.div == 0.0);
        div2 += (dvx_dx + dvy_dy) * (dvx_dx + dvy_dy);
        grad2 += dvx_dx * dvx_dx + dvy_dy * dvy_dy + dvy_dx * dvy_dx + dvx_dy * dvx_dy;
        curl_err2 += (dvy_dx - dvx_dy - c.curl) * (dvy_dx - dvx_dy - c.curl);
        curl2 += c.curl * c.curl;
    }
    WARN("layer flow: rms divergence / rms velocity gradient = " << std::sqrt(div2 / grad2)
                                                                 << ", rms curl error / rms curl = "
                                                                 << std::sqrt(curl_err2 / curl2));
    CHECK(std::sqrt(div2 / grad2) < 1e-5);
    CHECK(std::sqrt(curl_err2 / curl2) < 1e-5);

    // RMS speed on a grid over the region (1.1M points) against `speed`: the
    // normalisation is the exact E|grad psi_I|^2 of the interpolant. The sampling error comes
    // from the run itself: the region's 16 blocks of 512^2 are nearly independent (the velocity
    // correlates over 2R = 32 units), so the scatter of their means of |v|^2 gives the sd of the
    // overall mean.
    auto rms_speed = [&](const sim::Flow& f, double& rel_sd) {
        std::vector<double> blocks(16, 0.0);
        for (int by = 0; by < 4; ++by)
            for (int bx = 0; bx < 4; ++bx) {
                double sum = 0;
                int n = 0;
                // A step incommensurate with the lattice's (2 units), so the points fall
                // evenly over the lattice cells.
                for (double y = by * 512.0 + 0.3; y < (by + 1) * 512.0; y += 1.93)
                    for (double x = bx * 512.0 + 0.7; x < (bx + 1) * 512.0; x += 1.93) {
                        const Velocity v = velocity(f, x, y);
                        sum += v.vx * v.vx + v.vy * v.vy, ++n;
                    }
                blocks[by * 4 + bx] = sum / n;
            }
        double m = 0, v = 0;
        for (double b : blocks) m += b / 16.0;
        for (double b : blocks) v += (b - m) * (b - m) / 15.0;
        rel_sd = 0.5 * std::sqrt(v / 16.0) / m;  // of the RMS: half that of the mean square
        return std::sqrt(m);
    };
    double rel_sd = 0;
    const double rms = rms_speed(*flow, rel_sd);
    WARN("layer flow: RMS speed " << rms << " for speed 25 (relative sd " << rel_sd << ")");
    CHECK(std::abs(rms / 25.0 - 1.0) < 4.0 * rel_sd);
    // A random orientation and an anisotropic kernel normalise as well.
    Stream e(16.0, "orientation = \"random\"");
    e.layer.kernel.aspect = 2.0;
    e.kernel = kernels::Kernel(e.layer.kernel);
    e.layer.process.intensity = e.layer.density.value(0.0) / e.kernel.support_area();
    e.psi.process = e.layer.process;
    auto eflow = sim::make_stream_flow(e.psi, 25.0);
    eflow->prepare(region);
    double e_sd = 0;
    const double erms = rms_speed(*eflow, e_sd);
    WARN("layer flow, aspect 2, random orientation: RMS speed " << erms << " (relative sd " << e_sd << ")");
    CHECK(std::abs(erms / 25.0 - 1.0) < 4.0 * e_sd);
}

TEST_CASE("layer flow: particles stay on the stream function's level lines",
          "[scenes][compose][flow][slow]") {
    // The flow is the curl of psi_I, psi's Catmull-Rom interpolant on the lattice of spacing
    // R / 8 (rebuilt here from the exact psi at the nodes), so psi_I is constant along a path up
    // to the integrator's error: RK4 with steps of 1/64 s at 25 units/s (0.4 units against
    // ~R / pi = 5 for the field) leaves ~(0.08)^5 per step. psi_I itself is within the
    // interpolation error of psi, about 1 % of its sd for the cosine kernel (C1 at its rim). The
    // same paths along the gradient (v rotated by 90 degrees) climb across the level lines.
    const Stream s(16.0);
    auto flow = sim::make_stream_flow(s.psi, 25.0);
    flow->prepare({-500.0, -500.0, 1500.0, 1500.0});
    const double sd = std::sqrt(scenes::layer_theory(s.layer).variance);
    const double h = s.layer.process.cell_size / 8.0;
    auto interpolated = [&](double x, double y) {
        const double fx = x / h, fy = y / h;
        const int64_t i = int64_t(std::floor(fx)), j = int64_t(std::floor(fy));
        double wx[4], wy[4], d[4], dd[4];
        numeric::catmull_rom(fx - double(i), wx, d, dd);
        numeric::catmull_rom(fy - double(j), wy, d, dd);
        double v = 0;
        for (int b = 0; b < 4; ++b)
            for (int a = 0; a < 4; ++a)
                v += wx[a] * wy[b] * s.exact(double(i - 1 + a) * h, double(j - 1 + b) * h);
        return v;
    };
    auto integrate = [&](double x, double y, bool across) {
        const double dt = 1.0 / 512.0;
        auto v = [&](double px, double py) {
            const Velocity w = velocity(*flow, px, py);
            return across ? std::pair{-w.vy, w.vx} : std::pair{w.vx, w.vy};
        };
        for (int step = 0; step < 1024; ++step) {  // 2 s, about 50 units
            const auto [k1x, k1y] = v(x, y);
            const auto [k2x, k2y] = v(x + 0.5 * dt * k1x, y + 0.5 * dt * k1y);
            const auto [k3x, k3y] = v(x + 0.5 * dt * k2x, y + 0.5 * dt * k2y);
            const auto [k4x, k4y] = v(x + dt * k3x, y + dt * k3y);
            x += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
            y += dt / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
        }
        return std::pair{x, y};
    };
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(300.0, 700.0);
    double along = 0, across = 0, interpolation = 0;
    for (int i = 0; i < 100; ++i) {
        const double x = u(rng), y = u(rng), p0 = interpolated(x, y);
        const auto [ax, ay] = integrate(x, y, false);
        const auto [cx, cy] = integrate(x, y, true);
        along = std::max(along, std::abs(interpolated(ax, ay) - p0) / sd);
        across = std::max(across, std::abs(interpolated(cx, cy) - p0) / sd);
        interpolation = std::max(interpolation, std::abs(interpolated(x, y) - s.exact(x, y)) / sd);
    }
    WARN("layer flow: largest change of psi_I along 100 paths of 2 s: "
         << along << " sd (across: " << across << " sd); largest |psi_I - psi| " << interpolation << " sd");
    CHECK(along < 1e-4);
    CHECK(across > 0.5);
    CHECK(interpolation < 0.03);
}

TEST_CASE("layer flow: in a scene the Jacobian stays 1 and the frames keep their variance",
          "[scenes][compose][flow][slow]") {
    // div v = 0 exactly, so ln J stays 0 and sqrt(J) compensation changes nothing: the frames
    // with and without it have the same bits. A source flow (divergent) is the control.
    auto scene = [](const std::string& flow, bool jacobian) {
        return std::string(R"(
[output]
size = [128, 128]
frames = 60
[[layer]]
name = "psi"
visible = false
seed = 8
[layer.kernel]
radius = 48.0
[[layer]]
seed = 9
lifetime = 1.0
jacobian = )") + (jacobian ? "true" : "false") + "\n[layer.kernel]\nradius = 8.0\n" + flow;
    };
    const std::string layer_flow = "[[layer.flow]]\ntype = \"layer\"\nsource = \"psi\"\nspeed = 40.0\n";
    const std::string source_flow =
        "[[layer.flow]]\ntype = \"source\"\ncenter = [64.0, 64.0]\nrate = 0.5\nradius = 60.0\n";
    scenes::Renderer with(scenes::load_scene_string(scene(layer_flow, true), "j.toml"));
    scenes::Renderer without(scenes::load_scene_string(scene(layer_flow, false), "j.toml"));
    scenes::Renderer src_with(scenes::load_scene_string(scene(source_flow, true), "j.toml"));
    scenes::Renderer src_without(scenes::load_scene_string(scene(source_flow, false), "j.toml"));
    Frame a, b;
    size_t same = 0, src_same = 0;
    std::vector<double> variances;
    for (int64_t f = 0; f < 60; f += 6) {
        with.render(f, a);
        without.render(f, b);
        same += same_bits(a, b);
        double m = 0, v = 0;
        for (float x : a.data) m += x;
        m /= double(a.data.size());
        for (float x : a.data) v += (x - m) * (x - m);
        variances.push_back(v / double(a.data.size()));
        src_with.render(f, a);
        src_without.render(f, b);
        src_same += same_bits(a, b);
    }
    CHECK(same == 10);
    CHECK(src_same < 10);
    // Frame variance against Campbell's: a 128^2 frame holds N / A ~ 16384 / 29 independent
    // areas (A for the cosine kernel of radius 8), so the relative sd of a frame's variance is
    // about sqrt(2 A / N) ~ 0.06 (plus the fourth cumulant, 3 / (lambda A) ~ 0.2 of that):
    // every frame within 4 sd.
    const scenes::Scene sc = scenes::load_scene_string(scene(layer_flow, true), "j.toml");
    const double theory = scenes::layer_theory(sc.layers[1]).variance;
    const kernels::Kernel k(sc.layers[1].kernel);
    const double A = k.integral() * k.integral() / k.integral_sq();
    const double rel = std::sqrt((2.0 * A + 3.0 / sc.layers[1].process.intensity) / (128.0 * 128.0));
    for (double v : variances) CHECK(std::abs(v / theory - 1.0) < 4.0 * rel);
}

// ---------------------------------------------------------------------------------------------
// Orientation from a layer

namespace {

/// Hidden broad "hills" (index 0), still or animated; streaks (index 1) oriented by them.
std::string oriented_scene(const std::string& orientation, bool show_hills, bool animated) {
    return std::string("[output]\nsize = [320, 320]\nframes = 8\n[[layer]]\nname = \"hills\"\nseed = 31\n") +
           (show_hills ? "" : "visible = false\n") + (animated ? "lifetime = 1.5\n" : "") +
           "[layer.kernel]\nradius = 96.0\n[[layer]]\nseed = 21\ndensity = 16.0\n" +
           (show_hills ? "visible = false\n" : "") + "orientation = " + orientation +
           "\n[layer.kernel]\ntype = \"gaussian\"\nradius = 24.0\nsigma = 8.0\naspect = 4.0\n";
}

struct Follow {
    double median = 90, p90 = 90;
    size_t windows = 0;
};

/// Median error between the streaks' measured orientation (windows of 32 px) and the hills'
/// gradient direction (+ offset), over the windows where that direction varies little (the
/// doubled-angle mean of the per-pixel directions has length >= 0.9).
Follow follow(const Frame& streaks, const Frame& hills, double offset) {
    std::vector<double> err;
    for (const auto& e : test::structure_tensor(streaks, 32)) {
        double c = 0, s = 0;
        int n = 0;
        for (int y = int(e.cy) - 16; y < int(e.cy) + 16; ++y)
            for (int x = int(e.cx) - 16; x < int(e.cx) + 16; ++x) {
                const double gx = hills.at(x + 1, y) - hills.at(x - 1, y);
                const double gy = hills.at(x, y + 1) - hills.at(x, y - 1);
                const double a = 2.0 * std::atan2(gy, gx);
                c += std::cos(a), s += std::sin(a), ++n;
            }
        if (std::hypot(c, s) / n < 0.9) continue;
        err.push_back(test::orientation_error_deg(e.angle, 0.5 * std::atan2(s, c) + offset));
    }
    Follow f;
    f.windows = err.size();
    if (err.empty()) return f;
    std::sort(err.begin(), err.end());
    f.median = err[err.size() / 2];
    f.p90 = err[err.size() * 9 / 10];
    return f;
}

}  // namespace

TEST_CASE("layer orientation: the streaks follow the source's gradient or level lines",
          "[scenes][compose][orientation]") {
    // As for the orientation fields (tests/sim/test_orientation.cpp): 32 px windows hold about
    // 9 kernel areas, the structure tensor's angle scatters by a few degrees per window, so the
    // median error is held to 5 degrees; the wrong direction (90 degrees off) and no
    // orientation at all must fail it.
    for (bool animated : {false, true}) {
        const int64_t frame = animated ? 5 : 0;
        const Frame hills =
            render_text(oriented_scene("{ type = \"layer\", source = \"hills\" }", true, animated), frame);
        const Frame along_gradient =
            render_text(oriented_scene("{ type = \"layer\", source = \"hills\" }", false, animated), frame);
        const Frame along_level = render_text(
            oriented_scene("{ type = \"layer\", source = \"hills\", along = \"level\" }", false, animated), frame);
        const Frame fixed = render_text(oriented_scene("\"fixed\"", false, animated), frame);
        const Follow g = follow(along_gradient, hills, 0.0);
        const Follow g_wrong = follow(along_gradient, hills, 0.5 * kPi);
        const Follow l = follow(along_level, hills, 0.5 * kPi);
        const Follow l_wrong = follow(along_level, hills, 0.0);
        const Follow none = follow(fixed, hills, 0.0);
        WARN((animated ? "animated" : "still")
             << " source: gradient median " << g.median << " deg (90 % " << g.p90 << ") over "
             << g.windows << " windows, 90 deg off " << g_wrong.median << "; level lines "
             << l.median << " (" << l_wrong.median << " the other way); fixed " << none.median);
        CHECK(g.windows >= 20);
        CHECK(g.median <= 5.0);
        CHECK(l.median <= 5.0);
        CHECK(g_wrong.median > 5.0);
        CHECK(l_wrong.median > 5.0);
        CHECK(none.median > 5.0);
    }
}
