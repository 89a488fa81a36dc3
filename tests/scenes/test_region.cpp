// SPDX-License-Identifier: Apache-2.0
// Birth regions in scenes ([layer.region]): the rendered field of a still layer confined to a
// circle with a soft edge against Campbell's theorem for an inhomogeneous Poisson process
// (interior variance, the variance across the feather, exactly the mean outside), a region
// covering everything giving the same bytes as none, image masks, and the keys' errors.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "../support.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"
#include "numeric/errors.h"

namespace {

using impulse::kernels::Kernel;
using impulse::render::Frame;
using impulse::scenes::load_scene_string;
constexpr double kPi = std::numbers::pi;

Frame render(const std::string& text, int64_t frame = 0) {
    impulse::scenes::Renderer r(load_scene_string(text, "region.toml"));
    Frame f;
    r.render(frame, f);
    return f;
}

bool same_bits(const Frame& a, const Frame& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

std::string error_of(const std::string& text) {
    try {
        load_scene_string(text, "region.toml");
    } catch (const impulse::SceneError& e) {
        return e.what();
    }
    return "(no error)";
}

double smoothstep_region(double d, double feather) {
    const double t = std::clamp((d + 0.5 * feather) / feather, 0.0, 1.0);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

}  // namespace

TEST_CASE("a still layer in a soft circle: Campbell's theorem inside, across the edge, outside",
          "[scenes][region][stats][slow]") {
    // Cosine kernel R = 4 px, density 16, normal amplitudes, mean 0.25; circle of radius 320
    // round the frame centre with a feather of 64: p(r) = 1 - smoothstep((r - 288) / 64).
    // Eight seeds of a 1024^2 frame.
    //
    // Theory (Campbell's theorem for a Poisson process of intensity lambda p(y)): f - mean has
    // zero mean and variance V(x) = lambda E[a^2] int p(y) h(x - y)^2 dy; V = sigma^2 =
    // lambda E[a^2] int h^2 where p = 1 within the kernel's reach (r <= 284), and f = mean
    // exactly where no birth can reach (r > 320 + 32 + 4 = 356: p = 0 beyond the support).
    //
    // Bands. The mean of (f - mean)^2 over M pixel samples has variance
    //   (1/M^2) sum_pq [2 C(p, q)^2 + k4(p, q)],  C(p, q) = lambda E[a^2] int p h(p-y) h(q-y) dy,
    //   k4(p, q) = lambda E[a^4] int p h(p-y)^2 h(q-y)^2 dy,
    // bounded with p <= p_max (the largest p within the kernel's reach of the pixels) by
    //   (1/M) [2 p_max^2 int C0^2 + p_max lambda E[a^4] (int h^2)^2],  C0 = lambda E[a^2] h * h~,
    // (the sum over q of h(p-y)^2 h(q-y)^2 is at most int h^2 times h(p-y)^2). The interior
    // sample mean has variance S(0) / M, S(0) = lambda E[a^2] (int h)^2. Bands: 5 sd.
    const int size = 1024, seeds = 8;
    const double cx = 512, radius = 320, feather = 64, kr = 4, mean = 0.25;
    auto scene = [&](int seed, bool region) {
        std::string s = "seed = " + std::to_string(seed) +
                        "\n[output]\nsize = [1024, 1024]\n[[layer]]\ndensity = 16.0\nmean = 0.25\n"
                        "[layer.kernel]\ntype = \"cosine\"\nradius = 4.0\n";
        if (region)
            s += "[layer.region]\ntype = \"circle\"\ncenter = [512.0, 512.0]\nradius = 320.0\n"
                 "feather = 64.0\n";
        return s;
    };
    const auto sc = load_scene_string(scene(0, true), "region.toml");
    const Kernel k(sc.layers[0].kernel);
    const double lambda = sc.layers[0].process.intensity, ea2 = 1.0, ea4 = 3.0;
    const double sigma2 = lambda * ea2 * k.integral_sq();
    const double s0 = lambda * ea2 * k.integral() * k.integral();
    double int_c0_sq = 0;  // int (lambda E[a^2] A(rho))^2 d^2 tau, A radial, out to 2R
    for (int i = 0; i < 400; ++i) {
        const double rho = (i + 0.5) * 2 * kr / 400;
        int_c0_sq += 2 * kPi * rho * std::pow(lambda * ea2 * k.autocorrelation(rho, 0), 2) * 2 * kr / 400;
    }
    const double k4_term = lambda * ea4 * k.integral_sq() * k.integral_sq();
    auto p_of = [&](double r) { return smoothstep_region(r - radius, feather); };
    // V(r) on a table: polar quadrature over the kernel disc (64 radii x 128 angles, midpoint).
    const double r_lo = 270, r_hi = 390, dr = 0.25;
    std::vector<double> v_table, v_hard;
    for (double r = r_lo; r <= r_hi + dr; r += dr) {
        double v = 0, vh = 0;
        for (int a = 0; a < 64; ++a)
            for (int b = 0; b < 128; ++b) {
                const double u = (a + 0.5) * kr / 64, phi = (b + 0.5) * 2 * kPi / 128;
                const double h = k.evaluate(u, 0);
                const double dist = std::hypot(r + u * std::cos(phi), u * std::sin(phi));
                const double wgt = h * h * u * (kr / 64) * (2 * kPi / 128);
                v += p_of(dist) * wgt;
                vh += (dist <= radius ? 1.0 : 0.0) * wgt;
            }
        v_table.push_back(lambda * ea2 * v);
        v_hard.push_back(lambda * ea2 * vh);
    }
    auto interp = [&](const std::vector<double>& t, double r) {
        const double x = (r - r_lo) / dr;
        const size_t i = static_cast<size_t>(x);
        return t[i] + (x - i) * (t[i + 1] - t[i]);
    };
    REQUIRE(interp(v_table, 280.0) == Approx(sigma2).epsilon(2e-3));  // quadrature check

    // Annuli of 8 px from 272 to 368.
    const int nb = 12;
    std::vector<double> sum_sq(nb, 0), expect(nb, 0), expect_hard(nb, 0);
    std::vector<double> count(nb, 0);
    double in_sum = 0, in_sq = 0, in_n = 0;
    size_t outside = 0, outside_exact = 0;
    for (int seed = 1; seed <= seeds; ++seed) {
        const Frame f = render(scene(seed, true));
        for (int j = 0; j < size; ++j)
            for (int i = 0; i < size; ++i) {
                const double r = std::hypot(i + 0.5 - cx, j + 0.5 - cx);
                const double d = f.at(i, j) - mean;
                if (r < radius - feather / 2 - kr) in_sum += d, in_sq += d * d, ++in_n;
                if (r > radius + feather / 2 + kr) {
                    ++outside;
                    outside_exact += f.at(i, j) == static_cast<float>(mean);
                }
                const int b = static_cast<int>((r - 272) / 8);
                if (r >= 272 && b < nb) {
                    sum_sq[b] += d * d;
                    expect[b] += interp(v_table, r);
                    expect_hard[b] += interp(v_hard, r);
                    ++count[b];
                }
            }
    }
    // Exactly the mean outside the region's reach.
    CHECK(outside > 1000000);
    CHECK(outside_exact == outside);
    // Interior: Campbell's mean and variance.
    const double m = in_sum / in_n, var = in_sq / in_n - m * m;
    const double sd_mean = std::sqrt(s0 / in_n);
    const double sd_var = std::sqrt((2 * int_c0_sq + k4_term) / in_n);
    CAPTURE(m, sd_mean, var, sigma2, sd_var);
    CHECK(std::abs(m) < 5 * sd_mean);
    CHECK(std::abs(var - sigma2) < 5 * sd_var);
    // Across the edge: V(r) per annulus.
    int out = 0, out_hard = 0;
    for (int b = 0; b < nb; ++b) {
        const double r0 = 272 + 8 * b, r1 = r0 + 8;
        const double p_max = std::max(p_of(r0 - kr), 1e-3);  // p falls with r
        const double sd = std::sqrt((2 * p_max * p_max * int_c0_sq + p_max * k4_term) / count[b]);
        const double measured = sum_sq[b] / count[b], e = expect[b] / count[b];
        UNSCOPED_INFO("annulus " << r0 << ".." << r1 << ": measured " << measured / sigma2
                                 << " sigma^2, expected " << e / sigma2 << " (hard edge "
                                 << expect_hard[b] / count[b] / sigma2 << "), sd " << sd / sigma2);
        if (std::abs(measured - e) > 5 * sd) ++out;
        if (std::abs(measured - expect_hard[b] / count[b]) > 5 * sd) ++out_hard;
    }
    CHECK(out == 0);
    // Teeth: a hard edge at the radius is told apart in the feather.
    CHECK(out_hard >= 4);
}

TEST_CASE("a region covering everything gives the same bytes as no region",
          "[scenes][region][determinism]") {
    const std::string still = R"([output]
size = [256, 192]
[[layer]]
density = 16.0
[layer.kernel]
radius = 12.0
)";
    const std::string cover = R"([layer.region]
type = "box"
center = [128.0, 96.0]
size = [100000.0, 100000.0]
feather = 10.0
)";
    CHECK(same_bits(render(still), render(still + cover)));
    const std::string moving = R"([output]
size = [256, 192]
frames = 40
[[layer]]
density = 12.0
lifetime = 1.0
[layer.kernel]
radius = 12.0
[[layer.flow]]
type = "uniform"
velocity = [60.0, 20.0]
)";
    impulse::scenes::Renderer a(load_scene_string(moving, "a.toml"));
    impulse::scenes::Renderer b(load_scene_string(moving + cover, "b.toml"));
    Frame fa, fb;
    for (int f : {0, 1, 2, 17, 39, 5}) {
        a.render(f, fa);
        b.render(f, fb);
        CHECK(same_bits(fa, fb));
    }
    // An inverted region far away covers everything too.
    const std::string inverted = R"([layer.region]
type = "circle"
center = [-50000.0, 0.0]
radius = 10.0
invert = true
)";
    CHECK(same_bits(render(still), render(still + inverted)));
    // And a region that does confine changes the frame.
    CHECK_FALSE(same_bits(render(still), render(still + R"([layer.region]
type = "circle"
center = [128.0, 96.0]
radius = 60.0
)")));
}

TEST_CASE("an image mask confines births to its white pixels", "[scenes][region]") {
    // A 16 x 8 mask, white in columns 4..7 and rows 2..5, placed at origin (64, 32) with
    // 8 texture units per pixel: births only where the bilinear mask is > 0, i.e. texture x in
    // (64 + 3.5 * 8, 64 + 8.5 * 8) = (92, 132) and y in (32 + 1.5 * 8, 32 + 6.5 * 8) = (44, 84).
    impulse::test::TempDir dir("region");
    Frame mask;
    mask.resize(16, 8);
    for (int j = 2; j <= 5; ++j)
        for (int i = 4; i <= 7; ++i) mask.data[size_t(j) * 16 + i] = 1.0f;
    impulse::output::write_image(dir / "mask.png", mask, {0.0, 1.0}, {});
    const std::string text = R"([output]
size = [256, 128]
[[layer]]
density = 16.0
mean = 1.0
[layer.kernel]
radius = 6.0
[layer.region]
type = "image"
path = "mask.png"
origin = [64.0, 32.0]
spacing = 8.0
)";
    impulse::test::write_file(dir / "mask.toml", text);
    impulse::scenes::Renderer r(impulse::scenes::load_scene(dir / "mask.toml"));
    Frame f;
    r.render(0, f);
    const auto& imp = r.impulses(0);
    REQUIRE(imp.size() > 50);
    for (size_t i = 0; i < imp.size(); ++i) {
        CHECK(imp.x[i] > 92);
        CHECK(imp.x[i] < 132);
        CHECK(imp.y[i] > 44);
        CHECK(imp.y[i] < 84);
    }
    // Expected count: lambda times the integral of the bilinear mask, 4 x 4 pixels of 64 units^2
    // each (the ramps either side add as much as they take); Poisson, 5 sd.
    const double lambda = r.scene().layers[0].process.intensity;
    const double mu = lambda * 16 * 64;
    CHECK(std::abs(double(imp.size()) - mu) < 5 * std::sqrt(mu));
    size_t exact = 0, total = 0;
    for (int j = 0; j < 128; ++j)
        for (int i = 0; i < 256; ++i)
            if (i + 0.5 < 92 - 6 || i + 0.5 > 132 + 6 || j + 0.5 < 44 - 6 || j + 0.5 > 84 + 6)
                ++total, exact += f.at(i, j) == 1.0f;
    CHECK(exact == total);
    // Inverted: births everywhere but there.
    impulse::test::write_file(dir / "inv.toml", text + "invert = true\n");
    impulse::scenes::Renderer ri(impulse::scenes::load_scene(dir / "inv.toml"));
    ri.render(0, f);
    size_t inside = 0;
    for (size_t i = 0; i < ri.impulses(0).size(); ++i) {
        const double x = ri.impulses(0).x[i], y = ri.impulses(0).y[i];
        inside += x > 100 && x < 124 && y > 52 && y < 76;  // where the mask is exactly 1
    }
    CHECK(ri.impulses(0).size() > 500);
    CHECK(inside == 0);
}

TEST_CASE("region keys: shapes load, bad values give one line", "[scenes][region][errors]") {
    const std::string base = "[[layer]]\n[layer.region]\n";
    for (const char* ok :
         {"type = \"circle\"\ncenter = [0.0, 0.0]\nradius = 5.0\nfeather = 2.0\n",
          "type = \"ellipse\"\ncenter = [0.0, 0.0]\nradii = [5.0, 2.0]\nangle = 0.3\n",
          "type = \"box\"\ncenter = [0.0, 0.0]\nsize = [5.0, 2.0]\ncorner = 1.0\n",
          "type = \"capsule\"\nfrom = [0.0, 0.0]\nto = [9.0, 2.0]\nradius = 3.0\n",
          "type = \"polygon\"\npoints = [[0.0, 0.0], [9.0, 0.0], [3.0, 5.0]]\nfill = \"evenodd\"\n",
          "type = \"intersection\"\ninvert = true\n[[layer.region.shapes]]\ntype = \"circle\"\n"
          "center = [0.0, 0.0]\nradius = 5.0\n[[layer.region.shapes]]\ntype = \"union\"\n"
          "shapes = [{ type = \"circle\", center = [3.0, 0.0], radius = 2.0 }]\n"}) {
        INFO(ok);
        CHECK_NOTHROW(load_scene_string(base + ok, "region.toml"));
        CHECK(load_scene_string(base + ok, "region.toml").layers[0].process.region);
    }
    // (region keys after the two lines of `base`, the error it must give)
    const std::pair<const char*, const char*> cases[] = {
        {"type = \"circle\"\ncenter = [0.0, 0.0]\nradius = -5.0\n",
         "region.toml:5:10: layer[0].region.radius = -5: expected a radius > 0 (texture units)"},
        {"type = \"circle\"\nradius = 5.0\n",
         "region.toml:2:1: layer[0].region.center: missing: expected [x, y] in texture units"},
        {"type = \"square\"\n",
         "region.toml:3:8: layer[0].region.type = \"square\": expected one of circle, ellipse, box, "
         "capsule, polygon, union, intersection, subtract, image"},
        {"type = \"polygon\"\npoints = [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]\n",
         "region.toml:4:10: layer[0].region.points = [[0, 0], [1, 1], [2, 2]]: expected at least 3 "
         "[x, y] points, not all on one line"},
        {"type = \"circle\"\ncenter = [0.0, 0.0]\nradius = 5.0\nfeather = -1.0\n",
         "region.toml:6:11: layer[0].region.feather = -1: expected a soft-edge width >= 0 "
         "(texture units; 0: a hard edge)"},
        {"type = \"box\"\ncenter = [0.0, 0.0]\nsize = [4.0, 2.0]\ncorner = 1.5\n",
         "region.toml:6:10: layer[0].region.corner = 1.5: expected a corner radius in [0, half the "
         "smaller side]"},
        {"type = \"image\"\npath = \"no_such_mask.png\"\n",
         "region.toml:4:8: layer[0].region.path = \"no_such_mask.png\": cannot read: no such file"},
        {"type = \"image\"\npath = \"m.png\"\nfeather = 2.0\n",
         "region.toml:5:11: layer[0].region.feather = 2: applies to shapes: an image mask's grey "
         "levels are its soft edge"},
        {"type = \"union\"\n",
         "region.toml:2:1: layer[0].region.shapes: missing: expected a list of shapes "
         "([[...shapes]] tables)"},
    };
    for (const auto& [keys, expected] : cases) CHECK(error_of(base + keys) == expected);
}
