// SPDX-License-Identifier: Apache-2.0
// The tiled evaluator (render::accumulate): bit identity across thread counts, tile sizes, region
// splits and SIMD paths (design.md §4), and agreement with the naive double-precision
// reference (render::accumulate_naive) within a derived rounding budget.

#include <tbb/task_arena.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace {

using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelType;
using impulse::render::EvalOptions;
using impulse::render::Frame;
using impulse::render::View;
using impulse::sim::ProcessConfig;

constexpr double kPi = std::numbers::pi;

bool same_bits(const Frame& a, const Frame& b) {
    return a.width == b.width && a.height == b.height && a.data.size() == b.data.size() &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

/// A still layer: kernel, process (cell size = radius, as the scene loader sets it) and a view
/// whose origin is off the pixel grid and partly at negative coordinates.
struct Case {
    std::string name;
    KernelParams kernel;
    ProcessConfig process;
    View view;
};

Case cosine_case() {
    Case c;
    c.name = "cosine r=16";
    c.kernel.type = KernelType::Cosine;
    c.kernel.radius = 16.0;
    c.process.seed = 2024;
    c.process.cell_size = 16.0;
    c.process.intensity = 16.0 / (kPi * 16.0 * 16.0);
    c.view = {301, 229, -100.3, 37.25, 1.0};
    return c;
}

Case gabor_case() {
    Case c;
    c.name = "gabor r=12 aspect 2.5, random orientation";
    c.kernel.type = KernelType::Gabor;
    c.kernel.radius = 12.0;
    c.kernel.frequency = 0.08;
    c.kernel.phase = 0.4;
    c.kernel.aspect = 2.5;
    c.kernel.orientation = 0.3;
    c.process.seed = 77;
    c.process.layer = 3;
    c.process.cell_size = 12.0;
    c.process.amplitude = impulse::sim::Amplitude::Uniform;
    c.process.orientation = impulse::sim::OrientationMode::Random;
    c.process.intensity = 16.0 / (kPi * 12.0 * 12.0 / 2.5);
    c.view = {257, 190, 13.7, -61.1, 0.8};  // 0.8 texture units per pixel
    return c;
}

/// Isotropic Gaussian: the renderer's separable exp path.
Case gaussian_case() {
    Case c;
    c.name = "gaussian r=20 sigma=6 (separable)";
    c.kernel.type = KernelType::Gaussian;
    c.kernel.radius = 20.0;
    c.kernel.sigma = 6.0;
    c.process.seed = 31;
    c.process.cell_size = 20.0;
    c.process.amplitude = impulse::sim::Amplitude::Sign;
    c.process.intensity = 12.0 / (kPi * 20.0 * 20.0);
    c.view = {263, 201, -40.5, -300.125, 1.0};
    return c;
}

/// Isotropic Gabor with random orientation: the separable path with a carrier.
Case gabor_iso_case() {
    Case c;
    c.name = "gabor r=16 isotropic, random orientation (separable)";
    c.kernel.type = KernelType::Gabor;
    c.kernel.radius = 16.0;
    c.kernel.frequency = 0.07;
    c.kernel.phase = -0.9;
    c.process.seed = 32;
    c.process.cell_size = 16.0;
    c.process.orientation = impulse::sim::OrientationMode::Random;
    c.process.intensity = 16.0 / (kPi * 16.0 * 16.0);
    c.view = {240, 222, 5.0, 9.0, 1.25};
    return c;
}

/// Elliptical Gaussian with R = 12 sigma: the polynomial cannot fit it, the table envelope is
/// used.
Case gaussian_table_case() {
    Case c;
    c.name = "gaussian r=18 sigma=1.5 aspect 1.5 (table envelope)";
    c.kernel.type = KernelType::Gaussian;
    c.kernel.radius = 18.0;
    c.kernel.sigma = 1.5;
    c.kernel.aspect = 1.5;
    c.process.seed = 33;
    c.process.cell_size = 18.0;
    c.process.orientation = impulse::sim::OrientationMode::Random;
    c.process.intensity = 16.0 / (kPi * 18.0 * 18.0 / 1.5);
    c.view = {250, 190, 0.0, 0.0, 1.0};
    return c;
}

/// A 2-D grid of samples (of an elliptical Gabor): the renderer's grid path.
Case grid_case() {
    Case c = gabor_case();
    c.name = "sampled 65x65 grid of the elliptical gabor (grid path)";
    const Kernel ref(c.kernel);
    auto sk = std::make_shared<impulse::kernels::SampledKernel>();
    sk->radial = false;
    sk->n = 65;
    const double R = c.kernel.radius;
    for (int j = 0; j < sk->n; ++j)
        for (int i = 0; i < sk->n; ++i)
            sk->values.push_back(ref.evaluate(-R + 2 * R * i / (sk->n - 1), -R + 2 * R * j / (sk->n - 1)));
    KernelParams p;
    p.type = KernelType::Sampled;
    p.radius = R;
    p.sampled = sk;
    c.kernel = p;
    return c;
}

Case make_case(int i) {
    switch (i) {
        case 0: return cosine_case();
        case 1: return gabor_case();
        case 2: return gaussian_case();
        case 3: return gabor_iso_case();
        case 4: return gaussian_table_case();
        default: return grid_case();
    }
}

impulse::sim::Impulses impulses_for(const Case& c) {
    impulse::sim::LayerSimulator sim(c.process, nullptr, impulse::sim::Timing{}, c.kernel.radius);
    impulse::sim::Impulses imp;
    sim.impulses_at(0, c.view.box(), imp);
    return imp;
}

Frame evaluate(const Kernel& k, const impulse::sim::Impulses& imp, const View& v,
               const EvalOptions& o = {}) {
    Frame f;
    impulse::render::accumulate(k, imp, v, f, o);
    return f;
}

/// Standard deviation of the layer by Campbell's theorem.
double theory_sd(const Case& c) {
    const Kernel k(c.kernel);
    return std::sqrt(c.process.intensity * impulse::sim::amplitude_second_moment(c.process.amplitude) *
                     k.integral_sq());
}

}  // namespace

TEST_CASE("evaluation is bit-identical for any thread count, tiling, split and SIMD path",
          "[render][determinism]") {
    {
        const Case c = make_case(GENERATE(range(0, 6)));
        CAPTURE(c.name);
        const Kernel k(c.kernel);
        const auto imp = impulses_for(c);
        REQUIRE(imp.size() > 500);
        const Frame ref = evaluate(k, imp, c.view);
        // Not trivially zero: the field has its expected spread.
        double s2 = 0.0;
        for (float v : ref.data) s2 += double(v) * v;
        CHECK(std::sqrt(s2 / ref.data.size()) > 0.5 * theory_sd(c));

        SECTION("thread counts") {
            // (tbb::global_control, what `impulse render --threads N` uses, is exercised by the
            // CLI tests in a fresh process: in-process it makes TBB print warnings.)
            for (int n : {1, 2, 3, 4}) {
                CAPTURE(n);
                tbb::task_arena arena(n);
                Frame f;
                arena.execute([&] { f = evaluate(k, imp, c.view); });
                CHECK(same_bits(f, ref));
            }
            EvalOptions serial;
            serial.parallel = false;
            CHECK(same_bits(evaluate(k, imp, c.view, serial), ref));
        }
        SECTION("tile sizes") {
            for (int t : {8, 37, 64, 128, 1000}) {
                CAPTURE(t);
                EvalOptions o;
                o.tile_size = t;
                CHECK(same_bits(evaluate(k, imp, c.view, o), ref));
            }
        }
        SECTION("SIMD path") {
            // ref is the widest path the CPU has (AVX-512 here when present); AVX2 and the
            // baseline must give the same bits.
            EvalOptions avx2;
            avx2.use_avx512 = false;
            CHECK(same_bits(evaluate(k, imp, c.view, avx2), ref));
            EvalOptions base;
            base.use_avx2 = false;
            CHECK(same_bits(evaluate(k, imp, c.view, base), ref));
            base.tile_size = 37;
            base.parallel = false;
            CHECK(same_bits(evaluate(k, imp, c.view, base), ref));
        }
        SECTION("a frame assembled from separately evaluated regions") {
            // Irregular splits, including 1-pixel strips, each region evaluated on its own.
            const std::vector<int> xs = {0, 1, 50, 173, 240, c.view.width};
            const std::vector<int> ys = {0, 64, 65, 131, c.view.height};
            Frame assembled;
            assembled.resize(c.view.width, c.view.height);
            for (size_t j = 0; j + 1 < ys.size(); ++j)
                for (size_t i = 0; i + 1 < xs.size(); ++i) {
                    const int w = xs[i + 1] - xs[i], h = ys[j + 1] - ys[j];
                    std::vector<float> tile(size_t(w) * h, 0.0f);
                    EvalOptions o;
                    o.use_avx2 = (i + j) % 3 != 0;  // mix the three loop builds
                    o.use_avx512 = (i + j) % 3 == 1;
                    impulse::render::accumulate_region(k, imp, c.view, xs[i], ys[j], w, h, tile.data(), o);
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x)
                            assembled.data[size_t(ys[j] + y) * c.view.width + xs[i] + x] =
                                tile[size_t(y) * w + x];
                }
            CHECK(same_bits(assembled, ref));
        }
        SECTION("accumulate adds to what is there") {
            Frame f;
            f.resize(c.view.width, c.view.height);
            for (float& v : f.data) v = 0.25f;
            impulse::render::accumulate(k, imp, c.view, f);
            Frame expected = ref;
            for (float& v : expected.data) v = 0.25f + v;
            CHECK(same_bits(f, expected));
        }
    }
}

TEST_CASE("a scene with flow renders the same bits on 1 and 2 threads", "[render][determinism]") {
    // The whole frame path: births, RK2 integration with the Jacobian, flow orientation, two
    // layers, tiles.
    const char* text = R"(
[output]
size = [160, 120]
frames = 12
[[layer]]
seed = 5
density = 10.0
lifetime = 1.0
orientation = "flow"
[layer.kernel]
type = "gaussian"
radius = 14.0
sigma = 5.0
aspect = 1.5
[[layer.flow]]
type = "source"
center = [80.0, 60.0]
rate = 0.3
radius = 50.0
[[layer.flow]]
type = "curl"
scale = 60.0
speed = 15.0
[[layer]]
seed = 6
density = 12.0
gain = 0.5
lifetime = 0.8
orientation = "vorticity"
[layer.kernel]
type = "gabor"
radius = 10.0
frequency = 0.1
[[layer.flow]]
type = "vortex"
center = [70.0, 50.0]
circulation = 3000.0
core = 20.0
)";
    const auto scene = impulse::scenes::load_scene_string(text, "flow.toml");
    auto render = [&](int threads, int tile) {
        tbb::task_arena arena(threads);
        Frame f;
        arena.execute([&] {
            impulse::scenes::Renderer r(scene);
            EvalOptions o;
            o.tile_size = tile;
            r.render(9, f, o);
        });
        return f;
    };
    const Frame a = render(1, 64);
    const Frame b = render(2, 64);
    const Frame c = render(2, 24);
    double s2 = 0.0;
    for (float v : a.data) s2 += double(v) * v;
    CHECK(s2 > 0.0);
    CHECK(same_bits(a, b));
    CHECK(same_bits(a, c));
}

namespace {

/// Largest |h| just inside the support boundary (0 for kernels continuous at R): where a
/// float rounding can move a pixel across the boundary, the two evaluators differ by up to
/// this times |a|.
double edge_value(const Case& c) {
    if (c.kernel.type == KernelType::Sampled) return 0.0101;  // samples of a 1 %-edge Gabor
    const double e = std::abs(Kernel(c.kernel).envelope(1.0 - 1e-12));
    return e > 1e-6 ? e : 0.0;
}

/// max |a|: uniform and sign 1; normal from Box–Muller on 32-bit uniforms, sqrt(-2 ln 2^-33).
double max_amplitude(const Case& c) {
    return c.process.amplitude == impulse::sim::Amplitude::Normal ? 6.77 : 1.0;
}

// The two differ only in arithmetic. The tiled path rounds each impulse position to float
// pixel coordinates once: an error d per coordinate, uniform within half an ulp, so
// E[d^2] <= ulp^2 / 12 with ulp = 2^-15 px for coordinates below 512 px. The frame error
// sum_k a_k grad h(x - x_k) . d_k is itself shot noise, so by Campbell's theorem
//     rms_pos^2 = lambda E[a^2] int |grad h|^2 dA * (ulp * scale)^2 / 12
// (int |grad h|^2 by finite differences of Kernel::evaluate). The float envelope (polynomial
// or exp, error <= 1e-6), the float carrier cosine and sin/cos of the orientation add relative
// errors below 1e-6 per term: rms_eval <= 1e-6 sd. With rms_model = sqrt(rms_pos^2 +
// rms_eval^2) the measured RMS must be below it, and the maximum over ~5e4 roughly Gaussian
// pixel errors below 6 rms_model (4.4 expected) — and below the product promise of 1e-4 sd.
//
// A kernel that jumps at its support edge (Gabor: 1 % envelope at R; truncated Gaussian
// e^{-R^2/2s^2}) adds a rare, larger difference: a pixel centre within ~|d| of an impulse's
// edge can fall on the other side of q < 1 in float. The band around the edge has area
// ~ perimeter * E|d| ~ 100 px * 4e-6 px per impulse, times ~3000 impulses: ~1 such pixel
// expected. They are allowed (at most 6: Poisson(1) exceeds 6 with probability 8e-5) when
// bounded by one impulse's edge value, edge * max|a| + the band.
void check_against_naive(const Case& c) {
    CAPTURE(c.name);
    const Kernel k(c.kernel);
    const auto imp = impulses_for(c);
    const Frame tiled = evaluate(k, imp, c.view);
    Frame naive;
    impulse::render::accumulate_naive(k, c.process, c.view, naive);
    REQUIRE(naive.data.size() == tiled.data.size());

    // int |grad h|^2 over the support box, central differences with step e = 0.01 R on a
    // grid of 0.02 R (a jump at the edge adds a little: conservative).
    const double R = c.kernel.radius, g = 0.02 * R, e = 0.01 * R;
    double grad2 = 0.0;
    for (double y = -R - g; y <= R + g; y += g)
        for (double x = -R - g; x <= R + g; x += g) {
            const double hx = (k.evaluate(x + e, y) - k.evaluate(x - e, y)) / (2 * e);
            const double hy = (k.evaluate(x, y + e) - k.evaluate(x, y - e)) / (2 * e);
            grad2 += (hx * hx + hy * hy) * g * g;
        }
    const double ea2 = impulse::sim::amplitude_second_moment(c.process.amplitude);
    const double sd = theory_sd(c);
    const double ulp = std::ldexp(1.0, -15) * c.view.scale;
    const double rms_pos = std::sqrt(c.process.intensity * ea2 * grad2 * ulp * ulp / 12.0);
    const double rms_model = std::hypot(rms_pos, 1e-6 * sd);
    const double band = std::min(6.0 * rms_model, 1e-4 * sd);
    const double edge = edge_value(c) * max_amplitude(c);

    double worst = 0.0, s2 = 0.0, f2 = 0.0, worst_edge = 0.0;
    int edge_pixels = 0;
    for (size_t i = 0; i < tiled.data.size(); ++i) {
        const double d = double(tiled.data[i]) - naive.data[i];
        f2 += double(naive.data[i]) * naive.data[i];
        if (std::abs(d) > band && edge > 0.0) {
            ++edge_pixels;
            worst_edge = std::max(worst_edge, std::abs(d));
            continue;
        }
        worst = std::max(worst, std::abs(d));
        s2 += d * d;
    }
    const double rms = std::sqrt(s2 / tiled.data.size());
    CAPTURE(sd, rms_pos, rms_model, rms, worst, band, edge_pixels, worst_edge, edge);
    CHECK(rms < rms_model);
    CHECK(worst <= band);
    CHECK(edge_pixels <= 6);
    CHECK(worst_edge <= edge + band);
    CHECK(std::sqrt(f2 / tiled.data.size()) > 0.5 * sd);  // not two empty frames
}

}  // namespace

TEST_CASE("the tiled evaluator agrees with the naive double-precision reference", "[render]") {
    // Every analytic inner-loop path: Chebyshev (cosine; elliptical Gabor) and separable exp
    // (isotropic Gaussian and Gabor). The table envelope and the grid path follow.
    for (int i : {0, 1, 2, 3}) check_against_naive(make_case(i));
}

TEST_CASE("the tiled evaluator agrees with the naive reference for a narrow elliptical Gaussian",
          "[render]") {
    // R = 12 sigma with aspect 1.5 takes the table envelope (4097 entries linear in q), whose
    // interpolation error ~ (1/4096)^2 / 8 * 72^2 = 3.9e-5 of the peak exceeds the rounding
    // budget above by an order of magnitude.
    check_against_naive(make_case(4));
}

TEST_CASE("the tiled evaluator agrees with the naive reference for a grid kernel", "[render]") {
    // The renderer's grid path masks to the disk u^2 + v^2 < R^2 (kernels.h: "zero beyond the
    // radius R"); Kernel::evaluate (and so accumulate_naive, integral(), power_spectrum()) uses
    // the bilinear interpolant over the whole square [-R, R]^2. Here the samples are of an
    // elliptical Gabor, so only the bilinear ramp just beyond the ellipse's tips (which reach
    // R) differs — but in ~1700 pixels, by up to 0.6 % of an amplitude.
    check_against_naive(make_case(5));
}

TEST_CASE("accumulate refuses non-finite impulses with the impulse and value named",
          "[render][evaluate][errors]") {
    const Case c = gabor_case();
    const Kernel kernel(c.kernel);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    struct Bad {
        const char* what;
        double x, y, theta, weight;
        const char* message;
    };
    for (const Bad& b : {Bad{"x NaN", nan, 10.0, 0.0, 1.0, "impulse 1: x = nan"},
                         Bad{"y inf", 10.0, -inf, 0.0, 1.0, "impulse 1: y = -inf"},
                         Bad{"theta NaN", 10.0, 10.0, nan, 1.0, "impulse 1: theta = nan"},
                         Bad{"theta inf", 10.0, 10.0, inf, 1.0, "impulse 1: theta = inf"},
                         Bad{"weight NaN", 10.0, 10.0, 0.0, nan, "impulse 1: weight = nan"},
                         Bad{"x beyond float", 1e300, 10.0, 0.0, 1.0, "impulse 1: x = 1e+300"}}) {
        INFO(b.what);
        impulse::sim::Impulses imp;
        imp.x = {20.0, b.x}, imp.y = {20.0, b.y};
        imp.theta = {0.0f, static_cast<float>(b.theta)}, imp.weight = {1.0f, static_cast<float>(b.weight)};
        Frame out;
        CHECK_THROWS_MATCHES(impulse::render::accumulate(kernel, imp, c.view, out),
                             impulse::ValueError, Catch::Message(std::string("render::accumulate: ") + b.message + ": expected finite impulse coordinates, orientations and weights"));
        float tile[16] = {};
        CHECK_THROWS_AS(impulse::render::accumulate_region(kernel, imp, c.view, 0, 0, 4, 4, tile),
                        impulse::ValueError);
    }
}
