// SPDX-License-Identifier: Apache-2.0
// [[layer.flow]] type = "sequence" (docs/scenes.md "Velocity sequences"): velocity sequences
// written here as OpenVDB files and as EXR images with named channels, read back as flows.
// - a sampled copy of an analytic flow (a vortex whose circulation grows in time, a uniform
//   wind, a uniform divergence) moves points within the bound derived from the interpolation
//   error (bilinear: h^2/8 (max|f_xx| + max|f_yy|), Gronwall along the path);
// - the divergence is the interpolant's own, so sqrt(J) keeps the frame variance stationary
//   under the sampled divergent source, and without it the variance falls (design.md §1, §5);
// - each bad input of a sequence gives one line naming the file and the key.

#include <OpenImageIO/imageio.h>
#include <tbb/task_arena.h>
#include <openvdb/openvdb.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <span>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "analysis/analysis.h"
#include "numeric/errors.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "scenes/volume_scene.h"
#include "sim/sim.h"
#include "volume/volume.h"

using namespace impulse;
namespace fs = std::filesystem;

namespace {

constexpr double kPi = std::numbers::pi;
using Vec2 = std::array<double, 2>;
/// An analytic field v(x, y, t) in texture units per second.
using Field = std::function<Vec2(double x, double y, double t)>;

/// A directory of its own under the system's temporary directory, removed at the end.
struct TempDir {
    fs::path path;
    explicit TempDir(const std::string& name)
        : path(fs::temp_directory_path() / ("impulse_seq_" + name + "_" + std::to_string(getpid()))) {
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

std::string frame_file(const std::string& stem, int n, const std::string& ext) {
    char b[32];
    std::snprintf(b, sizeof b, "%04d", n);
    return stem + b + ext;
}

/// Frame n of a VDB sequence: a vec3s grid `velocity` (and a float grid `density`, so the
/// velocity is found among grids of other types) of W x H x D voxels of size `voxel`, voxel
/// (i, j, k) at world voxel (i, j, k); v(x, y) at z does not depend on z.
void write_vdb(const fs::path& file, int W, int H, int D, double voxel,
               const std::function<Vec2(double, double)>& v) {
    openvdb::initialize();
    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    vel->setName("velocity");
    vel->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    auto acc = vel->getAccessor();
    auto dacc = density->getAccessor();
    for (int k = 0; k < D; ++k)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const Vec2 u = v(voxel * i, voxel * j);
                acc.setValue({i, j, k}, openvdb::Vec3s(float(u[0]), float(u[1]), 0.25f));
                dacc.setValue({i, j, k}, 1.0f);
            }
    openvdb::io::File out(file.string());
    out.write({density, vel});
    out.close();
}

/// Frame n of an EXR sequence: channels vel.x, vel.y, density; pixel (i, j) holds v at the
/// pixel's centre (i + 0.5, j + 0.5) in pixel units.
void write_exr(const fs::path& file, int W, int H, const std::function<Vec2(double, double)>& v) {
    OIIO::ImageSpec spec(W, H, 3, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"density", "vel.x", "vel.y"};
    std::vector<float> px(size_t(W) * H * 3);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const Vec2 u = v(i + 0.5, j + 0.5);
            float* p = &px[(size_t(j) * W + i) * 3];
            p[0] = 1.0f, p[1] = float(u[0]), p[2] = float(u[1]);
        }
    auto out = OIIO::ImageOutput::create(file.string());
    REQUIRE(out);
    REQUIRE(out->open(file.string(), spec));
    REQUIRE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    out->close();
}

/// Frames 1..frames of `field` at 4 frames a second (frame n at t = (n - 1) / 4), the texture
/// being the simulation's world (VDB: voxel 4, 65 x 65 x 3; EXR: 64 x 64 pixels of 4 units).
void write_sequence(const fs::path& dir, bool vdb, int frames, const Field& field) {
    for (int n = 1; n <= frames; ++n) {
        const double t = (n - 1) / 4.0;
        if (vdb) {
            write_vdb(dir / frame_file("fluid_data_", n, ".vdb"), 65, 65, 3, 4.0,
                      [&](double x, double y) { return field(x, y, t); });
        } else {
            // pixel units: x = 4 a, v_texture = 4 v_pixel
            write_exr(dir / frame_file("vel_", n, ".exr"), 64, 64, [&](double a, double b) {
                const Vec2 u = field(4.0 * a, 4.0 * b, t);
                return Vec2{u[0] / 4.0, u[1] / 4.0};
            });
        }
    }
}

/// The [[layer.flow]] table reading write_sequence's frames as texture space.
std::string sequence_table(bool vdb, const std::string& extra = "") {
    std::ostringstream s;
    s << "[[layer.flow]]\ntype = \"sequence\"\nfps = 4\n";
    if (vdb) s << "path = \"fluid_data_####.vdb\"\n";
    else s << "path = \"vel_####.exr\"\nscale = 4.0\n";
    s << extra;
    return s.str();
}

std::string scene_text(const std::string& flows, bool jacobian = true, int size = 128) {
    std::ostringstream t;
    t << "[output]\nsize = [" << size << ", " << size << "]\nfps = 12\nframes = 2000\n\n"
      << "[[layer]]\nseed = 31\ndensity = 16.0\namplitude = \"normal\"\nlifetime = 2.0\n"
      << "substeps = 2\njacobian = " << (jacobian ? "true" : "false")
      << "\n[layer.kernel]\ntype = \"cosine\"\nradius = 6.0\n\n"
      << flows;
    return t.str();
}

scenes::Scene load_in(const fs::path& dir, const std::string& text) {
    const fs::path file = dir / "scene.toml";
    std::ofstream(file) << text;
    return scenes::load_scene(file.string());
}

/// RK4 paths of `n` points through `flow` from t0 over `seconds` in steps of dt.
std::vector<Vec2> paths(const sim::Flow& flow, std::vector<Vec2> p, double t0, double seconds,
                        double dt) {
    const size_t n = p.size();
    std::vector<double> x(n), y(n), vx(n), vy(n);
    auto eval = [&](const std::vector<Vec2>& q, double t, std::vector<Vec2>& k) {
        for (size_t i = 0; i < n; ++i) x[i] = q[i][0], y[i] = q[i][1], vx[i] = vy[i] = 0.0;
        flow.add(t, n, x.data(), y.data(), vx.data(), vy.data(), nullptr, nullptr);
        for (size_t i = 0; i < n; ++i) k[i] = {vx[i], vy[i]};
    };
    std::vector<Vec2> k1(n), k2(n), k3(n), k4(n), q(n);
    const int steps = int(std::lround(seconds / dt));
    for (int s = 0; s < steps; ++s) {
        const double t = t0 + s * dt;
        auto stage = [&](const std::vector<Vec2>& k, double f) {
            for (size_t i = 0; i < n; ++i) q[i] = {p[i][0] + f * dt * k[i][0], p[i][1] + f * dt * k[i][1]};
        };
        eval(p, t, k1), stage(k1, 0.5), eval(q, t + 0.5 * dt, k2), stage(k2, 0.5);
        eval(q, t + 0.5 * dt, k3), stage(k3, 1.0), eval(q, t + dt, k4);
        for (size_t i = 0; i < n; ++i)
            for (int c = 0; c < 2; ++c)
                p[i][size_t(c)] += dt / 6.0 * (k1[i][size_t(c)] + 2 * k2[i][size_t(c)] + 2 * k3[i][size_t(c)] + k4[i][size_t(c)]);
    }
    return p;
}

/// The bound on |x_sampled(T) - x_analytic(T)| of paths in a field sampled on a grid of spacing
/// h and interpolated bilinearly (linear in time, exact for a field linear in t): the velocity
/// error is at most eps = h^2/8 (max|v_xx| + max|v_yy|) per component (the bilinear error
/// bound for a C^2 function) plus float storage (2^-24 max|v|), so |error| <= sqrt(2) eps; two
/// paths whose fields differ by at most e and whose Lipschitz constant is L part by at most
/// e (exp(L T) - 1) / L (Gronwall). The maxima are taken over `box` at the frames' times by
/// central differences of step h/8 (their own error is O(h^2/64) of the fourth derivative).
double path_bound(const Field& f, const std::array<double, 4>& box, double h, double T, int frames) {
    double vxx = 0, vyy = 0, L = 0, vmax = 0;
    const double d = h / 8.0;
    for (int n = 0; n < frames; ++n) {
        const double t = n / 4.0;
        for (double x = box[0]; x <= box[2]; x += d)
            for (double y = box[1]; y <= box[3]; y += d) {
                const Vec2 c = f(x, y, t), xp = f(x + d, y, t), xm = f(x - d, y, t);
                const Vec2 yp = f(x, y + d, t), ym = f(x, y - d, t);
                for (int k = 0; k < 2; ++k) {
                    vxx = std::max(vxx, std::abs(xp[size_t(k)] - 2 * c[size_t(k)] + xm[size_t(k)]) / (d * d));
                    vyy = std::max(vyy, std::abs(yp[size_t(k)] - 2 * c[size_t(k)] + ym[size_t(k)]) / (d * d));
                }
                const double a = (xp[0] - xm[0]) / (2 * d), b = (yp[0] - ym[0]) / (2 * d);
                const double cc = (xp[1] - xm[1]) / (2 * d), dd = (yp[1] - ym[1]) / (2 * d);
                L = std::max(L, std::sqrt(a * a + b * b + cc * cc + dd * dd));  // >= the 2-norm
                vmax = std::max(vmax, std::hypot(c[0], c[1]));
            }
    }
    const double eps = h * h / 8.0 * (vxx + vyy) + std::ldexp(vmax, -24);
    return std::sqrt(2.0) * eps * std::expm1(L * T) / L;
}

/// Lamb-Oseen vortex round (128, 128), core 30, circulation growing linearly in time
/// 4000 -> 6000 over 2 s (so linear interpolation in time is exact).
Vec2 vortex(double x, double y, double t) {
    const double G = 4000.0 + 1000.0 * t, rc = 30.0;
    const double dx = x - 128.0, dy = y - 128.0, r2 = dx * dx + dy * dy;
    const double k = r2 > 0 ? G / (2 * kPi * r2) * -std::expm1(-r2 / (rc * rc)) : 0.0;
    return {-k * dy, k * dx};
}

}  // namespace

TEST_CASE("sequence: a sampled vortex moves points within the interpolation bound of the analytic paths",
          "[scenes][sequence]") {
    // The analytic twin: sim's vortex with the same keyframed circulation.
    numeric::Keyframed G;
    G.keys = {{0.0, 4000.0}, {2.0, 6000.0}};
    auto analytic = sim::make_vortex_flow(sim::VortexModel::LambOseen, 128.0, 128.0, G, 30.0);
    std::vector<Vec2> start;
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j < 9; ++j) start.push_back({68.0 + 15.0 * i, 68.0 + 15.0 * j});
    const double T = 1.5;
    const auto exact = paths(*analytic, start, 0.25, T, 1.0 / 480.0);
    // paths stay within 100 units of the centre (speed < 33 u/s: the bound's box holds them)
    const double bound = path_bound(vortex, {20.0, 20.0, 236.0, 236.0}, 4.0, T, 9);
    auto worst_distance = [&](const fs::path& dir, const std::string& table) {
        const scenes::Scene s = load_in(dir, scene_text(table));
        const auto sampled = paths(*s.layers[0].flow, start, 0.25, T, 1.0 / 480.0);
        double worst = 0.0;
        for (size_t i = 0; i < start.size(); ++i)
            worst = std::max(worst, std::hypot(sampled[i][0] - exact[i][0], sampled[i][1] - exact[i][1]));
        return worst;
    };
    for (bool vdb : {true, false}) {
        TempDir dir(vdb ? "vortex_vdb" : "vortex_exr");
        write_sequence(dir.path, vdb, 9, vortex);
        const double worst = worst_distance(dir.path, sequence_table(vdb));
        INFO((vdb ? "VDB" : "EXR") << ": worst distance " << worst << ", bound " << bound);
        CHECK(worst <= bound);
        CHECK(worst > 0.0);  // the field is sampled, not the analytic one
        // The check can fail: the same frames laid half a voxel off the analytic field.
        const double shifted = worst_distance(dir.path, sequence_table(vdb, "offset = [2.0, 2.0]\n"));
        INFO("half a voxel off: worst distance " << shifted);
        CHECK(shifted > bound);
    }
}

TEST_CASE("sequence: transform, time mapping and the domain's outside", "[scenes][sequence]") {
    TempDir dir("uniform");
    // a wind (3, 1) pixels/s until frame 2, then (1, -2): linear in time between frames
    for (int n = 1; n <= 3; ++n)
        write_exr(dir.path / frame_file("vel_", n, ".exr"), 8, 8, [&](double, double) {
            return n == 1 ? Vec2{3.0, 1.0} : Vec2{1.0, -2.0};
        });
    auto flow_at = [&](const std::string& keys, double x, double y, double t, double* div = nullptr) {
        const scenes::Scene s = load_in(dir.path, scene_text(
            "[[layer.flow]]\ntype = \"sequence\"\npath = \"vel_####.exr\"\n" + keys));
        double vx = 0, vy = 0, d = 0, c = 0;
        s.layers[0].flow->add(t, 1, &x, &y, &vx, &vy, &d, &c);
        if (div) *div = d;
        return Vec2{vx, vy};
    };
    // fps 2, start 1: frame 1 at t = 0, frame 2 at 0.5 s; halfway, the mean of the two
    Vec2 v = flow_at("fps = 2\n", 4.0, 4.0, 0.25);
    CHECK(v[0] == Approx(2.0).margin(1e-12));
    CHECK(v[1] == Approx(-0.5).margin(1e-12));
    // time_scale 0.5: the simulation runs at half speed, its velocities halve
    v = flow_at("fps = 2\ntime_scale = 0.5\n", 4.0, 4.0, 0.5);
    CHECK(v[0] == Approx(1.0).margin(1e-12));
    CHECK(v[1] == Approx(-0.25).margin(1e-12));
    // scale 2 and a quarter turn: (3, 1) px/s -> 2 (-1, 3); the grid covers texture
    // offset + R [1, 15]^2 = [-15, -1] x [1, 15] for offset 0
    v = flow_at("fps = 2\nscale = 2.0\nrotation = 1.5707963267948966\n", -8.0, 8.0, 0.0);
    CHECK(v[0] == Approx(-2.0).margin(1e-9));
    CHECK(v[1] == Approx(6.0).margin(1e-9));
    // outside: zero by default, the edge's value with clamp; a uniform field has div 0
    double div = 1.0;
    v = flow_at("fps = 2\n", 40.0, 4.0, 0.0, &div);
    CHECK(v[0] == 0.0);
    v = flow_at("fps = 2\noutside = \"clamp\"\n", 40.0, 4.0, 0.0, &div);
    CHECK(v[0] == Approx(3.0).margin(1e-12));
    CHECK(div == 0.0);
    // start 3: the last frame from t = 0 on (held after the end)
    v = flow_at("fps = 2\nstart = 3\n", 4.0, 4.0, 5.0);
    CHECK(v[0] == Approx(1.0).margin(1e-12));
}

TEST_CASE("sequence: the divergence is the interpolant's, for sqrt(J)", "[scenes][sequence]") {
    // v = 0.125 (x - c): bilinear interpolation reproduces a linear field, so the interpolant's
    // divergence is 0.25/s up to float storage; a vortex's (divergence-free) interpolant
    // diverges by O(h^2) only.
    TempDir dir("divergence");
    write_sequence(dir.path, true, 2, [](double x, double y, double) {
        return Vec2{0.125 * (x - 128.0), 0.125 * (y - 128.0)};
    });
    const scenes::Scene s = load_in(dir.path, scene_text(sequence_table(true)));
    std::vector<double> x, y;
    for (int i = 0; i < 50; ++i) x.push_back(3.0 + 5.1 * i), y.push_back(250.0 - 4.9 * i);
    std::vector<double> vx(x.size()), vy(x.size()), div(x.size()), curl(x.size());
    s.layers[0].flow->add(0.1, x.size(), x.data(), y.data(), vx.data(), vy.data(), div.data(), curl.data());
    for (size_t i = 0; i < x.size(); ++i) {
        CHECK(div[i] == Approx(0.25).margin(1e-6));  // float samples of |v| <= 16: 2e-6 / 4 units
        CHECK(curl[i] == Approx(0.0).margin(1e-6));
    }
    // jacobian = false is refused where the field diverges
    try {
        load_in(dir.path, scene_text(sequence_table(true), false));
        FAIL("jacobian = false loaded");
    } catch (const SceneError& e) {
        const std::string m = e.what();
        CHECK(m.find("layer[0].jacobian = false: the velocity sequence diverges") != std::string::npos);
        CHECK(m.find("fluid_data_0001.vdb") != std::string::npos);
    }
}

TEST_CASE("sequence: a frame is the same in order, out of order and on one thread", "[scenes][sequence]") {
    // design.md §4: frame 7 after frames 0-6 (the frames held move along, the next is read
    // ahead) and frame 7 alone (every frame it needs read on demand) give the same bits.
    TempDir dir("order");
    write_sequence(dir.path, true, 9, vortex);
    const std::string text = scene_text(sequence_table(true, "interpolation = \"cubic\"\n"), true, 64) +
                             "[camera]\ncenter = [128.0, 128.0]\n";
    render::Frame in_order, alone, one_thread;
    {
        scenes::Renderer r(load_in(dir.path, text));
        for (int f = 0; f <= 7; ++f) r.render(f, in_order);
    }
    scenes::Renderer(load_in(dir.path, text)).render(7, alone);
    tbb::task_arena one(1);
    one.execute([&] { scenes::Renderer(load_in(dir.path, text)).render(7, one_thread); });
    CHECK(in_order.data == alone.data);
    CHECK(in_order.data == one_thread.data);
    // What the frames in use may hold, for limits.max_memory_mib (docs/scenes.md): a 2 s
    // lifetime at 4 frames a second spans 8 frames, plus one for the step before, four for
    // Catmull-Rom: 13, at most the 9 of the sequence, and the one read ahead; 65 x 65 samples
    // of two floats each.
    const scenes::Scene s = load_in(dir.path, text);
    CHECK(s.layers[0].flow->cache_bytes({0.0, 0.0, 1.0, 1.0}) == 10.0 * 65 * 65 * 8);
}

namespace {

/// The frame variance of `count` frames of `scene` rendered in order.
std::vector<double> frame_variances(scenes::Scene scene, int count) {
    scenes::Renderer renderer(std::move(scene));
    render::Frame frame;
    std::vector<double> v;
    for (int i = 0; i < count; ++i) {
        renderer.render(i, frame);
        const analysis::Image im{frame.width, frame.height, frame.data};
        v.push_back(analysis::frame_stats(std::span(&im, 1)).back().variance);
    }
    return v;
}

struct Blocks {
    double mean = 0, se = 0;
};
/// Run mean of a series and its standard error from the scatter of `blocks` block means
/// (blocks of two lifetimes, nearly independent: tests/sim/test_motion_stats.cpp).
Blocks blocks_of(const std::vector<double>& s, int blocks) {
    const auto m = analysis::block_means(s, blocks);
    Blocks b;
    for (double x : m) b.mean += x / blocks;
    double ss = 0;
    for (double x : m) ss += (x - b.mean) * (x - b.mean);
    b.se = std::sqrt(ss / (blocks - 1) / blocks);
    return b;
}

}  // namespace

TEST_CASE("sequence: a sampled divergent source keeps the frame variance only with sqrt(J)",
          "[scenes][sequence][stats][slow]") {
    // The uniform divergence of tests/sim/test_motion_stats.cpp case a, v = 0.125 (x - c),
    // div 0.25/s, as a VDB sequence over [0, 256]^2 round the 128^2 view at [64, 192]^2
    // (particles born within the view's reach stay inside the grid for a lifetime). Without
    // sqrt(J) the variance is int w^2 e^{-0.25 a} da / int w^2 ~ 0.78 of the still field's. 480
    // frames at 12 fps = 20 lifetimes in 10 blocks of 2 lifetimes; the run means of the flow and
    // of a still run differ by t = d / sqrt(se1^2 + se2^2), ~ t with ~18 degrees of freedom:
    // P(|t| > 5) = 1e-4.
    TempDir dir("stationary");
    write_sequence(dir.path, true, 2, [](double x, double y, double) {
        return Vec2{0.125 * (x - 128.0), 0.125 * (y - 128.0)};
    });
    const std::string view = "[camera]\ncenter = [128.0, 128.0]\n";
    constexpr int kFrames = 480, kBlocks = 10;
    const Blocks still = blocks_of(frame_variances(load_in(dir.path, scene_text("") + view), kFrames), kBlocks);
    for (bool jacobian : {true, false}) {
        scenes::Scene s = load_in(dir.path, scene_text(sequence_table(true)) + view);
        s.layers[0].process.jacobian = jacobian;  // the loader refuses false: switched off here
        const Blocks b = blocks_of(frame_variances(std::move(s), kFrames), kBlocks);
        const double t = (b.mean - still.mean) / std::hypot(b.se, still.se);
        INFO("jacobian " << jacobian << ": mean variance " << b.mean << " vs still " << still.mean
                         << ", t = " << t);
        if (jacobian)
            CHECK(std::abs(t) < 5.0);
        else
            CHECK(t < -5.0);
    }
}

TEST_CASE("sequence: writes the error corpus's sequences", "[.generate]") {
    // Run by hand (test_scenes "[.generate]") to remake tests/scenes/errors/sequences/, the
    // files the corpus's sequence scenes read (tests/scenes/errors/1*_sequence_*.toml), and
    // data/sequences/.
    const fs::path root = fs::path(IMPULSE_SOURCE_DIR) / "tests" / "scenes" / "errors" / "sequences";
    auto wind = [](double, double) { return Vec2{1.0, 0.5}; };
    for (const char* d : {"gap", "sizes", "nan", "scalar", "grids", "div"}) fs::create_directories(root / d);
    for (int n : {1, 2, 4}) write_exr(root / "gap" / frame_file("v_", n, ".exr"), 4, 4, wind);
    write_exr(root / "sizes" / "v_0001.exr", 4, 4, wind);
    write_exr(root / "sizes" / "v_0002.exr", 5, 4, wind);
    write_exr(root / "nan" / "v_0001.exr", 4, 4, wind);
    write_exr(root / "nan" / "v_0002.exr", 4, 4, [](double a, double b) {
        return a == 2.5 && b == 1.5 ? Vec2{NAN, 0.0} : Vec2{1.0, 0.5};
    });
    {
        openvdb::initialize();
        auto density = openvdb::FloatGrid::create(0.0f);
        density->setName("density");
        for (int i = 0; i < 4; ++i) density->getAccessor().setValue({i, 0, 0}, 1.0f);
        openvdb::io::File out((root / "scalar" / "d_0001.vdb").string());
        out.write({density});
        out.close();
    }
    write_vdb(root / "grids" / "f_0001.vdb", 4, 4, 2, 1.0, wind);
    for (int n : {1, 2})
        write_vdb(root / "div" / frame_file("f_", n, ".vdb"), 4, 4, 2, 1.0, [](double x, double y) {
            return Vec2{0.5 * (x - 1.5), 0.5 * (y - 1.5)};
        });
    // data/sequences/: the example of docs/scenes.md "Velocity sequences", four frames of a
    // 16 x 16 x 4 vortex that drifts and strengthens (units: voxels per second)
    const fs::path data = fs::path(IMPULSE_SOURCE_DIR) / "data" / "sequences";
    fs::create_directories(data);
    for (int n = 1; n <= 4; ++n)
        write_vdb(data / frame_file("vortex_", n, ".vdb"), 16, 16, 4, 1.0, [n](double x, double y) {
            const double dx = x - 6.5 - 0.5 * n, dy = y - 7.5, r2 = dx * dx + dy * dy;
            const double k = (1.0 + 0.2 * n) * 8.0 * -std::expm1(-r2 / 9.0) / std::max(r2, 1e-9);
            return Vec2{-k * dy + 0.5, k * dx};
        });
}

namespace {

using Vec3 = std::array<double, 3>;

/// A VDB frame of vec3s `velocity` over voxels [lo, hi]^3 of size `voxel` (voxel (i, j, k) at
/// world voxel (i, j, k)).
void write_vdb3(const fs::path& file, int lo, int hi, double voxel,
                const std::function<Vec3(double, double, double)>& v) {
    openvdb::initialize();
    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    vel->setName("velocity");
    vel->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    auto acc = vel->getAccessor();
    for (int k = lo; k <= hi; ++k)
        for (int j = lo; j <= hi; ++j)
            for (int i = lo; i <= hi; ++i) {
                const Vec3 u = v(voxel * i, voxel * j, voxel * k);
                acc.setValue({i, j, k}, openvdb::Vec3s(float(u[0]), float(u[1]), float(u[2])));
            }
    openvdb::io::File out(file.string());
    out.write({vel});
    out.close();
}

/// A [volume] scene of one unshaped octave (48^3 voxels, cosine kernel r = 6, 8 impulses per
/// kernel volume, 1 s Hann lifetimes, 6 fps) with `flows`.
std::string volume_scene(const std::string& flows) {
    return "[output]\nfps = 6\nframes = 1000\n[volume]\nsize = [48, 48, 48]\n"
           "density = 8.0\noctaves = 1\nlifetime = 1.0\nsubsteps = 2\n"
           "[volume.kernel]\ntype = \"cosine\"\nradius = 6.0\n[volume.shape]\nenabled = false\n" +
           flows;
}

}  // namespace

TEST_CASE("sequence: a volume's sampled divergent flow is the analytic one, and keeps its variance "
          "only with sqrt(J)",
          "[scenes][sequence][volume][stats][slow]") {
    // v = 0.15 (x - c), c the middle of the 48^3 volume, sampled every 4 voxels over
    // [-40, 88]^3 (the birth region's reach: speed <= 0.15 * 64 sqrt 3 = 17 voxels/s over a 1 s
    // life): trilinear interpolation reproduces a linear field, so v and div v = 0.45/s match
    // the analytic flow up to float storage; then the frame variance test of
    // tests/volume/test_volume_stats.cpp: 40 frames a lifetime apart (independent), their mean
    // against Campbell's theorem, t with 39 degrees of freedom, |t| < 5.09 (P = 1e-5); without
    // sqrt(J) the variance falls to ~0.80 of it.
    TempDir dir("volume");
    const auto field = [](double x, double y, double z) {
        return Vec3{0.15 * (x - 24.0), 0.15 * (y - 24.0), 0.15 * (z - 24.0)};
    };
    for (int n : {1, 2}) write_vdb3(dir.path / frame_file("fluid_data_", n, ".vdb"), -10, 22, 4.0, field);
    const std::string flows = "[[volume.flow]]\ntype = \"sequence\"\npath = \"fluid_data_####.vdb\"\n";
    const scenes::Scene s = load_in(dir.path, volume_scene(flows));
    REQUIRE(s.volume);
    const auto analytic = volume::make_divergent_flow3({24.0, 24.0, 24.0}, 0.15);
    for (int p = 0; p < 40; ++p) {
        const double x = -30.0 + 2.9 * p, y = 80.0 - 2.7 * p, z = 10.0 + 0.9 * p;
        double a[4] = {0, 0, 0, 0}, b[4] = {0, 0, 0, 0};
        analytic->add(0.3, 1, &x, &y, &z, &a[0], &a[1], &a[2], &a[3]);
        s.volume->cloud.flow->add(0.3, 1, &x, &y, &z, &b[0], &b[1], &b[2], &b[3]);
        for (int c = 0; c < 3; ++c) CHECK(b[c] == Approx(a[c]).margin(2e-5));  // |v| <= 17: float 1e-6
        CHECK(b[3] == Approx(0.45).margin(1e-5));
    }
    constexpr int kIndependent = 40;
    constexpr double kT39 = 5.09;
    const volume::CloudConfig still = load_in(dir.path, volume_scene("")).volume->cloud;
    const double theory = volume::CloudVolume(still).theory().variance;
    for (bool jacobian : {true, false}) {
        volume::CloudConfig c = s.volume->cloud;
        c.jacobian = jacobian;  // the loader refuses false for a divergent sequence
        volume::CloudVolume cloud(c);
        std::vector<double> v;
        for (int f = 0; f < kIndependent; ++f) {
            const volume::DensityGrid g = cloud.field(int64_t(f) * 6);
            double m2 = 0.0;
            for (float x : g.values) m2 += double(x) * x;
            v.push_back(m2 / double(g.values.size()));
        }
        double mean = 0.0, ss = 0.0;
        for (double x : v) mean += x / kIndependent;
        for (double x : v) ss += (x - mean) * (x - mean) / (kIndependent - 1);
        const double t = (mean - theory) / std::sqrt(ss / kIndependent);
        INFO("sqrt(J) " << jacobian << ": mean frame variance " << mean << " vs " << theory << ", t = " << t);
        if (jacobian)
            CHECK(std::abs(t) < kT39);
        else
            CHECK(t < -kT39);
    }
}

TEST_CASE("sequence: a volume's sampled solid-body rotation turns and aligns kernels as the "
          "analytic one",
          "[scenes][sequence][volume][orientation]") {
    // v = Omega z^ x (x - c) + (0, 0, w), Omega = 0.5 rad/s about the vertical through
    // c = (8, 8), w = 1 voxel/s, sampled every 4 voxels over [-40, 56]^3: it covers the birth
    // region of the view [0, 16]^3 (support 4, speed <= 0.5 * 48 sqrt 2 + 1 = 35 over a 1 s
    // life), and an impulse that reaches the view stays within 17 voxels of the axis, inside.
    // Trilinear interpolation reproduces a linear field, so the interpolant's error is the
    // samples' float rounding, eps = 2^-24 * 24 (the largest component) = 1.4e-6: v is off by
    // <= eps per component; a derivative along e is a convex combination of differences of two
    // samples times scale_e = 1/4, off by <= 2 eps / 4; a curl component, a difference of two
    // derivatives, by <= eps. Hence (docs/volume.md "Orientation"): the vorticity axis turns
    // at Omega within eps / 2 and tilts out of the plane at <= eps / sqrt 2, so after age a its
    // angle is Omega a within the Heun bound Omega^3 h^2 a / 6 plus a eps / 2, |u_z| <= a eps;
    // the flow axis is within sqrt 3 eps / |v| <= sqrt 3 eps / w of v. Plus 1e-6 for the
    // axis's float storage. Shown able to fail: a sequence curl with its sign flipped
    // (volume/sequence.cpp) turns the axes backwards, by up to 1 rad off.
    constexpr double kOmega = 0.5, kW = 1.0, kEps = 24.0 / 16777216.0, kH = 0.1;
    TempDir dir("volume_rotation");
    const auto field = [](double x, double y, double) {
        return Vec3{-kOmega * (y - 8.0), kOmega * (x - 8.0), kW};
    };
    for (int n : {1, 2}) write_vdb3(dir.path / frame_file("fluid_data_", n, ".vdb"), -10, 14, 4.0, field);
    const std::string flows = "[[volume.flow]]\ntype = \"sequence\"\npath = \"fluid_data_####.vdb\"\n";
    const scenes::Scene s = load_in(dir.path, volume_scene(flows));
    REQUIRE(s.volume);
    const std::shared_ptr<volume::Flow3> flow = s.volume->cloud.flow;
    double worst_v = 0.0, worst_w = 0.0;
    for (int p = 0; p < 200; ++p) {  // the interpolant's v and curl inside the grid
        const double x = -36.0 + 0.43 * p, y = 50.0 - 0.41 * p, z = -20.0 + 0.37 * p;
        double v[3] = {0, 0, 0}, w[3] = {0, 0, 0};
        const volume::CurlOut3 out{&w[0], &w[1], &w[2]};
        flow->add(0.3, 1, &x, &y, &z, &v[0], &v[1], &v[2], nullptr, &out);
        const Vec3 e = field(x, y, z);
        for (int c = 0; c < 3; ++c) worst_v = std::max(worst_v, std::abs(v[c] - e[size_t(c)]));
        worst_w = std::max({worst_w, std::abs(w[0]), std::abs(w[1]), std::abs(w[2] - 2.0 * kOmega)});
    }
    CHECK(worst_v <= kEps);
    CHECK(worst_w <= kEps);

    volume::Process3 p;
    p.seed = 3;
    p.intensity = 2e-2;
    p.cell_size = 4.0;
    p.lifetime_s = 1.0;
    p.fps = 1.0 / kH;
    const volume::Box3 view{0, 0, 0, 16, 16, 16};
    p.orientation = sim::OrientationMode::Vorticity;
    volume::Simulator3 vort(p, flow, 4.0);
    volume::Impulses3 imp;
    vort.impulses_at(17, view, imp);
    REQUIRE(imp.size() > 100);
    double worst_turn = 0.0;
    for (size_t i = 0; i < imp.size(); ++i) {
        const double a = imp.age_s[i];
        const double turn = std::remainder(std::atan2(double(imp.ay[i]), double(imp.ax[i])) - kOmega * a,
                                           2.0 * std::numbers::pi);
        const double bound = kOmega * kOmega * kOmega * kH * kH * a / 6.0 + a * kEps / 2.0 + 1e-6;
        worst_turn = std::max(worst_turn, std::abs(turn) / bound);
        CHECK(std::abs(turn) <= bound);
        CHECK(std::abs(imp.az[i]) <= a * kEps + 1e-6);
    }
    p.orientation = sim::OrientationMode::Flow;
    volume::Simulator3 along(p, flow, 4.0);
    along.impulses_at(17, view, imp);
    REQUIRE(imp.size() > 100);
    double worst_angle = 0.0;
    for (size_t i = 0; i < imp.size(); ++i) {
        const Vec3 v = field(imp.x[i], imp.y[i], imp.z[i]);
        const double u[3] = {imp.ax[i], imp.ay[i], imp.az[i]};
        const double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        worst_angle = std::max(worst_angle, std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                                                       u[0] * v[0] + u[1] * v[1] + u[2] * v[2]));
    }
    std::printf("[sequence] sampled rotation: v within %.2e, curl within %.2e (eps %.2e); vorticity "
                "axis turn at most %.3f of its bound; flow axis within %.2e rad of v (bound %.2e)\n",
                worst_v, worst_w, kEps, worst_turn, worst_angle, std::sqrt(3.0) * kEps / kW + 1e-6);
    CHECK(worst_angle <= std::sqrt(3.0) * kEps / kW + 1e-6);

    // The grid's edge moves (|v| up to sqrt((0.5 * 48 sqrt 2)^2 + 1) = 33.9559 voxels/s):
    // outside = "zero" jumps to 0 beyond it, a divergence sqrt(J) does not see, and the loader
    // says so once, as for a layer; "clamp" is continuous and quiet. Shown able to fail: without
    // the volume's call to warn_outside_zero (scenes/language/sequence_config.cpp) nothing is said.
    auto warned = [](const scenes::Scene& scene) {
        return std::count_if(scene.warnings.begin(), scene.warnings.end(), [](const std::string& w) {
            return w.find("volume.flow[0].outside: \"zero\" (the default) makes the field jump from up to "
                          "33.9559 voxels/s at the grid's edge") != std::string::npos;
        });
    };
    CHECK(warned(s) == 1);
    CHECK(warned(load_in(dir.path, volume_scene(flows + "outside = \"clamp\"\n"))) == 0);
}

namespace {

/// A VDB frame as Mantaflow writes one: `velocity` active only where `keep(i, j)` (its smoke),
/// the other voxels left inactive (the background, 0). `faces`: component c holds v at the face
/// below the voxel along c ((i - 1/2) along x), else at its centre; `staggered`: the grid's
/// class says so.
void write_sparse_vdb(const fs::path& file, int W, int H, int D, double voxel, bool faces, bool staggered,
                      const std::function<bool(int, int)>& keep,
                      const std::function<Vec2(double, double)>& v) {
    openvdb::initialize();
    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    vel->setName("velocity");
    vel->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    if (staggered) vel->setGridClass(openvdb::GRID_STAGGERED);
    auto acc = vel->getAccessor();
    const double half = faces ? 0.5 : 0.0;
    for (int k = 0; k < D; ++k)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i)
                if (keep(i, j))
                    acc.setValue({i, j, k}, openvdb::Vec3s(float(v(voxel * (i - half), voxel * j)[0]),
                                                           float(v(voxel * i, voxel * (j - half))[1]), 0.0f));
    openvdb::io::File out(file.string());
    out.write({vel});
    out.close();
}

/// The layer's flow at t at points (x, y).
std::vector<Vec2> flow_at(const scenes::Scene& s, double t, const std::vector<Vec2>& p) {
    std::vector<double> x, y;
    for (const auto& q : p) x.push_back(q[0]), y.push_back(q[1]);
    std::vector<double> vx(p.size()), vy(p.size()), div(p.size()), curl(p.size());
    s.layers[0].flow->add(t, p.size(), x.data(), y.data(), vx.data(), vy.data(), div.data(), curl.data());
    std::vector<Vec2> out;
    for (size_t i = 0; i < p.size(); ++i) out.push_back({vx[i], vy[i]});
    return out;
}

}  // namespace

TEST_CASE("sequence: sparse frames are read over the union of their boxes", "[scenes][sequence]") {
    // docs/scenes.md "A Blender cache": Mantaflow's velocity is active only where there is
    // smoke, so frame 1 (smoke in the left half, x < 64) and frame 2 (everywhere) cover
    // different boxes. Both load; frame 1 is the wind (3, 1) where it has smoke and 0 beyond
    // (the background), frame 2 the wind everywhere (outside = "zero", the default). Before the union was read the loader
    // refused frame 2 ("expected the same grid and transform in every frame").
    TempDir dir("sparse");
    auto wind = [](double, double) { return Vec2{3.0, 1.0}; };
    write_sparse_vdb(dir.path / "fluid_data_0001.vdb", 33, 33, 3, 4.0, false, false, [](int i, int) { return i <= 16; }, wind);
    write_sparse_vdb(dir.path / "fluid_data_0002.vdb", 33, 33, 3, 4.0, false, false, [](int, int) { return true; }, wind);
    const scenes::Scene s = load_in(dir.path, scene_text(sequence_table(true)));
    const std::vector<Vec2> p{{20.0, 50.0}, {60.0, 100.0}, {72.0, 50.0}, {120.0, 100.0}};
    const auto first = flow_at(s, 0.0, p), second = flow_at(s, 0.25, p);
    for (size_t i = 0; i < p.size(); ++i) {
        INFO("point (" << p[i][0] << ", " << p[i][1] << ")");
        const bool smoke = p[i][0] <= 64.0;
        CHECK(first[i][0] == Approx(smoke ? 3.0 : 0.0).margin(1e-6));
        CHECK(first[i][1] == Approx(smoke ? 1.0 : 0.0).margin(1e-6));
        CHECK(second[i][0] == Approx(3.0).margin(1e-6));
        CHECK(second[i][1] == Approx(1.0).margin(1e-6));
    }
    // The wind is 3.16 at the grid's edge: outside = "zero" (the default) jumps to 0 there, a
    // divergence sqrt(J) does not see, and says so once; "clamp" is continuous and quiet.
    auto warned = [](const scenes::Scene& scene) {
        return std::count_if(scene.warnings.begin(), scene.warnings.end(), [](const std::string& w) {
            return w.find("flow[0].outside: \"zero\" (the default) makes the field jump from up to 3.16") != std::string::npos;
        });
    };
    CHECK(warned(s) == 1);
    CHECK(warned(load_in(dir.path, scene_text(sequence_table(true, "outside = \"clamp\"\n")))) == 0);
}

TEST_CASE("sequence: a staggered grid is averaged to the voxel centres", "[scenes][sequence]") {
    // A MAC grid (Mantaflow's velocity) of the linear field v = 0.125 (x - 64, y - 64): the
    // faces' values averaged to the centres are v at the centres exactly (linear), so the flow
    // is the analytic field between them (bilinear reproduces a linear field). Read as a
    // centred grid (the class not set) the same values are v half a voxel (2 units) back along
    // each component: off by 0.125 * 2 = 0.25.
    TempDir dir("staggered");
    auto linear = [](double x, double y) { return Vec2{0.125 * (x - 64.0), 0.125 * (y - 64.0)}; };
    for (bool staggered : {true, false}) {
        for (int n : {1, 2})
            write_sparse_vdb(dir.path / frame_file("fluid_data_", n, ".vdb"), 33, 33, 3, 4.0, true,
                             staggered, [](int, int) { return true; }, linear);
        const scenes::Scene s = load_in(dir.path, scene_text(sequence_table(true)));
        // away from the last voxel along each axis (which keeps its face value)
        const std::vector<Vec2> p{{10.0, 20.0}, {33.3, 90.1}, {64.0, 64.0}, {101.7, 47.5}};
        const auto v = flow_at(s, 0.1, p);
        for (size_t i = 0; i < p.size(); ++i) {
            const Vec2 exact = linear(p[i][0], p[i][1]);
            INFO("staggered " << staggered << ", point (" << p[i][0] << ", " << p[i][1] << ")");
            const double off = staggered ? 0.0 : -0.25;
            CHECK(v[i][0] == Approx(exact[0] + off).margin(1e-5));
            CHECK(v[i][1] == Approx(exact[1] + off).margin(1e-5));
        }
    }
}

namespace {

/// Per frame of `count` frames of `scene` rendered in order, the variance over each mask's
/// pixels (the layer's mean is 0: normal amplitudes).
std::vector<std::vector<double>> masked_variances(scenes::Scene scene, int count,
                                                  const std::vector<std::vector<bool>>& masks) {
    scenes::Renderer renderer(std::move(scene));
    render::Frame frame;
    std::vector<std::vector<double>> v(masks.size());
    for (int i = 0; i < count; ++i) {
        renderer.render(i, frame);
        for (size_t m = 0; m < masks.size(); ++m) {
            double ss = 0.0;
            size_t n = 0;
            for (size_t k = 0; k < masks[m].size(); ++k)
                if (masks[m][k]) ss += double(frame.data[k]) * frame.data[k], ++n;
            v[m].push_back(ss / double(n));
        }
    }
    return v;
}

}  // namespace

TEST_CASE("sequence: a Mantaflow cache keeps the frame variance only with sqrt(J)", "[.mantaflow]") {
    // Run by blender/test_mantaflow.sh (ctest -L blender) after Blender baked a smoke plume:
    // IMPULSE_MANTAFLOW_SCENES names the folder where blender/test_mantaflow.py wrote
    // variance.toml (a 128 x 128 texture on the slice y = 0 of the cache, docs/scenes.md "A
    // Blender cache") and still.toml (the same layer without its flow). 240 frames at 24 fps:
    // the sequence's 24 frames, then its last frame held; 20 lifetimes of 0.5 s in 10 blocks of
    // 2 lifetimes. The flow carries as many impulses into the picture as out of it (the
    // velocity is 0 at its edges outside the smoke), so the whole picture's variance hardly
    // moves without sqrt(J); where the held slice stretches (div v > 2/s at the pixel) the
    // impulses thin out and where it converges (div v < -2/s) they crowd (design.md §1), so the
    // variance is taken over those pixels. Each region's run mean against the still run's:
    // t = d / sqrt(se1^2 + se2^2), ~ t with ~18 degrees of freedom, P(|t| > 5) ~ 1e-4.
    const char* dir = std::getenv("IMPULSE_MANTAFLOW_SCENES");
    REQUIRE(dir != nullptr);
    constexpr int kFrames = 240, kBlocks = 10;
    const fs::path flow_scene = fs::path(dir) / "variance.toml";
    std::vector<std::vector<bool>> masks(2);
    {
        const scenes::Scene s = scenes::load_scene(flow_scene.string());
        const int W = s.output.width, H = s.output.height;
        std::vector<double> x, y;
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) x.push_back(i + 0.5), y.push_back(j + 0.5);
        std::vector<double> vx(x.size()), vy(x.size()), div(x.size()), curl(x.size());
        s.layers[0].flow->add(5.0, x.size(), x.data(), y.data(), vx.data(), vy.data(), div.data(), curl.data());
        for (double d : div) masks[0].push_back(d > 2.0), masks[1].push_back(d < -2.0);
    }
    const char* names[] = {"stretching", "converging"};
    const auto still = masked_variances(scenes::load_scene((fs::path(dir) / "still.toml").string()), kFrames, masks);
    for (bool jacobian : {true, false}) {
        scenes::Scene s = scenes::load_scene(flow_scene.string());
        s.layers[0].process.jacobian = jacobian;  // the loader would refuse false: switched off here
        const auto moving = masked_variances(std::move(s), kFrames, masks);
        double worst = 0.0;
        for (size_t m = 0; m < masks.size(); ++m) {
            const Blocks a = blocks_of(moving[m], kBlocks), b = blocks_of(still[m], kBlocks);
            const double t = (a.mean - b.mean) / std::hypot(a.se, b.se);
            WARN("sqrt(J) " << (jacobian ? "on" : "off") << ", " << names[m] << " pixels ("
                            << std::count(masks[m].begin(), masks[m].end(), true) << "): mean variance "
                            << a.mean << " (se " << a.se << ") vs still " << b.mean << " (se " << b.se
                            << "), t = " << t);
            worst = std::max(worst, std::abs(t));
        }
        if (jacobian)
            CHECK(worst < 5.0);
        else
            CHECK(worst > 5.0);
    }
}

namespace {

/// A VDB frame of `v(i, j, k)` (3-D velocities at the voxels) of W x H x D voxels of size
/// `voxel`, every voxel active.
void write_vdb3(const fs::path& file, int W, int H, int D, double voxel,
                const std::function<std::array<double, 3>(int, int, int)>& v) {
    openvdb::initialize();
    auto vel = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    vel->setName("velocity");
    vel->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    auto acc = vel->getAccessor();
    for (int k = 0; k < D; ++k)
        for (int j = 0; j < H; ++j)
            for (int i = 0; i < W; ++i) {
                const auto u = v(i, j, k);
                acc.setValue({i, j, k}, openvdb::Vec3s(float(u[0]), float(u[1]), float(u[2])));
            }
    openvdb::io::File out(file.string());
    out.write({vel});
    out.close();
}

}  // namespace

TEST_CASE("sequence: plane modes and cubic time and the nearest sample outside in closed form",
          "[scenes][sequence]") {
    TempDir dir("modes");
    const std::vector<Vec2> points{{10.0, 20.0}, {33.3, 90.1}, {101.7, 47.5}};
    SECTION("average: the mean through the depth") {
        // v = (1 + 0.5 k, 2 - 0.25 k, 0) over k = 0..4: the depth's mean is (2, 1.5) at every
        // point; a slice at the default height (the middle layer, k = 2) is the same, and one
        // at z = 0 (k = 0) is (1, 2): the mode is seen.
        for (int n : {1, 2})
            write_vdb3(dir.path / frame_file("fluid_data_", n, ".vdb"), 33, 33, 5, 4.0,
                       [](int, int, int k) { return std::array<double, 3>{1.0 + 0.5 * k, 2.0 - 0.25 * k, 0.0}; });
        for (const auto& [keys, want] : std::vector<std::pair<std::string, Vec2>>{
                 {"plane = \"average\"\n", {2.0, 1.5}}, {"height = 0.0\n", {1.0, 2.0}}}) {
            const auto v = flow_at(load_in(dir.path, scene_text(sequence_table(true, keys))), 0.1, points);
            for (const auto& u : v) {
                INFO(keys);
                CHECK(u[0] == Approx(want[0]).margin(1e-5));
                CHECK(u[1] == Approx(want[1]).margin(1e-5));
            }
        }
    }
    SECTION("project: the wind's part in the plane") {
        // a uniform wind (1, 2, 3) on the plane of normal (1, 1, 1): its in-plane part has
        // |v|^2 - (v.n)^2 = 14 - 12 = 2 (speed sqrt 2), whatever axes the plane takes
        for (int n : {1, 2})
            write_vdb3(dir.path / frame_file("fluid_data_", n, ".vdb"), 17, 17, 17, 4.0,
                       [](int, int, int) { return std::array<double, 3>{1.0, 2.0, 3.0}; });
        const auto s = load_in(dir.path, scene_text(sequence_table(true, "plane = \"project\"\nnormal = [1.0, 1.0, 1.0]\n")));
        // the projected plane's texture coordinates start at its first sample: points inside it
        const auto v = flow_at(s, 0.1, {{20.0, 20.0}, {30.0, 25.0}});
        for (const auto& u : v) CHECK(std::hypot(u[0], u[1]) == Approx(std::sqrt(2.0)).margin(1e-5));
    }
    SECTION("cubic time: Catmull-Rom is exact for a quadratic in time, linear is not") {
        // a wind (t_f^2, 0) at frame times t_f = 0, 0.25, ... (fps 4): halfway between frames 3
        // and 4 (t = 0.625) Catmull-Rom gives 0.625^2 = 0.390625 exactly (quadratic precision);
        // linear gives the chord's (0.25 + 0.5625) / 2 = 0.40625
        for (int n = 1; n <= 6; ++n) {
            const double t = (n - 1) / 4.0;
            write_vdb(dir.path / frame_file("fluid_data_", n, ".vdb"), 9, 9, 3, 16.0,
                      [&](double, double) { return Vec2{t * t, 0.0}; });
        }
        const std::vector<Vec2> p{{64.0, 64.0}};
        CHECK(flow_at(load_in(dir.path, scene_text(sequence_table(true, "interpolation = \"cubic\"\n"))), 0.625, p)[0][0] ==
              Approx(0.390625).margin(1e-6));
        CHECK(flow_at(load_in(dir.path, scene_text(sequence_table(true))), 0.625, p)[0][0] ==
              Approx(0.40625).margin(1e-6));
    }
    SECTION("nearest: the nearest sample's value beyond the grid") {
        // v = 0.125 (x - 64, y - 64) on samples 4 apart over [0, 128]^2: beyond the corner at
        // (140, -10) the nearest sample is (128, 0), v = (8, -8); clamp takes the nearest point
        // of the grid, the same corner here, and zero gives 0; beside the right edge at
        // (135, 49) nearest is the sample (128, 48), v = (8, -2), and clamp interpolates along
        // the edge to (128, 49): (8, -1.875)
        for (int n : {1, 2})
            write_vdb(dir.path / frame_file("fluid_data_", n, ".vdb"), 33, 33, 3, 4.0,
                      [](double x, double y) { return Vec2{0.125 * (x - 64.0), 0.125 * (y - 64.0)}; });
        const std::vector<Vec2> p{{140.0, -10.0}, {135.0, 49.0}};
        const auto nearest = flow_at(load_in(dir.path, scene_text(sequence_table(true, "outside = \"nearest\"\n"))), 0.1, p);
        const auto clamp = flow_at(load_in(dir.path, scene_text(sequence_table(true, "outside = \"clamp\"\n"))), 0.1, p);
        const auto zero = flow_at(load_in(dir.path, scene_text(sequence_table(true))), 0.1, p);
        CHECK(nearest[0][0] == Approx(8.0).margin(1e-6));
        CHECK(nearest[0][1] == Approx(-8.0).margin(1e-6));
        CHECK(nearest[1][0] == Approx(8.0).margin(1e-6));
        CHECK(nearest[1][1] == Approx(-2.0).margin(1e-6));
        CHECK(clamp[1][1] == Approx(-1.875).margin(1e-6));
        CHECK(zero[0][0] == 0.0);
        CHECK(zero[1][1] == 0.0);
    }
}
