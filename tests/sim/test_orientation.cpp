// SPDX-License-Identifier: Apache-2.0
// Orientation fields (issue "Non-stationary and perspective", items 2 and 5c): the analytic
// fields' angles, sampled fields, the simulator's use of them (at the particle's current
// position at the frame time; jitter; sequential = random access), the scene keys and their
// errors, and (c) the local orientation of rendered textures, measured with a structure tensor,
// following constant, circular and image fields within 5 degrees where the kernel is
// anisotropic (aspect 4).

#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"
#include "tests/structure_tensor.h"
#include "numeric/errors.h"

namespace {

namespace fs = std::filesystem;
namespace numeric = impulse::numeric;
namespace sim = impulse::sim;
using Catch::Matchers::Contains;
constexpr double kPi = std::numbers::pi;

using impulse::test::orientation_error_deg;

float angle_at(const sim::OrientationField& f, double x, double y, double t = 0.0) {
    float th = 0.0f;
    f.angles(t, 1, &x, &y, &th);
    return th;
}

fs::path temp_dir() {
    const fs::path d =
        fs::temp_directory_path() / ("impulse_orientation_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

}  // namespace

TEST_CASE("orientation fields: analytic angles", "[sim][orientation]") {
    const auto constant = sim::make_constant_orientation(numeric::Keyframed{0.7});
    CHECK(angle_at(*constant, 10, 20) == Approx(0.7f));
    numeric::Keyframed turning;
    turning.keys = {{0.0, 0.0}, {2.0, 1.0}};
    CHECK(angle_at(*sim::make_constant_orientation(turning), 0, 0, 1.0) == Approx(0.5f));

    const auto radial = sim::make_radial_orientation(numeric::Keyframed{10.0}, numeric::Keyframed{20.0});
    CHECK(angle_at(*radial, 20, 20) == Approx(0.0f).margin(1e-7));
    CHECK(angle_at(*radial, 10, 30) == Approx(kPi / 2));
    CHECK(angle_at(*radial, 10, 20) == 0.0f);  // the centre itself
    const auto ccw =
        sim::make_circular_orientation(numeric::Keyframed{10.0}, numeric::Keyframed{20.0}, false);
    const auto cw =
        sim::make_circular_orientation(numeric::Keyframed{10.0}, numeric::Keyframed{20.0}, true);
    CHECK(angle_at(*ccw, 20, 20) == Approx(kPi / 2));
    CHECK(angle_at(*cw, 20, 20) == Approx(-kPi / 2));

    // Polyline: the nearest segment's direction; smoothed across the vertex.
    const auto poly = sim::make_polyline_orientation({{0, 0}, {100, 0}, {100, 100}}, 0.0);
    CHECK(angle_at(*poly, 50, -5) == Approx(0.0f).margin(1e-7));
    CHECK(angle_at(*poly, 105, 60) == Approx(kPi / 2));
    const auto smooth = sim::make_polyline_orientation({{0, 0}, {100, 0}, {100, 100}}, 20.0);
    const double at_corner = angle_at(*smooth, 110, -10);  // equidistant: halfway, 45 degrees
    CHECK(at_corner == Approx(kPi / 4).margin(1e-6));
    CHECK(angle_at(*smooth, 20, -3) == Approx(0.0f).margin(1e-3));  // far from the other segment
    CHECK_THROWS_AS(sim::make_polyline_orientation({{0, 0}}, 0.0), impulse::ValueError);
    CHECK_THROWS_AS(sim::make_polyline_orientation({{0, 0}, {0, 0}}, 0.0), impulse::ValueError);

    // Sine curves w = A sin(2 pi u / L + phase) along direction `angle` through `origin`.
    const double A = 10.0, L = 100.0;
    const auto sine = sim::make_sine_orientation(A, L, 0.0, 0.0, 0.0, 0.0);
    CHECK(angle_at(*sine, 0, 37) == Approx(std::atan(2 * kPi * A / L)));  // the tangent at u = 0
    CHECK(angle_at(*sine, 25, -3) == Approx(0.0f).margin(1e-6));          // a crest
    CHECK(angle_at(*sine, 50, 0) == Approx(-std::atan(2 * kPi * A / L)));
    const auto tilted = sim::make_sine_orientation(A, L, 0.0, kPi / 2, 5.0, 0.0);
    CHECK(angle_at(*tilted, 5.0, 25.0) == Approx(kPi / 2));  // a crest of the rotated family

    // Angles beyond +-64 rad are wrapped into [-pi, pi] before they become a float theta: 1e300
    // rad had become an infinite theta, and the renderer crashed on its cosine.
    for (double a : {1e300, -1e300, 1e10, 100.0}) {
        const float th = angle_at(*sim::make_constant_orientation(numeric::Keyframed{a}), 0, 0);
        CHECK(th == static_cast<float>(std::remainder(a, 2.0 * kPi)));
        CHECK(std::abs(th) <= kPi + 1e-6);
        CHECK(std::isfinite(angle_at(*sim::make_sine_orientation(A, L, 0.0, a, 0.0, 0.0), 3, 4)));
    }
    CHECK(angle_at(*sim::make_constant_orientation(numeric::Keyframed{60.0}), 0, 0) == 60.0f);
}

TEST_CASE("orientation fields: sampled angles and directions", "[sim][orientation]") {
    sim::OrientationGrid g;
    g.width = 2, g.height = 1, g.channels = 1;
    g.values = {0.0f, static_cast<float>(kPi / 2)};
    g.spacing = 10.0;
    const auto f = sim::make_grid_orientation(g);
    CHECK(angle_at(*f, 5, 5) == Approx(0.0f).margin(1e-7));  // pixel (0, 0) centre
    CHECK(angle_at(*f, 15, 5) == Approx(kPi / 2));
    CHECK(angle_at(*f, 10, 5) == Approx(kPi / 4));             // unit vectors interpolated
    CHECK(angle_at(*f, -50, 5) == Approx(0.0f).margin(1e-7));  // clamped at the edge
    sim::OrientationGrid d = g;
    d.channels = 2;
    d.values = {1.0f, 0.0f, 0.0f, -2.0f};  // direction (x, y)
    const auto fd = sim::make_grid_orientation(d);
    CHECK(angle_at(*fd, 15, 5) == Approx(-kPi / 2));
    d.channels = 3;
    CHECK_THROWS_AS(sim::make_grid_orientation(d), impulse::ValueError);
    d.channels = 2;
    d.values[3] = std::numeric_limits<float>::quiet_NaN();
    CHECK_THROWS_WITH(sim::make_grid_orientation(d),
                      Catch::Contains("expected finite values, found nan at pixel (1, 0)"));
    // the same for image flows (a NaN velocity crashed the simulator)
    sim::VectorGrid v;
    v.width = 2, v.height = 2;
    v.vx = {1.0f, 1.0f, 1.0f, 1.0f}, v.vy = {0.0f, 0.0f, std::numeric_limits<float>::infinity(), 0.0f};
    CHECK_THROWS_WITH(sim::make_grid_flow(v, 1.0),
                      Catch::Contains("expected finite velocities, found (1, inf) at pixel (0, 1)"));
    v.vy[2] = 0.0f;
    CHECK_NOTHROW(sim::make_grid_flow(v, 1.0));
    v.vx.pop_back();
    CHECK_THROWS_AS(sim::make_grid_flow(v, 1.0), impulse::ValueError);
}

TEST_CASE("orientation fields in the simulator: current positions and jitter and random access",
          "[sim][orientation][determinism]") {
    sim::ProcessConfig c;
    c.seed = 3;
    c.cell_size = 16.0;
    c.intensity = 16.0 / (kPi * 256.0);
    c.lifetime_s = 2.0;
    c.orientation = sim::OrientationMode::Field;
    c.orientation_field = sim::make_radial_orientation(numeric::Keyframed{0.0}, numeric::Keyframed{0.0});
    auto flow = std::shared_ptr<sim::Flow>(
        sim::make_vortex_flow(sim::VortexModel::LambOseen, numeric::Keyframed{0.0}, numeric::Keyframed{0.0},
                              numeric::Keyframed{3000.0}, 30.0));
    const numeric::Box view{-100, -100, 100, 100};
    sim::Impulses seq, rnd;
    {
        sim::LayerSimulator s(c, flow, {}, 16.0);
        for (int f = 0; f <= 20; ++f) s.impulses_at(f, view, seq);
    }
    sim::LayerSimulator s2(c, flow, {}, 16.0);
    s2.impulses_at(20, view, rnd);
    REQUIRE(seq.size() > 100);
    REQUIRE(seq.size() == rnd.size());
    CHECK(std::memcmp(seq.theta.data(), rnd.theta.data(), seq.size() * sizeof(float)) == 0);
    // theta is the field at the particle's position now (it has moved with the vortex)
    for (size_t i = 0; i < seq.size(); ++i)
        CHECK(seq.theta[i] == static_cast<float>(std::atan2(seq.y[i], seq.x[i])));

    // Jitter: within +-jitter of the field, fixed per particle, different between particles.
    c.orientation_jitter = 0.3;
    sim::LayerSimulator s3(c, flow, {}, 16.0);
    sim::Impulses jit;
    s3.impulses_at(20, view, jit);
    REQUIRE(jit.size() == seq.size());
    double spread = 0.0;
    for (size_t i = 0; i < jit.size(); ++i) {
        const double d = std::remainder(double(jit.theta[i]) - seq.theta[i], 2.0 * kPi);
        CHECK(std::abs(d) <= 0.3 + 1e-6);
        spread += d * d;
    }
    // uniform on [-0.3, 0.3): sd 0.3 / sqrt(3) = 0.173
    CHECK(std::sqrt(spread / double(jit.size())) == Approx(0.3 / std::sqrt(3.0)).epsilon(0.15));

    // A huge jitter gives finite thetas in [-pi, pi] (it gave infinities, and a crash).
    c.orientation_jitter = 1e300;
    sim::LayerSimulator s4(c, flow, {}, 16.0);
    s4.impulses_at(20, view, jit);
    REQUIRE(jit.size() == seq.size());
    for (float th : jit.theta) CHECK(std::abs(th) <= kPi + 1e-6);
}

TEST_CASE("orientation modes: only vorticity integrates the spin", "[sim][orientation]") {
    // A Lamb–Oseen vortex, circulation G = 20000, core 40: vorticity w = w0 exp(-r^2/rc^2) with
    // w0 = G / (pi rc^2) = 3.98/s, so d theta/dt = w/2 turns a kernel near the core by up to
    // w0/2 * T = 3.98 rad over its T = 2 s life. `fixed` must stay at 0 and `random` at its birth
    // angle in [0, 2 pi) (the old behaviour, integrating the spin in every mode, fails both).
    sim::ProcessConfig c;
    c.seed = 8;
    c.cell_size = 16.0;
    c.intensity = 16.0 / (kPi * 256.0);
    c.lifetime_s = 2.0;
    auto flow = std::shared_ptr<sim::Flow>(
        sim::make_vortex_flow(sim::VortexModel::LambOseen, numeric::Keyframed{0.0}, numeric::Keyframed{0.0},
                              numeric::Keyframed{20000.0}, 40.0));
    const numeric::Box view{-60, -60, 60, 60};
    auto run = [&](sim::OrientationMode mode) {
        c.orientation = mode;
        sim::LayerSimulator s(c, flow, {}, 16.0);
        sim::Impulses out;
        s.impulses_at(90, view, out);
        REQUIRE(out.size() > 100);
        return out.theta;
    };
    const auto spun = run(sim::OrientationMode::Vorticity);
    const double w0 = 20000.0 / (kPi * 1600.0);
    CHECK(*std::min_element(spun.begin(), spun.end()) >= 0.0f);
    CHECK(*std::max_element(spun.begin(), spun.end()) <= w0 / 2 * c.lifetime_s + 1e-6);
    CHECK(*std::max_element(spun.begin(), spun.end()) > 2.0);

    const auto fixed = run(sim::OrientationMode::Fixed);
    CHECK(std::all_of(fixed.begin(), fixed.end(), [](float t) { return t == 0.0f; }));

    const auto random = run(sim::OrientationMode::Random);
    CHECK(*std::min_element(random.begin(), random.end()) >= 0.0f);
    CHECK(*std::max_element(random.begin(), random.end()) < 2.0 * kPi);
    CHECK(*std::max_element(random.begin(), random.end()) > 5.0);  // spread over [0, 2 pi)
}

// ---------------------------------------------------------------------------------------------
// (c) structure tensor

namespace {

using impulse::test::structure_tensor;

impulse::render::Frame render_scene(const std::string& text) {
    impulse::scenes::Renderer r(impulse::scenes::load_scene_string(text, "orientation.toml"));
    impulse::render::Frame f;
    r.render(0, f);
    return f;
}

/// A still 256^2 texture of elongated Gaussian kernels (aspect 4: 24 along, 6 across).
std::string streak_scene(const std::string& orientation) {
    return "[output]\nsize = [256, 256]\n[[layer]]\nseed = 21\ndensity = 16.0\norientation = " +
           orientation +
           "\n[layer.kernel]\ntype = \"gaussian\"\nradius = 24.0\nsigma = 8.0\naspect = 4.0\n";
}

struct Follow {
    double median = 0, p90 = 0;
    size_t windows = 0;
};
/// Errors between the measured orientation and `field` (texture = pixel coordinates here) over
/// the windows that `use` accepts.
Follow follow(const impulse::render::Frame& f, const std::function<double(double, double)>& field,
              const std::function<bool(double, double)>& use, int win = 32) {
    std::vector<double> err;
    for (const auto& e : structure_tensor(f, win))
        if (use(e.cx, e.cy)) err.push_back(orientation_error_deg(e.angle, field(e.cx, e.cy)));
    std::sort(err.begin(), err.end());
    Follow r;
    r.windows = err.size();
    if (err.empty()) return r;
    r.median = err[err.size() / 2];
    r.p90 = err[std::min(err.size() - 1, err.size() * 9 / 10)];
    return r;
}

}  // namespace

TEST_CASE(
    "orientation (c): the measured local orientation follows constant and circular and "
    "image fields within 5 degrees",
    "[sim][orientation][stats]") {
    // Windows of 32 x 32 px hold about 9 kernel areas: the structure tensor's angle has a
    // sampling scatter of a few degrees per window, so the median error over the windows is
    // compared with 5 degrees, and a field rotated by 15 degrees must fail the same criterion.
    auto all = [](double, double) { return true; };
    std::ostringstream log;

    const auto fc = render_scene(streak_scene("{ type = \"constant\", angle = 0.7 }"));
    const auto c_ok = follow(
        fc, [](double, double) { return 0.7; }, all);
    const auto c_bad = follow(
        fc, [](double, double) { return 0.7 + 15.0 * kPi / 180.0; }, all);
    log << "constant: median " << c_ok.median << " deg, 90 % " << c_ok.p90 << " over "
        << c_ok.windows << " windows (rotated 15 deg: median " << c_bad.median << ")\n";
    CHECK(c_ok.median <= 5.0);
    CHECK(c_bad.median > 5.0);

    // Circular around the centre; windows whose centre is within 48 px of it are left out (the
    // field turns by more than the window's width / radius there).
    const auto fr = render_scene(streak_scene("{ type = \"circular\", center = [128.0, 128.0] }"));
    auto circ = [](double x, double y) { return std::atan2(y - 128.0, x - 128.0) + 0.5 * kPi; };
    auto away = [](double x, double y) { return std::hypot(x - 128.0, y - 128.0) > 48.0; };
    const auto r_ok = follow(fr, circ, away);
    const auto r_bad = follow(
        fr, [&](double x, double y) { return circ(x, y) + 15.0 * kPi / 180.0; }, away);
    log << "circular: median " << r_ok.median << " deg, 90 % " << r_ok.p90 << " over "
        << r_ok.windows << " windows (rotated 15 deg: median " << r_bad.median << ")\n";
    CHECK(r_ok.median <= 5.0);
    CHECK(r_bad.median > 5.0);

    // An angle image (1 channel, radians; EXR), one pixel per texture unit.
    const fs::path dir = temp_dir();
    impulse::render::Frame img;
    img.resize(256, 256);
    auto wave = [](double x, double y) {
        return 0.3 + 0.8 * std::sin(2.0 * kPi * (x + 0.5 * y) / 256.0);
    };
    for (int j = 0; j < 256; ++j)
        for (int i = 0; i < 256; ++i)
            img.data[size_t(j) * 256 + i] = static_cast<float>(wave(i + 0.5, j + 0.5));
    const fs::path path = dir / "angles.exr";
    impulse::output::write_image(path.string(), img, {0.0, 1.0}, {});
    const auto fi =
        render_scene(streak_scene("{ type = \"image\", path = \"" + path.string() + "\" }"));
    const auto i_ok = follow(fi, wave, all);
    const auto i_bad = follow(
        fi, [&](double x, double y) { return wave(x, y) + 15.0 * kPi / 180.0; }, all);
    log << "image: median " << i_ok.median << " deg, 90 % " << i_ok.p90 << " over " << i_ok.windows
        << " windows (rotated 15 deg: median " << i_bad.median << ")\n";
    CHECK(i_ok.median <= 5.0);
    CHECK(i_bad.median > 5.0);
    WARN("orientation (c):\n" << log.str());
    fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Scene keys and errors

TEST_CASE("orientation scene keys: modes and fields and one-line errors",
          "[sim][orientation][scenes][errors]") {
    using impulse::scenes::load_scene_string;
    auto scene = [](const std::string& orientation) {
        return "[[layer]]\nseed = 1\norientation = " + orientation +
               "\n[layer.kernel]\nradius = 8.0\n";
    };
    auto error_of = [&](const std::string& orientation) {
        try {
            load_scene_string(scene(orientation), "o.toml");
        } catch (const impulse::SceneError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    // The string modes still work; the same names as table types.
    CHECK(load_scene_string(scene("\"random\""), "o.toml").layers[0].process.orientation ==
          sim::OrientationMode::Random);
    CHECK(load_scene_string(scene("{ type = \"flow\" }"), "o.toml").layers[0].process.orientation ==
          sim::OrientationMode::Flow);
    const auto s = load_scene_string(
        scene("{ type = \"sine\", amplitude = 8.0, wavelength = 64.0, jitter = 0.1 }"), "o.toml");
    CHECK(s.layers[0].process.orientation == sim::OrientationMode::Field);
    CHECK(s.layers[0].process.orientation_jitter.value(0.0) == 0.1);
    REQUIRE(s.layers[0].process.orientation_field);
    CHECK(load_scene_string(
              scene("{ type = \"polyline\", points = [[0.0, 0.0], [10.0, 5.0]], smooth = 4.0 }"),
              "o.toml")
              .layers[0]
              .process.orientation_field);

    CHECK(error_of("{ type = \"spiral\" }") ==
          "o.toml:3:24: layer[0].orientation.type = \"spiral\": expected one of constant, radial, "
          "circular, polyline, sine, image, fixed, random, flow, vorticity, layer");
    CHECK_THAT(error_of("{ type = \"circular\" }"),
               Contains("layer[0].orientation.center: missing"));
    CHECK_THAT(error_of("{ type = \"polyline\", points = [[0.0, 0.0]] }"),
               Contains("layer[0].orientation.points = [[0, 0]]: expected at least two"));
    CHECK_THAT(
        error_of("{ type = \"sine\", wavelength = 0.0 }"),
        Contains("layer[0].orientation.wavelength = 0") && Contains("expected a wavelength > 0"));
    CHECK_THAT(error_of("{ type = \"constant\", angel = 1.0 }"),
               Contains("unknown key \"angel\"") && Contains("did you mean \"angle\"?"));
    CHECK_THAT(error_of("12"), Contains("layer[0].orientation = 12: expected a mode"));
    // Images: missing file, wrong channel count.
    const fs::path dir = temp_dir();
    const std::string missing = (dir / "nope.exr").string();
    const std::string e1 = error_of("{ type = \"image\", path = \"" + missing + "\" }");
    CHECK_THAT(e1, Contains("o.toml:3:") &&
                       Contains("layer[0].orientation.path = \"" + missing + "\": cannot read"));
    CHECK(e1.find('\n') == std::string::npos);
    const fs::path rgb = dir / "rgb.png";
    impulse::output::write_rgb_image(rgb.string(), 4, 4, std::vector<float>(48, 0.5f), {});
    CHECK_THAT(error_of("{ type = \"image\", path = \"" + rgb.string() + "\" }"),
               Contains("layer[0].orientation.path = \"" + rgb.string() +
                        "\": expected an image with 1 channel (angle in radians) or 2 (direction "
                        "x, y), found 3"));
    fs::remove_all(dir);
}
