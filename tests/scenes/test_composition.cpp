// SPDX-License-Identifier: Apache-2.0
// Composition of layers (docs/scenes.md "Composition"): blend modes against their per-pixel
// definitions and closed forms, the plain sum unchanged bit for bit, domain warps against
// exact lookups of the warped layer, determinism with every composition feature at once, and
// the loader's handling of names, sources and warnings.
//
// Notation: sigma^2 = a layer's Campbell variance, N = pixels, A = (int h)^2 / int h^2 the
// correlation area of a layer with a non-negative kernel h (sum over pixel lags of its
// correlation rho(tau) >= 0; the pixel is 1 texture unit here, far below the kernels' radii).

#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/detail/compose.h"
#include "scenes/scenes.h"
#include "tests/scene_render.h"
#include "numeric/errors.h"
#include "numeric/gaussian.h"

namespace {

using namespace impulse;
using Catch::Matchers::Contains;
using render::Frame;
constexpr double kPi = std::numbers::pi;

Frame render_text(const std::string& text, int64_t frame = 0) {
    return test::render_scene_text(text, frame, "compose.toml");
}

using test::same_bits;

struct Moments {
    double mean = 0, variance = 0;
};
Moments moments(const Frame& f) {
    double s = 0, s2 = 0;
    for (float v : f.data) s += v;
    const double m = s / double(f.data.size());
    for (float v : f.data) s2 += (v - m) * (v - m);
    return {m, s2 / double(f.data.size())};
}

/// Correlation area (int h)^2 / int h^2 of a layer whose kernel is non-negative.
double correlation_area(const scenes::LayerConfig& l) {
    const kernels::Kernel k(l.kernel);
    return k.integral() * k.integral() / k.integral_sq();
}

/// Excess kurtosis of a still layer: lambda E[a^4] int h^4 / sigma^4 (Campbell, fourth cumulant).
double excess_kurtosis(const scenes::LayerConfig& l) {
    const kernels::Kernel k(l.kernel);
    const double lambda = l.process.intensity;
    const double ea2 = sim::amplitude_second_moment(l.process.amplitude);
    const double ea4 = sim::amplitude_fourth_moment(l.process.amplitude);
    return ea4 * k.integral_4() / (lambda * ea2 * ea2 * k.integral_sq() * k.integral_sq());
}

using impulse::numeric::normal_cdf;
using impulse::numeric::normal_pdf;

/// Two still layers X (index 0) and Y (index 1); `y_keys` are added to Y, `x_keys` to X.
std::string pair_scene(int size, const std::string& x_keys, const std::string& y_keys,
                       double rx = 6.0, double ry = 9.0) {
    std::ostringstream s;
    s << "[output]\nsize = [" << size << ", " << size << "]\n"
      << "[[layer]]\nseed = 3\n" << x_keys << "\n[layer.kernel]\nradius = " << rx << "\n"
      << "[[layer]]\nseed = 4\n" << y_keys << "\n[layer.kernel]\nradius = " << ry << "\n";
    return s.str();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The plain sum

TEST_CASE("composition: a sum of layers has the bits of the summing renderer", "[scenes][compose]") {
    // The summing algorithm the renderer had before composition (renderer.cpp at 93ef735),
    // rebuilt from the library's parts: each unshaped layer's impulses accumulated into the one
    // frame in layer order, a shaped layer through its own buffer and g, the unshaped layers'
    // means added last.
    const std::string text = R"(
[output]
size = [160, 112]
frames = 4
[[layer]]
seed = 3
mean = 0.5
lifetime = 1.0
[layer.kernel]
radius = 12.0
[[layer.flow]]
type = "curl"
scale = 60.0
speed = 20.0
[[layer]]
seed = 4
marginal = { type = "exponential", rate = 1.0 }
[layer.kernel]
type = "gaussian"
radius = 10.0
sigma = 3.0
[[layer]]
seed = 5
gain = 0.5
mean = 2.0
orientation = { type = "circular", center = [80.0, 60.0] }
[layer.kernel]
radius = 16.0
aspect = 3.0
)";
    const scenes::Scene scene = scenes::load_scene_string(text, "sum.toml");
    REQUIRE(scenes::is_sum_of_layers(scene));
    scenes::Renderer r(scene);
    Frame out;
    r.render(2, out);
    const auto& o = scene.output;
    const render::View view = scene.camera.view(o.width, o.height, 2.0 / o.fps);
    Frame ref, scratch;
    ref.resize(o.width, o.height);
    double mean = 0.0;
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const auto& l = scene.layers[i];
        const kernels::Kernel k(l.kernel);
        if (l.marginal) {
            scratch.resize(o.width, o.height);
            render::accumulate(k, r.impulses(i), view, scratch);
            l.marginal->apply(scratch.data, l.mean.value(0.0));
            for (size_t p = 0; p < ref.data.size(); ++p) ref.data[p] += scratch.data[p];
            continue;
        }
        render::accumulate(k, r.impulses(i), view, ref);
        mean += l.mean.value(0.0);
    }
    for (auto& v : ref.data) v = static_cast<float>(v + mean);
    CHECK(same_bits(out, ref));

    // The defaults written out change nothing.
    std::string explicit_text = text;
    for (size_t at = 0; (at = explicit_text.find("[[layer]]\n", at)) != std::string::npos; at += 10)
        explicit_text.insert(at + 10, "blend = \"add\"\nopacity = 1.0\nvisible = true\n");
    CHECK(same_bits(render_text(explicit_text, 2), out));
    // The theory of a sum is the sum of the layers' theories.
    const scenes::Theory t = scenes::scene_theory(scene);
    double m = 0, v = 0;
    for (const auto& l : scene.layers) m += scenes::layer_theory(l).mean, v += scenes::layer_theory(l).variance;
    CHECK(t.mean == m);
    CHECK(t.variance == v);
}

// ---------------------------------------------------------------------------------------------
// Blend modes, pixel by pixel

TEST_CASE("composition: each blend mode is its per-pixel formula", "[scenes][compose]") {
    // X alone (Y hidden) and Y alone (X hidden, Y added) are the layers' own fields with the
    // same impulses (a layer's index is part of its generator key, so both stay in place).
    const std::string y_mean = "mean = 0.75\n";
    const Frame fx = render_text(pair_scene(96, "mean = 0.25", y_mean + "visible = false"));
    const Frame fy = render_text(pair_scene(96, "visible = false", y_mean));
    auto check = [&](const std::string& x_keys, const std::string& y_keys, auto&& formula) {
        const Frame f = render_text(pair_scene(96, x_keys, y_mean + y_keys));
        size_t bad = 0;
        for (size_t p = 0; p < f.data.size(); ++p)
            if (f.data[p] != formula(fx.data[p], fy.data[p])) ++bad;
        return bad;
    };
    CHECK(check("mean = 0.25", "blend = \"multiply\"", [](float r, float l) { return r * l; }) == 0);
    CHECK(check("mean = 0.25", "blend = \"max\"", [](float r, float l) { return std::max(r, l); }) == 0);
    CHECK(check("mean = 0.25", "blend = \"min\"", [](float r, float l) { return std::min(r, l); }) == 0);
    // Over at alpha 1 is the layer, at alpha 0 what lies under it, exactly.
    CHECK(check("mean = 0.25", "blend = \"over\"", [](float, float l) { return l; }) == 0);
    CHECK(check("mean = 0.25", "blend = \"over\"\nopacity = 0.0", [](float r, float) { return r; }) == 0);
    // With weights (computed in double, rounded once).
    const double o = 0.3;
    CHECK(check("mean = 0.25", "blend = \"multiply\"\nopacity = 0.3", [&](float r, float l) {
              return static_cast<float>(r * ((1.0 - o) + o * l));
          }) == 0);
    CHECK(check("mean = 0.25", "blend = \"max\"\nopacity = 0.3", [&](float r, float l) {
              return static_cast<float>(r + o * (std::max(r, l) - r));
          }) == 0);
    CHECK(check("mean = 0.25", "blend = \"over\"\nopacity = 0.3", [&](float r, float l) {
              return static_cast<float>(double(r) * (1.0 - o) + double(l) * o);
          }) == 0);
    // Add with a weight: X's mean stays pending until the end, so X has none here.
    const Frame fx0 = render_text(pair_scene(96, "", y_mean + "visible = false"));
    const Frame fa = render_text(pair_scene(96, "", y_mean + "opacity = 0.3"));
    size_t bad = 0;
    for (size_t p = 0; p < fa.data.size(); ++p)
        if (fa.data[p] != static_cast<float>(fx0.data[p] + o * fy.data[p])) ++bad;
    CHECK(bad == 0);
    // Over with an alpha range: under where Y <= lo, Y where Y >= hi, the ramp between.
    size_t below = 0, above = 0, between = 0;
    const Frame fo = render_text(pair_scene(96, "mean = 0.25", y_mean + "blend = \"over\"\nalpha = [0.0, 1.5]"));
    for (size_t p = 0; p < fo.data.size(); ++p) {
        const float r = fx.data[p], l = fy.data[p];
        const double a = scenes::detail::alpha_ramp(0.0, 1.5, l);
        CHECK(fo.data[p] == static_cast<float>(double(r) * (1.0 - a) + double(l) * a));
        if (l <= 0.0f) below += fo.data[p] == r;
        else if (l >= 1.5f) above += fo.data[p] == l;
        else ++between;
        if (l <= 0.0f) REQUIRE(fo.data[p] == r);
        if (l >= 1.5f) REQUIRE(fo.data[p] == l);
    }
    CHECK(below > 1000);
    CHECK(above > 1000);
    CHECK(between > 1000);
    // The ramp: smoothstep, falling when lo > hi.
    CHECK(scenes::detail::alpha_ramp(0.0, 2.0, 1.0) == 0.5);
    CHECK(scenes::detail::alpha_ramp(0.0, 2.0, 0.5) == Approx(0.15625));
    CHECK(scenes::detail::alpha_ramp(2.0, 0.0, 0.5) == Approx(1.0 - 0.15625));
}

// ---------------------------------------------------------------------------------------------
// Blend modes, statistics

TEST_CASE("composition: multiply of independent zero-mean layers has mean 0 and variance "
          "sigma_x^2 sigma_y^2", "[scenes][compose][stats]") {
    const int size = 1024;
    const std::string text = pair_scene(size, "", "blend = \"multiply\"", 4.0, 6.0);
    const scenes::Scene scene = scenes::load_scene_string(text, "multiply.toml");
    const auto& X = scene.layers[0];
    const auto& Y = scene.layers[1];
    const double vx = scenes::layer_theory(X).variance, vy = scenes::layer_theory(Y).variance;
    const Moments m = moments(render_text(text));
    const double N = double(size) * size;
    const double ax = correlation_area(X), ay = correlation_area(Y);
    // Mean: Var(mean) = (1/N) sum_tau C_x C_y <= sigma_x^2 sigma_y^2 min(A_x, A_y) / N.
    const double sd_mean = std::sqrt(vx * vy * std::min(ax, ay) / N);
    // Variance: Cov((XY)^2_0, (XY)^2_tau) = sx^4 g_y + sy^4 g_x + g_x g_y with
    // g = E[X_0^2 X_tau^2] - sigma^4 = 2 C^2 + lambda E[a^4] int h^2(x) h^2(x + tau) dx >= 0, whose
    // sum over tau is S = 2 sum C^2 + lambda E[a^4] (int h^2)^2 <= sigma^4 (2 A + E[a^4]/E[a^2]^2
    // / lambda); g_x <= g_x(0) = sigma_x^4 (2 + kurtosis_x). So relative
    // Var(s^2) <= (S_x' + (3 + kurtosis_x) S_y') / N, S' = S / sigma^4.
    const double sx = 2 * ax + 3.0 / X.process.intensity, sy = 2 * ay + 3.0 / Y.process.intensity;
    const double sd_var = vx * vy * std::sqrt((sx + (3.0 + excess_kurtosis(X)) * sy) / N);
    WARN("multiply: mean " << m.mean << " (sd " << sd_mean << "), variance " << m.variance
                           << " vs " << vx * vy << " (sd " << sd_var << ")");
    CHECK(std::abs(m.mean) < 4.0 * sd_mean);
    CHECK(std::abs(m.variance - vx * vy) < 4.0 * sd_var);
    const scenes::Theory t = scenes::scene_theory(scene);
    CHECK(t.mean == 0.0);
    CHECK(t.variance == Approx(vx * vy).epsilon(1e-12));
    // Blending by addition instead fails the same test (variance sigma_x^2 + sigma_y^2).
    const Moments a = moments(render_text(pair_scene(size, "", "", 4.0, 6.0)));
    CHECK(std::abs(a.variance - vx * vy) > 4.0 * sd_var);
}

TEST_CASE("composition: max with a constant layer is max(X, c), with E[max(X, c)] = c Phi(c/s) + "
          "s phi(c/s)", "[scenes][compose][stats]") {
    const int size = 1024;
    const double c = 1.0;
    // The constant: gain 0 leaves only the layer's mean.
    const std::string text = pair_scene(size, "density = 32.0", "gain = 0.0\nmean = 1.0\nblend = \"max\"", 4.0, 4.0);
    const scenes::Scene scene = scenes::load_scene_string(text, "max.toml");
    const Frame f = render_text(text);
    const Frame fx = render_text(pair_scene(size, "density = 32.0", "gain = 0.0\nmean = 1.0\nvisible = false", 4.0, 4.0));
    size_t bad = 0;
    for (size_t p = 0; p < f.data.size(); ++p)
        if (f.data[p] != std::max(fx.data[p], 1.0f)) ++bad;
    CHECK(bad == 0);

    const auto& X = scene.layers[0];
    const double s = std::sqrt(scenes::layer_theory(X).variance), z = c / s;
    const double mean = c * normal_cdf(z) + s * normal_pdf(z);
    const double second = s * s * (1.0 - normal_cdf(z) + z * normal_pdf(z)) + c * c * normal_cdf(z);
    const scenes::Theory t = scenes::scene_theory(scene);
    CHECK(t.mean == Approx(mean).epsilon(1e-12));
    CHECK(t.variance == Approx(second - mean * mean).epsilon(1e-12));
    // Sampling: max(X, c) is a function of X alone, so its correlation is at most X's and
    // Var(mean) <= Var(max) A / N. The closed form is the Gaussian one; X's marginal differs by
    // its excess kurtosis k, which moves E[(X - c)^+] by s k / 24 (z^2 - 1) phi(z) (Edgeworth,
    // the symmetric amplitudes have no skewness); twice that is allowed for higher orders.
    const double N = double(size) * size;
    const double sd_mean = std::sqrt((second - mean * mean) * correlation_area(X) / N);
    const double edgeworth = s * excess_kurtosis(X) / 24.0 * std::abs(z * z - 1.0) * normal_pdf(z);
    const Moments m = moments(f);
    WARN("max: mean " << m.mean << " vs " << mean << " (sd " << sd_mean << ", Edgeworth "
                      << edgeworth << ")");
    CHECK(std::abs(m.mean - mean) < 4.0 * sd_mean + 2.0 * edgeworth);
    // Without the max (X alone) the mean is 0: far outside.
    CHECK(std::abs(moments(fx).mean - mean) > 4.0 * sd_mean + 2.0 * edgeworth);
}

TEST_CASE("composition: the theory of over with an alpha range matches the measured frame",
          "[scenes][compose][stats][slow]") {
    // R = X (1 - A) + Y A, A = 0.8 smoothstep(0, 1.5, Y): the closed form integrates over Y's
    // marginal taken as Gaussian. Sampling: R is a function of the independent X and Y, so its
    // correlation is at most max(rho_x, rho_y) (Hermite expansion) and
    // Var(mean) <= Var(R) (A_x + A_y) / N. Approximation: averaged over X (exact, through its
    // moments) a moment of R is E[f(Y)]; Y's Edgeworth density phi(z) (1 + k He4(z) / 24) (no
    // skewness: symmetric amplitudes) moves it by k / 24 E[f He4] <= k rms(f) / sqrt(24)
    // (Cauchy-Schwarz, E[He4^2] = 24), rms(f) <= sqrt(E[R^2]) for the mean and sqrt(E[R^4])
    // for the second moment (measured); twice that is allowed for the higher orders.
    const int size = 1024;
    // Y dense with +-1 amplitudes (E[a^4] / E[a^2]^2 = 1) keeps its excess kurtosis near 0.01;
    // X enters only through its mean and variance.
    const std::string text = pair_scene(
        size, "", "density = 256.0\namplitude = \"sign\"\nblend = \"over\"\nopacity = 0.8\nalpha = [0.0, 1.5]");
    const scenes::Scene scene = scenes::load_scene_string(text, "over.toml");
    const double k = excess_kurtosis(scene.layers[1]);
    CHECK(k < 0.015);
    const scenes::Theory t = scenes::scene_theory(scene);
    const Frame f = render_text(text);
    const Moments m = moments(f);
    double m4 = 0;
    for (float v : f.data) m4 += double(v) * v * v * v;
    m4 /= double(f.data.size());
    const double N = double(size) * size;
    const double A = correlation_area(scene.layers[0]) + correlation_area(scene.layers[1]);
    const double sd_mean = std::sqrt(t.variance * A / N);
    const double second = t.variance + t.mean * t.mean;
    const double approx_mean = 2.0 * k * std::sqrt(second) / std::sqrt(24.0);
    const double approx_second = 2.0 * k * std::sqrt(m4) / std::sqrt(24.0);
    WARN("over: mean " << m.mean << " vs " << t.mean << " (sd " << sd_mean << ", approximation "
                       << approx_mean << "), variance " << m.variance << " vs " << t.variance
                       << " (approximation " << approx_second + 2 * std::abs(t.mean) * approx_mean << ")");
    CHECK(std::abs(m.mean - t.mean) < 4.0 * sd_mean + approx_mean);
    // The variance estimator's sd is about Var sqrt(2 A / N) for a near-Gaussian R; R is a
    // mixture, so its kurtosis (measured) replaces the 2: sqrt((m4' - 1) A / N) relative, m4'
    // the standardised fourth moment about the mean (bounded here by the raw one).
    const double kurt = m4 / (m.variance * m.variance);
    const double sd_var = t.variance * std::sqrt(kurt * A / N);
    CHECK(std::abs(m.variance - t.variance) <
          4.0 * sd_var + approx_second + 2.0 * std::abs(t.mean) * approx_mean);
    // Ignoring the alpha ramp (constant alpha 0.8) predicts a different mean.
    scenes::Scene flat = scene;
    flat.layers[1].compose.alpha.reset();
    CHECK(std::abs(scenes::scene_theory(flat).mean - m.mean) > 4.0 * sd_mean + approx_mean);
}

// ---------------------------------------------------------------------------------------------
// Domain warp

namespace {

/// Sources wx, wy (broad; hidden unless shown), the warped layer (index 2; `warp` is its warp
/// table).
std::string warp_scene(const std::string& warp, int frames = 1, bool show_wx = false,
                       bool show_wy = false, bool show_target = true) {
    auto visible = [](bool v) { return v ? std::string() : std::string("visible = false\n"); };
    return "[output]\nsize = [160, 128]\nframes = " + std::to_string(frames) +
           "\n[[layer]]\nname = \"wx\"\n" + visible(show_wx) +
           "seed = 11\nlifetime = 2.0\n[layer.kernel]\nradius = 40.0\n"
           "[[layer]]\nname = \"wy\"\n" + visible(show_wy) +
           "seed = 12\n[layer.kernel]\nradius = 40.0\n"
           "[[layer]]\nseed = 3\nmean = 0.5\n" + visible(show_target) + warp +
           "\n[layer.kernel]\nradius = 12.0\n";
}

}  // namespace

TEST_CASE("composition: a warp of amount 0 is no warp, bit for bit", "[scenes][compose][warp]") {
    const Frame plain = render_text(warp_scene(""));
    CHECK(same_bits(render_text(warp_scene("warp = { source = [\"wx\", \"wy\"], amount = 0.0 }")), plain));
    // Keyframed: 0 at t = 0, then growing.
    const std::string keyed = warp_scene(
        "warp = { source = [\"wx\", \"wy\"], amount = { keys = [[0.0, 0.0], [1.0, 8.0]] } }", 10);
    CHECK(same_bits(render_text(keyed, 0), plain));
    CHECK(!same_bits(render_text(keyed, 9), render_text(warp_scene("", 10), 9)));
}

TEST_CASE("composition: a warped layer is the layer looked up at x + amount z(x)",
          "[scenes][compose][warp]") {
    // The reference evaluates the warped layer exactly (in double, from its impulses) at each
    // pixel's displaced point, with z from the sources rendered alone. The renderer instead
    // resamples the layer rendered on a grown view with a Catmull-Rom bicubic: exact for
    // quadratics, its error for the cosine kernel of radius 12 px (curvature scale ~R/pi) at
    // 1 px spacing is of order (pi / 12)^4 / 8 ~ 6e-4 of the field; plus float rounding.
    const double amount = 9.0;
    const std::string text =
        warp_scene("warp = { source = [\"wx\", \"wy\"], amount = " + std::to_string(amount) + " }");
    const scenes::Scene scene = scenes::load_scene_string(text, "warp.toml");
    scenes::Renderer r(scene);
    Frame out;
    r.render(0, out);
    // The sources' own fields, same impulses: each shown alone, the warped layer hidden, and
    // evaluated directly as the warp reads them (docs/multirate.md §5: a layer a warp reads is
    // never on a lattice; shown alone it would be, 0.5 % of its sd off, x amount 9).
    const std::string direct = "[render]\ntolerance = 0.0\n";
    const Frame zx = render_text(direct + warp_scene("", 1, true, false, false));
    const Frame zy = render_text(direct + warp_scene("", 1, false, true, false));
    const scenes::Theory tx = scenes::layer_theory(scene.layers[0]), ty = scenes::layer_theory(scene.layers[1]);
    const auto& T = scene.layers[2];
    const kernels::Kernel k(T.kernel);
    const sim::Impulses& imp = r.impulses(2);
    const render::View view = scene.camera.view(160, 128, 0.0);
    auto exact = [&](double x, double y) {
        double v = T.mean.value(0.0);
        for (size_t i = 0; i < imp.size(); ++i)
            v += imp.weight[i] * k.evaluate(x - imp.x[i], y - imp.y[i], imp.theta[i]);
        return v;
    };
    const double sd = std::sqrt(scenes::layer_theory(T).variance);
    double worst = 0, worst_unwarped = 0, largest_shift = 0;
    std::mt19937 rng(5);
    for (int s = 0; s < 400; ++s) {
        const int i = int(rng() % 160), j = int(rng() % 128);
        const size_t p = size_t(j) * 160 + i;
        const double x = view.x0 + i + 0.5, y = view.y0 + j + 0.5;
        const double dx = amount * (zx.data[p] - tx.mean) / std::sqrt(tx.variance);
        const double dy = amount * (zy.data[p] - ty.mean) / std::sqrt(ty.variance);
        largest_shift = std::max(largest_shift, std::hypot(dx, dy));
        worst = std::max(worst, std::abs(out.data[p] - exact(x + dx, y + dy)) / sd);
        worst_unwarped = std::max(worst_unwarped, std::abs(out.data[p] - exact(x, y)) / sd);
    }
    WARN("warp: worst error " << worst << " sd over 400 pixels (displacements up to "
                              << largest_shift << " units); against the unwarped layer "
                              << worst_unwarped << " sd");
    CHECK(largest_shift > 2.0 * amount);
    CHECK(worst < 5e-3);
    CHECK(worst_unwarped > 0.5);  // the mechanism matters
}

TEST_CASE("composition: the warp's resampling is exact at whole-pixel shifts and bicubic "
          "between", "[scenes][compose][warp]") {
    // A layer rendered on a view grown by `margin` and resampled at a constant displacement is
    // the layer rendered on the shifted view: exactly for whole pixels (the Catmull-Rom weights
    // are 0, 1, 0, 0), within the bicubic's error (see above) for fractions.
    const scenes::Scene scene = scenes::load_scene_string(
        "[output]\nsize = [64, 48]\n[[layer]]\nseed = 2\n[layer.kernel]\nradius = 12.0\n", "s.toml");
    const kernels::Kernel k(scene.layers[0].kernel);
    const render::View view = scene.camera.view(64, 48, 0.0);
    const int margin = 6;
    render::View grown = view;
    grown.width += 2 * margin, grown.height += 2 * margin;
    grown.x0 -= margin, grown.y0 -= margin;
    sim::LayerSimulator simulator(scene.layers[0].process, nullptr, {}, k.radius());
    sim::Impulses imp;
    simulator.impulses_at(0, grown.box(), imp);
    Frame src;
    src.resize(grown.width, grown.height);
    render::accumulate(k, imp, grown, src);
    auto shifted = [&](double sx, double sy) {
        render::View v = view;
        v.x0 += sx, v.y0 += sy;
        Frame f;
        f.resize(64, 48);
        render::accumulate(k, imp, v, f);
        return f;
    };
    auto resampled = [&](double sx, double sy) {
        Frame f;
        f.resize(64, 48);
        std::vector<float> dx(64 * 48, float(sx)), dy(64 * 48, float(sy));
        scenes::detail::warp_resample(src, margin, dx, dy, f);
        return f;
    };
    // Whole pixels: the same numbers as the grown render's pixels (its pixel centres).
    const Frame whole = resampled(3.0, -2.0);
    size_t bad = 0;
    for (int j = 0; j < 48; ++j)
        for (int i = 0; i < 64; ++i)
            if (whole.at(i, j) != src.at(i + margin + 3, j + margin - 2)) ++bad;
    CHECK(bad == 0);
    const double sd = std::sqrt(scenes::layer_theory(scene.layers[0]).variance);
    double worst = 0, worst_none = 0;
    const Frame frac = resampled(2.25, -1.5), ref = shifted(2.25, -1.5), none = shifted(0.0, 0.0);
    for (size_t p = 0; p < frac.data.size(); ++p) {
        worst = std::max(worst, std::abs(double(frac.data[p]) - ref.data[p]) / sd);
        worst_none = std::max(worst_none, std::abs(double(none.data[p]) - ref.data[p]) / sd);
    }
    WARN("resampling at (2.25, -1.5) px: worst error " << worst << " sd (unshifted: " << worst_none << ")");
    CHECK(worst < 5e-3);
    CHECK(worst_none > 0.1);
}

// ---------------------------------------------------------------------------------------------
// Determinism

TEST_CASE("composition: sequential and random-access frames, any thread count, have the same "
          "bits", "[scenes][compose][determinism]") {
    // Every feature at once: animated warp sources, a still stream function, an orientation
    // from an animated layer, blends with keyframed opacity, a hidden layer.
    const std::string text = R"(
[output]
size = [96, 80]
frames = 12
[[layer]]
name = "psi"
visible = false
seed = 21
[layer.kernel]
radius = 40.0
[[layer]]
name = "wx"
visible = false
seed = 22
lifetime = 1.0
[layer.kernel]
radius = 30.0
[[layer.flow]]
type = "uniform"
velocity = [12.0, 0.0]
[[layer]]
name = "wy"
seed = 23
lifetime = 0.7
gain = 0.5
[layer.kernel]
radius = 24.0
[[layer]]
seed = 24
lifetime = 0.8
blend = "over"
alpha = [-0.5, 1.0]
opacity = { keys = [[0.0, 0.2], [0.3, 1.0]] }
orientation = { type = "layer", source = "wx", along = "level", jitter = 0.1 }
warp = { source = ["wx", "wy"], amount = 6.0 }
[layer.kernel]
type = "gaussian"
radius = 16.0
sigma = 5.0
aspect = 3.0
[[layer.flow]]
type = "layer"
source = "psi"
speed = 30.0
[[layer]]
seed = 25
blend = "multiply"
mean = 1.0
gain = 0.3
lifetime = 0.5
[layer.kernel]
radius = 10.0
)";
    const scenes::Scene scene = scenes::load_scene_string(text, "all.toml");
    std::vector<Frame> sequential(12);
    {
        scenes::Renderer r(scene);
        for (int64_t f = 0; f < 12; ++f) r.render(f, sequential[f]);
    }
    // Fresh renderers, backwards and jumping.
    for (int64_t f : {11, 4, 7, 0}) {
        scenes::Renderer r(scene);
        Frame out;
        r.render(f, out);
        CHECK(same_bits(out, sequential[f]));
    }
    {
        scenes::Renderer r(scene);
        Frame out;
        for (int64_t f : {5, 6, 2, 9, 10, 1}) {
            r.render(f, out);
            CHECK(same_bits(out, sequential[f]));
        }
    }
    // One thread, small tiles, the serial path.
    tbb::task_arena one(1);
    one.execute([&] {
        scenes::Renderer r(scene);
        Frame out;
        render::EvalOptions o;
        o.tile_size = 16;
        o.parallel = false;
        for (int64_t f : {3, 8}) {
            r.render(f, out, o);
            CHECK(same_bits(out, sequential[f]));
        }
    });
    // The frames change (the test sees motion, not a constant).
    CHECK(!same_bits(sequential[0], sequential[11]));
}

// ---------------------------------------------------------------------------------------------
// Scene keys

TEST_CASE("composition keys: names, indices, defaults and warnings", "[scenes][compose]") {
    const std::string base = R"(
[[layer]]
name = "a"
visible = false
[[layer]]
name = "b"
[[layer]]
blend = "over"
opacity = 0.5
orientation = { type = "layer", source = "a", along = "level" }
warp = { source = [0, "b"], amount = 3.0 }
[layer.kernel]
aspect = 2.0
)";
    const scenes::Scene s = scenes::load_scene_string(base, "k.toml");
    const auto& c = s.layers[2].compose;
    CHECK(c.blend == scenes::Blend::Over);
    CHECK(c.opacity.value(0.0) == 0.5);
    REQUIRE(c.orientation);
    CHECK(c.orientation->source == 0);
    CHECK(c.orientation->level_lines);
    CHECK(s.layers[2].process.orientation == sim::OrientationMode::Field);
    REQUIRE(c.warp);
    CHECK(c.warp->source == std::array<size_t, 2>{0, 1});
    CHECK(c.warp->amount.value(0.0) == 3.0);
    CHECK(!s.layers[0].compose.visible);
    CHECK(s.layers[1].compose.name == "b");
    CHECK(!scenes::is_sum_of_layers(s));
    CHECK(s.warnings.empty());

    auto error_of = [](const std::string& text) {
        try {
            scenes::load_scene_string(text, "k.toml");
        } catch (const SceneError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    // Unknown names list the names when none is close; say how to name one when none is named.
    CHECK_THAT(error_of("[[layer]]\nname = \"alpha\"\n[[layer]]\nname = \"beta\"\n[[layer]]\n"
                        "orientation = { type = \"layer\", source = \"zzz\" }\n"),
               Contains("no layer is named \"zzz\" (names: alpha, beta)"));
    CHECK_THAT(error_of("[[layer]]\n[[layer]]\norientation = { type = \"layer\", source = \"x\" }\n"),
               Contains("(no layer has a name: give the source layer name = \"...\")"));
    CHECK_THAT(error_of("[[layer]]\nname = \"\"\n"), Contains("layer[0].name = \"\": expected a non-empty name"));
    CHECK_THAT(error_of("[[layer]]\n[[layer]]\nwarp = { source = [0, 1.5], amount = 1.0 }\n"),
               Contains("layer[1].warp.source[1] = 1.5: expected a layer's name or index, found float"));
    CHECK_THAT(error_of("[[layer]]\nvisible = false\nlifetime = 1.0\n[[layer]]\nlifetime = 1.0\n"
                        "[[layer.flow]]\ntype = \"layer\"\nsource = 0\n"),
               Contains("layer[0] has lifetime = 1: a stream function must be a still layer"));
    CHECK_THAT(error_of("[[layer]]\nvisible = false\norientation = \"random\"\nwarp = { source = [1, 1], amount = 1.0 }\n"
                        "[[layer]]\n[[layer]]\nlifetime = 1.0\n[[layer.flow]]\ntype = \"layer\"\nsource = 0\n"),
               Contains("layer[0] is warped: a stream function must be an unwarped layer"));
    CHECK_THAT(error_of("[[layer]]\nvisible = false\norientation = { type = \"constant\", angle = 1.0 }\n"
                        "[[layer]]\nlifetime = 1.0\n[[layer.flow]]\ntype = \"layer\"\nsource = 0\n"),
               Contains("layer[0] has an orientation field: a stream function takes fixed or random"));
    CHECK_THAT(error_of("[[layer]]\nvisible = false\ngain = 0.0\n"
                        "[[layer]]\nlifetime = 1.0\n[[layer.flow]]\ntype = \"layer\"\nsource = 0\n"),
               Contains("layer[0] has gain = 0: a constant field has no level lines"));
    // A --set override is named like a file location.
    CHECK_THAT(
        [&] {
            try {
                scenes::load_scene_string(base, "k.toml", {"layer.2.blend=screen"});
            } catch (const SceneError& e) {
                return std::string(e.what());
            }
            return std::string("no error");
        }(),
        Contains("--set layer.2.blend=screen: layer[2].blend = \"screen\": expected one of add, multiply, max, min, over"));

    // Warnings: a hidden layer nothing reads; an alpha range on a blend that has none.
    const scenes::Scene w = scenes::load_scene_string(
        "[[layer]]\n[[layer]]\nvisible = false\n[[layer]]\nalpha = [0.0, 1.0]\n", "w.toml");
    REQUIRE(w.warnings.size() == 2);
    CHECK_THAT(w.warnings[0], Contains("layer[2].alpha: ignored for blend = \"add\""));
    CHECK_THAT(w.warnings[1], Contains("layer[1].visible: this hidden layer is no layer's source"));
    // A hidden layer only a flow reads is not rendered: the budget does not count it.
    const scenes::Scene f = scenes::load_scene_string(R"(
[[layer]]
visible = false
[layer.kernel]
radius = 4.0
[[layer]]
lifetime = 1.0
[[layer.flow]]
type = "layer"
source = 0
)", "f.toml");
    CHECK(f.warnings.empty());
    scenes::Scene g = f;
    g.layers[0].compose.visible = true;
    CHECK(scenes::Renderer(f).estimated_impulses() < 0.5 * scenes::Renderer(g).estimated_impulses());
}

namespace {
std::string curl_scene(double scale, double max_memory_mib) {
    std::ostringstream s;
    s << "[output]\nsize = [64, 48]\nframes = 2\n[limits]\nmax_memory_mib = " << max_memory_mib
      << "\n[[layer]]\nseed = 3\nlifetime = 1.0\n[layer.kernel]\nradius = 12.0\n"
      << "[[layer.flow]]\ntype = \"curl\"\nscale = " << scale << "\nspeed = 20.0\n";
    return s.str();
}
double estimated_mib(double scale) {
    return scenes::Renderer(scenes::load_scene_string(curl_scene(scale, 1e6), "curl.toml"))
        .estimated_memory_mib();
}
}  // namespace

TEST_CASE("composition: a curl flow's potential lattice counts in the memory budget",
          "[scenes][compose][errors]") {
    // The lattice holds a node every scale / 8 over the region the impulses move in (the view
    // plus the kernel and the flow's reach, ~370 units across here): 27 bytes a node with the
    // cells and the growth of a rebuild. Scale 0.5 needs ~14 M nodes, hundreds of MiB, before a
    // frame is drawn: refused at load with the estimate. Scale 60 (~2500 nodes) renders.
    const double tiny = estimated_mib(0.5), coarse = estimated_mib(60.0);
    CHECK(tiny - coarse > 200.0);                          // uncounted: equal estimates
    CHECK(estimated_mib(1.0) - coarse == Approx((tiny - coarse) / 4.0).epsilon(0.01));  // 1 / scale^2
    try {
        scenes::Renderer r(scenes::load_scene_string(curl_scene(0.5, 60.0), "curl.toml"));
        FAIL("no error");
    } catch (const BudgetError& e) {
        CHECK_THAT(std::string(e.what()), Contains("curl.toml:") && Contains("MiB") &&
                                              Contains("limits.max_memory_mib"));
    }
    scenes::Renderer fine(scenes::load_scene_string(curl_scene(60.0, 60.0), "curl.toml"));
    Frame f;
    fine.render(1, f);
    CHECK(std::isfinite(f.data[0]));
}

namespace {
std::string flow_scene(const std::string& flow, int substeps, double max_flow_steps) {
    std::ostringstream s;
    s << "[output]\nsize = [64, 48]\nframes = 2\nfps = 24\n[limits]\nmax_flow_steps = "
      << max_flow_steps << "\n[[layer]]\nseed = 3\nlifetime = 2.0\nsubsteps = " << substeps
      << "\n[layer.kernel]\nradius = 12.0\n" << flow;
    return s.str();
}
double estimated_steps(const std::string& flow, int substeps) {
    return scenes::Renderer(scenes::load_scene_string(flow_scene(flow, substeps, 1e10), "f.toml"))
        .estimated_flow_steps();
}
}  // namespace

TEST_CASE("composition: a first frame's flow steps are held to limits.max_flow_steps",
          "[scenes][compose][errors]") {
    // Every live impulse is moved from its birth: ~(lifetime / 2) fps substeps steps each.
    const std::string curl = "[[layer.flow]]\ntype = \"curl\"\nscale = 40.0\nspeed = 20.0\n";
    const double one = estimated_steps(curl, 1);
    CHECK(estimated_steps(curl, 2) == Approx(2.0 * one).epsilon(1e-12));  // steps, not impulses
    CHECK(estimated_steps("", 1) == 0.0);                                  // no flow: no steps
    const double n = scenes::Renderer(scenes::load_scene_string(flow_scene(curl, 1, 1e10), "f.toml"))
                         .estimated_impulses();
    CHECK(one == Approx(n * (0.5 * 2.0 + 1.0 / 24.0) * 24.0).epsilon(1e-12));
    try {
        scenes::Renderer r(scenes::load_scene_string(flow_scene(curl, 1, 0.999 * one), "f.toml"));
        FAIL("no error");
    } catch (const BudgetError& e) {
        CHECK_THAT(std::string(e.what()), Contains("f.toml:") && Contains("flow steps") &&
                                              Contains("limits.max_flow_steps"));
    }
    scenes::Renderer fine(scenes::load_scene_string(flow_scene(curl, 1, 1.001 * one), "f.toml"));
    Frame f;
    fine.render(1, f);
    CHECK(std::isfinite(f.data[0]));
}

TEST_CASE("composition: a warp beyond the memory budget is refused with its size",
          "[scenes][compose][errors]") {
    const std::string text = warp_scene("warp = { source = [\"wx\", \"wy\"], amount = 2000.0 }") +
                             "[limits]\nmax_memory_mib = 60.0\n";
    const scenes::Scene scene = scenes::load_scene_string(text, "big.toml");
    try {
        scenes::Renderer r(scene);
        Frame f;
        r.render(0, f);
        FAIL("no error");
    } catch (const BudgetError& e) {
        CHECK_THAT(std::string(e.what()), Contains("big.toml:") && Contains("MiB") &&
                                              Contains("limits.max_memory_mib"));
    }
}
