// SPDX-License-Identifier: Apache-2.0
// Keyframed layer, kernel, marginal, orientation, flow and shading numbers: each changes the
// frames as its closed form says, a keyframed density acts through the births of the last
// lifetime (thinning), and sequential and random-access rendering give the same bits.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <numbers>

#include "scenes/scenes.h"
#include "numeric/errors.h"

using namespace impulse;
namespace S = impulse::scenes;

namespace {

constexpr double kPi = std::numbers::pi;

render::Frame render_frame(S::Renderer& r, int64_t frame) {
    render::Frame f;
    r.render(frame, f);
    return f;
}

/// Pixel variance about a known mean, with its standard error from the scatter of the
/// variances of B x B blocks (blocks several correlation lengths wide are nearly independent:
/// design.md §5, bands from the run itself).
struct BlockVariance {
    double variance = 0.0, se = 0.0;
    size_t blocks = 0;
};
BlockVariance block_variance(const std::vector<const render::Frame*>& frames, double mean, int B) {
    std::vector<double> v;
    for (const render::Frame* f : frames)
        for (int by = 0; by + B <= f->height; by += B)
            for (int bx = 0; bx + B <= f->width; bx += B) {
                double s = 0.0;
                for (int y = by; y < by + B; ++y)
                    for (int x = bx; x < bx + B; ++x) {
                        const double d = f->at(x, y) - mean;
                        s += d * d;
                    }
                v.push_back(s / (double(B) * B));
            }
    BlockVariance r;
    r.blocks = v.size();
    for (double x : v) r.variance += x / v.size();
    double ss = 0.0;
    for (double x : v) ss += (x - r.variance) * (x - r.variance);
    r.se = std::sqrt(ss / (v.size() - 1) / v.size());
    return r;
}

/// Keys (0, v0) and (t1, v1), linear.
numeric::Keyframed linear_keys(double v0, double t1, double v1) {
    numeric::Keyframed k;
    k.keys = {{0.0, v0}, {t1, v1}};
    return k;
}

bool same_bits(const render::Frame& a, const render::Frame& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("a keyframed gain scales the field and a keyframed mean shifts it, exactly",
          "[scenes][keyframes]") {
    // A still layer: the impulses are the same in every frame, so frame t is exactly
    // mean(t) + gain(t) / gain(0) (frame 0 - mean(0)) up to float rounding.
    const S::Scene scene = S::load_scene_string(R"(
[output]
size = [96, 64]
fps = 4
frames = 9
[[layer]]
gain = { keys = [[0.0, 1.0], [2.0, 3.0]] }
mean = { keys = [[0.0, 0.0], [1.0, 5.0], [2.0, -2.0]], ease = "smooth" }
[layer.kernel]
radius = 8.0
)",
                                                "gain.toml");
    S::Renderer r(scene);
    const render::Frame f0 = render_frame(r, 0);
    for (int64_t frame : {2, 5, 8}) {  // t = 0.5, 1.25, 2 s
        const double t = scene.frame_time(frame);
        const double gain = scene.layers[0].gain.value(t), mean = scene.layers[0].mean.value(t);
        CAPTURE(t, gain, mean);
        CHECK(gain == Approx(1.0 + t).epsilon(1e-12));
        const render::Frame f = render_frame(r, frame);
        double worst = 0.0, scale = 0.0;
        for (size_t p = 0; p < f.data.size(); ++p) {
            worst = std::max(worst, std::abs(f.data[p] - (mean + gain * f0.data[p])));
            scale = std::max(scale, std::abs(double(f0.data[p])));
        }
        // float sums of a few dozen terms: relative rounding of order 1e-6
        CHECK(worst <= 1e-5 * (scale * gain + std::abs(mean)));
        // The closed form follows: Var(t) = gain(t)^2 Var(0), mean(t).
        const S::Theory th = S::layer_theory(scene.layers[0], t);
        CHECK(th.mean == mean);
        CHECK(th.variance == Approx(gain * gain * S::layer_theory(scene.layers[0], 0.0).variance));
    }
}

TEST_CASE("a keyframed kernel sigma changes the variance as Campbell's theorem says",
          "[scenes][keyframes][stats]") {
    // Var = lambda E[a^2] int h_t^2 with the kernel at t (radius fixed, so lambda is too).
    const S::Scene scene = S::load_scene_string(R"(
[output]
size = [512, 512]
fps = 1
frames = 3
[[layer]]
density = 24.0
[layer.kernel]
type = "gaussian"
radius = 12.0
sigma = { keys = [[0.0, 2.0], [2.0, 5.0]] }
)",
                                                "sigma.toml");
    S::Renderer r(scene);
    const S::LayerConfig& L = scene.layers[0];
    double previous = 0.0;
    for (int64_t frame : {0, 1, 2}) {
        const double t = scene.frame_time(frame);
        kernels::KernelParams k = L.kernel;
        k.sigma = 2.0 + 1.5 * t;
        const double campbell =
            L.process.intensity * kernels::Kernel(k).integral_sq();  // E[a^2] = 1 (normal)
        CHECK(S::layer_theory(L, t).variance == Approx(campbell).epsilon(1e-12));
        const render::Frame f = render_frame(r, frame);
        // 64 x 64 blocks are over five kernel radii wide. Tolerance: 5 standard errors of the
        // block mean (4 would do for independent blocks; neighbours share a kernel-wide strip).
        const BlockVariance m = block_variance({&f}, 0.0, 64);
        CAPTURE(t, m.variance, m.se, campbell);
        CHECK(std::abs(m.variance - campbell) < 5.0 * m.se);
        CHECK(m.se < 0.05 * campbell);  // the test can tell sigma 2 from 3.5 from 5
        // int h^2 ~ pi sigma^2 (peak 1): sigma 2 -> 3.5 -> 5 multiplies it by 3.1, then 2.0.
        if (frame > 0) CHECK(campbell > 1.8 * previous);
        previous = campbell;
    }
}

TEST_CASE("a keyframed radius keeps the seeding cells at the largest radius",
          "[scenes][keyframes]") {
    // A still layer: its intensity is that of the kernel at t = 0 (density 4 per area of radius
    // 4), its cells are as large as the largest radius (16). At t = 1 the kernel has radius 16:
    // the frame is the one of a constant radius-16 kernel with the same intensity (density 64
    // per area of radius 16) and cells, bit for bit: no impulse is lost to a too-small cell or
    // cull box.
    const std::string head = "[output]\nsize = [96, 80]\nfps = 1\nframes = 2\n[[layer]]\n";
    const S::Scene keyed = S::load_scene_string(
        head + "density = 4.0\n[layer.kernel]\nradius = { keys = [[0.0, 4.0], [1.0, 16.0]] }\n",
        "r.toml");
    const S::Scene fixed =
        S::load_scene_string(head + "density = 64.0\n[layer.kernel]\nradius = 16.0\n", "r.toml");
    CHECK(keyed.layers[0].process.cell_size == 16.0);
    CHECK(keyed.layers[0].process.intensity == Approx(fixed.layers[0].process.intensity).epsilon(1e-15));
    S::Renderer a(keyed), b(fixed);
    CHECK(same_bits(render_frame(a, 1), render_frame(b, 1)));
    CHECK_FALSE(same_bits(render_frame(a, 0), render_frame(b, 0)));
}

TEST_CASE("a keyframed density acts through the births of the last lifetime (thinning)",
          "[scenes][keyframes][stats]") {
    // density ramps 4 -> 32 over [0, 4] s; hann lifetime 2 s. The live impulses at t were born
    // in [t - 2, t] at the rate of their birth time: Var(t) = lambda_max E[a^2] int h^2
    // (1/T) int_0^T s(t - a) w(a)^2 da. At t = 3 the ramp is linear over the lifetime and w^2 is
    // symmetric, so the variance is that of density(2) = 18, not density(3) = 25.
    const std::string text = R"(
[output]
size = [512, 512]
fps = 10
frames = 60
[[layer]]
lifetime = 2.0
density = { keys = [[0.0, 4.0], [4.0, 32.0]] }
[layer.kernel]
radius = 8.0
)";
    const S::Scene scene = S::load_scene_string(text, "ramp.toml");
    const S::LayerConfig& L = scene.layers[0];
    REQUIRE(L.process.density_scale);
    const double area = kPi * 64.0, h2 = kernels::Kernel(L.kernel).integral_sq();
    CHECK(L.process.intensity == Approx(32.0 / area).epsilon(1e-12));
    const double v3 = S::layer_theory(L, 3.0).variance;
    CHECK(v3 == Approx(18.0 / area * h2 * 3.0 / 8.0).epsilon(1e-6));  // the midpoint rule: 1e-8

    // The same scene with a second seed doubles the sample.
    const S::Scene scene2 = S::load_scene_string(text, "ramp.toml", {"seed=7"});
    S::Renderer a(scene), b(scene2);
    // Without thinning: births at the maximum rate all the time (the mechanism turned off).
    S::Scene off = scene;
    off.layers[0].process.density_scale = nullptr;
    S::Renderer c(off);

    for (int64_t frame : {10, 30, 50}) {  // t = 1, 3, 5 s
        const double t = frame / 10.0;
        const double theory = S::layer_theory(L, t).variance;
        CAPTURE(t, theory);
        // Live count in the frame: Poisson with mean lambda_max area (1/T) int s(t_b) dt_b.
        {
            double integral = 0.0;  // (1/T) int_{t-T}^t s, midpoint rule
            for (int i = 0; i < 4000; ++i) integral += L.process.density_scale(t - 2.0 * (i + 0.5) / 4000) / 4000;
            const double expected = L.process.intensity * 512.0 * 512.0 * integral;
            render::Frame f;
            a.render(frame, f);
            const auto& imp = a.impulses(0);
            double n = 0;
            for (size_t i = 0; i < imp.size(); ++i)
                n += imp.x[i] >= 0 && imp.x[i] < 512 && imp.y[i] >= 0 && imp.y[i] < 512;
            CAPTURE(n, expected);
            CHECK(std::abs(n - expected) < 5.0 * std::sqrt(expected));  // 5 Poisson sd
        }
        const render::Frame fa = render_frame(a, frame), fb = render_frame(b, frame);
        const BlockVariance m = block_variance({&fa, &fb}, 0.0, 64);
        CAPTURE(m.variance, m.se);
        // 128 blocks of 64 x 64 (8 kernel radii): 5 standard errors, as above.
        CHECK(std::abs(m.variance - theory) < 5.0 * m.se);
        if (frame == 30) {
            // The measurement separates the thinned closed form from the naive one that takes
            // the density at the frame time (25 instead of 18).
            const double naive = 25.0 / area * h2 * 3.0 / 8.0;
            CHECK(std::abs(m.variance - naive) > 5.0 * m.se);
        }
        if (frame != 50) {  // at t = 5 the ramp is nearly over: 30 vs 32 is within the noise
            const render::Frame fc = render_frame(c, frame);
            const BlockVariance mc = block_variance({&fc}, 0.0, 64);
            CAPTURE(mc.variance, mc.se);
            CHECK(std::abs(mc.variance - theory) > 5.0 * mc.se);  // without thinning it fails
        }
    }
}

TEST_CASE("keyframed scenes render the same bits in order, alone and looped",
          "[scenes][keyframes][determinism][slow]") {
    const std::string text = R"(
[output]
size = [80, 64]
fps = 8
frames = 24
[[layer]]
lifetime = 1.0
loop = 2.0
density = { keys = [[0.0, 6.0], [1.0, 20.0], [2.0, 6.0]], ease = "smooth" }
gain = { keys = [[0.0, 0.5], [1.5, 2.0]] }
mean = { keys = [[0.0, 0.0], [1.0, 0.3]], ease = "step" }
orientation = { type = "sine", wavelength = { keys = [[0.0, 40.0], [2.0, 80.0]] }, jitter = { keys = [[0.0, 0.0], [2.0, 0.5]] } }
[layer.kernel]
type = "gabor"
radius = { keys = [[0.0, 8.0], [1.0, 12.0]] }
frequency = { keys = [[0.0, 0.1], [2.0, 0.2]] }
orientation = { keys = [[0.0, 0.0], [2.0, 1.5]] }
aspect = 2.0
[[layer.flow]]
type = "vortex"
center = [40.0, 32.0]
core = { keys = [[0.0, 10.0], [2.0, 30.0]] }
circulation = 600.0
[[layer]]
seed = 3
density = 8.0
marginal = { type = "uniform", a = -1.0, b = { keys = [[0.0, 1.0], [2.0, 3.0]] } }
[layer.kernel]
type = "gaussian"
radius = 10.0
sigma = { keys = [[0.0, 3.0], [3.0, 4.0]] }
)";
    const S::Scene scene = S::load_scene_string(text, "det.toml");
    S::Renderer seq(scene);
    std::vector<render::Frame> frames;
    for (int64_t f = 0; f < 24; ++f) frames.push_back(render_frame(seq, f));
    for (int64_t f : {23, 5, 17, 0, 11}) {
        S::Renderer alone(scene);
        CAPTURE(f);
        CHECK(same_bits(render_frame(alone, f), frames[size_t(f)]));
    }
    // The first layer loops every 2 s = 16 frames: its keys, births and flow repeat. The second
    // layer is still and keyframed over 3 s, so compare the looped layer alone.
    S::Scene looped = scene;
    looped.layers.pop_back();
    S::Renderer l(looped);
    const render::Frame l0 = render_frame(l, 0), l3 = render_frame(l, 3);
    CHECK(same_bits(render_frame(l, 16), l0));
    CHECK(same_bits(render_frame(l, 19), l3));
    CHECK_FALSE(same_bits(l0, l3));
}

TEST_CASE("a keyframed marginal target moves the shaped layer's distribution",
          "[scenes][keyframes][stats]") {
    // Uniform on [0, b(t)]: mean b/2, variance b^2 / 12 (the transfer is rebuilt per frame).
    const S::Scene scene = S::load_scene_string(R"(
[output]
size = [384, 384]
fps = 1
frames = 3
[[layer]]
density = 16.0
marginal = { type = "uniform", a = 0.0, b = { keys = [[0.0, 1.0], [2.0, 4.0]] } }
[layer.kernel]
radius = 8.0
)",
                                                "marginal.toml");
    S::Renderer r(scene);
    for (int64_t frame : {0, 2}) {
        const double b = frame == 0 ? 1.0 : 4.0;
        const S::Theory th = S::layer_theory(scene.layers[0], double(frame));
        CHECK(th.mean == Approx(b / 2));
        CHECK(th.variance == Approx(b * b / 12));
        const render::Frame f = render_frame(r, frame);
        double lo = 1e9, hi = -1e9, sum = 0.0;
        for (float v : f.data) lo = std::min(lo, double(v)), hi = std::max(hi, double(v)), sum += v;
        CHECK(lo >= 0.0);
        CHECK(hi <= b * (1 + 1e-6));
        CHECK(hi > 0.95 * b);
        // The field's mean: sd b / sqrt(12) over about 384^2 / 100 independent areas (cosine
        // kernel of radius 8: correlation area ~ 100 px), tolerance 5 of them.
        const double se = b / std::sqrt(12.0) / std::sqrt(384.0 * 384.0 / 100.0);
        CHECK(std::abs(sum / f.data.size() - b / 2) < 5 * se);
    }
}

TEST_CASE("a keyframed kernel orientation turns every impulse", "[scenes][keyframes][slow]") {
    // At t = 1 the keyframed layer equals the same layer with the constant orientation 1.2
    // (the turn is added per impulse, in float, instead of to the kernel: rounding only).
    const std::string base = R"(
[output]
size = [128, 96]
fps = 1
frames = 2
[[layer]]
[layer.kernel]
type = "gaussian"
radius = 16.0
sigma = 5.0
aspect = 3.0
)";
    const S::Scene keyed = S::load_scene_string(base + "orientation = { keys = [[0.0, 0.0], [1.0, 1.2]] }\n", "o.toml");
    const S::Scene fixed = S::load_scene_string(base + "orientation = 1.2\n", "o.toml");
    S::Renderer a(keyed), b(fixed);
    const render::Frame fa = render_frame(a, 1), fb = render_frame(b, 1);
    double worst = 0.0, scale = 0.0;
    for (size_t p = 0; p < fa.data.size(); ++p) {
        worst = std::max(worst, double(std::abs(fa.data[p] - fb.data[p])));
        scale = std::max(scale, double(std::abs(fb.data[p])));
    }
    CHECK(worst < 1e-4 * scale);
    CHECK_FALSE(same_bits(render_frame(a, 0), fb));  // and at t = 0 it is not turned

    // Through the anti-aliasing pyramid (a perspective camera) the turn works the same way.
    const std::string camera = "[camera]\ntype = \"perspective\"\nheight = 60.0\npitch = 50.0\n";
    const S::Scene pk = S::load_scene_string(camera + base + "orientation = { keys = [[0.0, 0.0], [1.0, 1.2]] }\n", "p.toml");
    const S::Scene pf = S::load_scene_string(camera + base + "orientation = 1.2\n", "p.toml");
    S::Renderer c(pk), d(pf);
    const render::Frame fc = render_frame(c, 1), fd = render_frame(d, 1);
    worst = 0.0, scale = 0.0;
    for (size_t p = 0; p < fc.data.size(); ++p) {
        worst = std::max(worst, double(std::abs(fc.data[p] - fd.data[p])));
        scale = std::max(scale, double(std::abs(fd.data[p])));
    }
    CHECK(scale > 0.0);
    CHECK(worst < 1e-4 * scale);
    CHECK_FALSE(same_bits(render_frame(c, 0), fd));

    // A keyframed jitter spreads the impulses' own angles by jitter(t): none at t = 0.
    const std::string field = "orientation = { type = \"constant\", angle = 0.3, jitter = ";
    const std::string layer = "[output]\nsize = [96, 64]\nfps = 1\nframes = 2\n[[layer]]\nlifetime = 4.0\n";
    const std::string kernel = "[layer.kernel]\ntype = \"gaussian\"\nradius = 16.0\nsigma = 5.0\naspect = 3.0\n";
    S::Renderer jk(S::load_scene_string(layer + field + "{ keys = [[0.0, 0.0], [1.0, 0.6]] } }\n" + kernel, "j.toml"));
    S::Renderer j0(S::load_scene_string(layer + field + "0.0 }\n" + kernel, "j.toml"));
    S::Renderer j6(S::load_scene_string(layer + field + "0.6 }\n" + kernel, "j.toml"));
    CHECK(same_bits(render_frame(jk, 0), render_frame(j0, 0)));
    CHECK(same_bits(render_frame(jk, 1), render_frame(j6, 1)));
    CHECK_FALSE(same_bits(render_frame(jk, 1), render_frame(j0, 1)));
}

TEST_CASE("keyframed orientation fields, flows and shading take their values at t",
          "[scenes][keyframes]") {
    const double xs[3] = {3.0, 40.0, 77.0}, ys[3] = {5.0, -20.0, 61.0};
    // Sine field: keyed amplitude, wavelength, phase and angle equal the constant field at t.
    const auto keyed = sim::make_sine_orientation(linear_keys(0.0, 2.0, 16.0),
                                                  linear_keys(64.0, 2.0, 128.0),
                                                  linear_keys(0.0, 2.0, 1.0),
                                                  linear_keys(0.0, 2.0, 0.5), 1.0, 2.0);
    const auto fixed = sim::make_sine_orientation(8.0, 96.0, 0.5, 0.25, 1.0, 2.0);
    float a[3], b[3];
    keyed->angles(1.0, 3, xs, ys, a);
    fixed->angles(1.0, 3, xs, ys, b);
    for (int i = 0; i < 3; ++i) CHECK(a[i] == b[i]);
    // Shear with keyed centre and angle; vortex with keyed core: the static flow at t.
    auto v = [&](const sim::Flow& f, double t, double* out) {
        double vx[3] = {}, vy[3] = {}, dv[3] = {}, cu[3] = {};
        f.add(t, 3, xs, ys, vx, vy, dv, cu);
        for (int i = 0; i < 3; ++i) out[2 * i] = vx[i], out[2 * i + 1] = vy[i];
    };
    const numeric::Keyframed ramp = linear_keys(0.0, 4.0, 4.0);  // value t
    double p[6], q[6];
    v(*sim::make_shear_flow(0.3, ramp, 2.0, ramp), 2.0, p);
    v(*sim::make_shear_flow(0.3, 2.0, 2.0, 2.0), 2.0, q);
    for (int i = 0; i < 6; ++i) CHECK(p[i] == q[i]);
    const numeric::Keyframed core = linear_keys(10.0, 4.0, 30.0);
    v(*sim::make_vortex_flow(sim::VortexModel::LambOseen, 40.0, 0.0, 900.0, core), 2.0, p);
    v(*sim::make_vortex_flow(sim::VortexModel::LambOseen, 40.0, 0.0, 900.0, 20.0), 2.0, q);
    for (int i = 0; i < 6; ++i) CHECK(p[i] == q[i]);
    // The speed bound holds for the smallest core: 0.6382 G / (2 pi core_min).
    CHECK(sim::make_vortex_flow(sim::VortexModel::LambOseen, 0.0, 0.0, 900.0, core)->max_speed({}) ==
          Approx(0.6382 * 900.0 / (2 * kPi * 10.0)));

    // Shading numbers at the frame time.
    const S::Scene s = S::load_scene_string(R"(
[[layer]]
[shading]
relief = { keys = [[0.0, 0.0], [2.0, 4.0]] }
light_azimuth = { keys = [[0.0, 0.0], [4.0, 360.0]] }
light_elevation = 30.0
ambient = { keys = [[0.0, 0.1], [2.0, 0.5]], ease = "step" }
)",
                                            "shade.toml");
    const output::Shading sh = s.shading_at(1.0);
    CHECK(sh.relief == 2.0);
    CHECK(sh.light_azimuth_deg == 90.0);
    CHECK(sh.light_elevation_deg == 30.0);
    CHECK(sh.ambient == 0.1);
    CHECK(s.shading_at(2.0).ambient == 0.5);
    CHECK(s.shading.relief == 0.0);  // the t = 0 values
    // Relief at t = 1 shades the field differently from the flat t = 0.
    render::Frame f;
    f.resize(16, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) f.data[size_t(y) * 16 + x] = 0.1f * x * y - 0.02f * y * y;
    std::vector<float> flat, lit;
    output::shade(f, {-3.0, 3.0}, s.shading_at(0.0), flat);
    output::shade(f, {-3.0, 3.0}, sh, lit);
    CHECK(flat != lit);
}

TEST_CASE("the display range covers the keyframed layers over the output's frames",
          "[scenes][keyframes]") {
    const S::Scene scene = S::load_scene_string(R"(
[output]
frames = 41
fps = 10
[[layer]]
gain = { keys = [[1.0, 1.0], [3.0, 3.0]] }
mean = { keys = [[0.0, -1.0], [4.0, 2.0]] }
)",
                                                "range.toml");
    const S::Renderer r(scene);
    const output::ValueMapping m = r.mapping();
    const double sd1 = std::sqrt(S::layer_theory(scene.layers[0], 0.0).variance);
    // mean(t) - 3 gain(t) sd1 falls while the gain grows (3 sd1 > 0.75 per second, the mean's
    // rise), so it is lowest at t = 3 (mean 1.25, gain 3); the top is at t = 4 (mean 2, gain 3).
    REQUIRE(3.0 * sd1 > 0.75);
    CHECK(m.lo == Approx(1.25 - 9.0 * sd1));
    CHECK(m.hi == Approx(2.0 + 9.0 * sd1));
    // A scene without layer keys keeps mean +- 3 sd.
    const S::Scene plain = S::load_scene_string("[[layer]]\nmean = 1.0\n", "plain.toml");
    const output::ValueMapping p = S::Renderer(plain).mapping();
    CHECK(p.lo == Approx(1.0 - 3.0 * sd1));
}
