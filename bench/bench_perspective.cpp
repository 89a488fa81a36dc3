// SPDX-License-Identifier: Apache-2.0
// impulse_bench_perspective: the cost of a 1920x1080 perspective frame with a visible horizon
// against an orthographic frame of the same size and scene (issue "Non-stationary and
// perspective", item 6; target: <= 2x), and the cost per level of building the band-limited
// kernel pyramid. Frames are timed side by side (orthographic, then each perspective row, per
// repetition); every figure is the median [min-max] of the repetitions after an untimed warm-up,
// with 2 threads. See bench/README.md for the rows and columns.

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "bench/common.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "sim/sim.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

constexpr int kWidth = 1920, kHeight = 1080;
constexpr double kTargetRatio = 2.0;

struct Options {
    bool quick = false;
    bool csv = false;
    int reps = 7;
    double height = 64.0;  ///< camera height, texture units
};

[[noreturn]] void usage_error(const std::string& m) {
    throw std::invalid_argument(
        m + " (usage: impulse_bench_perspective [--quick] [--csv] [--reps N] [--height H])");
}

Options parse_args(int argc, char** argv) {
    Options o;
    bool reps_set = false;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage_error(std::string(a) + ": missing value");
            return argv[++i];
        };
        if (a == "--quick")
            o.quick = true;
        else if (a == "--csv")
            o.csv = true;
        else if (a == "--reps") {
            const std::string v = value();
            o.reps = std::atoi(v.c_str());
            if (o.reps < 1 || o.reps > 1000)
                usage_error("--reps " + v + ": expected an integer in [1, 1000]");
            reps_set = true;
        } else if (a == "--height") {
            const std::string v = value();
            o.height = std::atof(v.c_str());
            if (!(o.height > 0.0)) usage_error("--height " + v + ": expected a number > 0");
        } else
            usage_error(std::string(a) + ": unknown flag");
    }
    if (o.quick && !reps_set) o.reps = 3;
    return o;
}

struct Stat {
    std::vector<double> v;
    double median() const {
        std::vector<double> s = v;
        std::sort(s.begin(), s.end());
        return s.empty()      ? 0.0
               : s.size() % 2 ? s[s.size() / 2]
                              : 0.5 * (s[s.size() / 2 - 1] + s[s.size() / 2]);
    }
    double min() const { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }
    double max() const { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }
};

std::string cell(const Stat& s) {
    char b[64];
    std::snprintf(b, sizeof b, "%.1f [%.1f-%.1f]", s.median(), s.min(), s.max());
    return b;
}

/// One frame's timings.
struct FrameTimes {
    Stat setup, generate, evaluate, total;  // setup: region + pixel coordinates (perspective)
    Stat cpu;                               // process CPU time of the frame (both threads)
    Stat far_setup, prepare, tiles, far;    // parts of evaluate (perspective)
    size_t impulses = 0;
    render::PerspectiveStats stats;
};

/// The scene of every frame row: cosine kernels of radius 16, 16 impulses per kernel area, a
/// still process (the `still` built-in scene), seed 1.
struct Scene {
    kernels::Kernel kernel{[] {
        kernels::KernelParams p;
        p.type = kernels::KernelType::Cosine;
        p.radius = 16.0;
        return p;
    }()};
    sim::ProcessConfig process = [this] {
        sim::ProcessConfig c;
        c.seed = 1;
        c.cell_size = 16.0;
        c.intensity = 16.0 / kernel.support_area();
        return c;
    }();
};

/// What a renderer keeps from frame to frame for a layer (scenes/frame/renderer.cpp: the impulses and
/// the frame; scenes/frame/camera_render.cpp: the perspective workspace), one per row so every row's
/// frames are timed as frames of a sequence.
struct Buffers {
    render::Frame f;
    sim::Impulses imp;
    render::PerspectiveWorkspace ws;
};

void time_ortho(const Scene& sc, sim::LayerSimulator& s, Buffers& buf, FrameTimes& t) {
    const render::View view{kWidth, kHeight, 0.0, 0.0, 1.0};
    render::Frame& f = buf.f;
    f.resize(kWidth, kHeight);
    sim::Impulses& imp = buf.imp;
    const double c0 = own_cpu_s();
    auto t0 = Clock::now();
    s.impulses_at(0, view.box(), imp);
    const double g = ms_since(t0);
    t0 = Clock::now();
    render::accumulate(sc.kernel, imp, view, f);
    const double e = ms_since(t0);
    t.cpu.v.push_back(1e3 * (own_cpu_s() - c0));
    t.generate.v.push_back(g), t.evaluate.v.push_back(e), t.total.v.push_back(g + e);
    t.setup.v.push_back(0.0);
    t.impulses = imp.size();
}

/// Times one perspective frame; `buf` is reused from frame to frame, as a renderer keeps its
/// buffers per layer.
void time_perspective(const kernels::KernelPyramid& pyr, sim::LayerSimulator& s,
                      const render::PerspectiveCamera& cam, const render::AntiAlias& aa,
                      Buffers& buf, FrameTimes& t) {
    render::Frame& f = buf.f;
    f.resize(kWidth, kHeight);
    sim::Impulses& imp = buf.imp;
    const double c0 = own_cpu_s();
    auto t0 = Clock::now();
    const render::PerspectiveView view(cam);
    const numeric::Region box = render::perspective_region(pyr, view, aa);
    const render::PixelCoords pc = render::pixel_coords(view);
    const double su = ms_since(t0);
    t0 = Clock::now();
    s.impulses_at(0, box, imp);
    const double g = ms_since(t0);
    t0 = Clock::now();
    render::accumulate_perspective(pyr, imp, view, pc, f, aa, {}, &t.stats, &buf.ws);
    const double e = ms_since(t0);
    t.cpu.v.push_back(1e3 * (own_cpu_s() - c0));
    t.setup.v.push_back(su), t.generate.v.push_back(g), t.evaluate.v.push_back(e);
    t.total.v.push_back(su + g + e);
    t.far_setup.v.push_back(t.stats.setup_ms), t.prepare.v.push_back(t.stats.prepare_ms);
    t.tiles.v.push_back(t.stats.tiles_ms), t.far.v.push_back(t.stats.far_ms);
    t.impulses = imp.size();
}

struct Row {
    std::string name;
    render::AntiAlias aa;
    bool moving = false;  ///< the camera moves 1 texture unit a frame (a fly-over)
    FrameTimes t;
};

render::PerspectiveCamera bench_camera(const Options& o) {
    render::PerspectiveCamera cam;
    cam.width = kWidth, cam.height = kHeight;
    cam.x = 0.5 * kWidth, cam.y = 0.5 * kHeight;
    cam.altitude = o.height, cam.pitch_deg = 15.0, cam.fov_deg = 50.0;
    return cam;
}

std::vector<Row> bench_rows(const Options& o) {
    std::vector<Row> rows;
    auto add = [&](const std::string& name, auto&& tweak, bool moving = false) {
        Row r;
        r.name = name;
        tweak(r.aa);
        r.moving = moving;
        rows.push_back(std::move(r));
    };
    add("perspective, cut-off 1 % (default)", [](render::AntiAlias&) {});
    // A still camera keeps its far-field set-up from frame to frame (as the scene renderer's
    // layers do); a moving one sets it up every frame.
    add("perspective, 1 %, camera moving", [](render::AntiAlias&) {}, true);
    add("perspective, cut-off 2 %", [](render::AntiAlias& a) { a.cutoff = 0.02; });
    add("perspective, cut-off 5 %", [](render::AntiAlias& a) { a.cutoff = 0.05; });
    if (!o.quick) {
        add("perspective, cut-off 20 %", [](render::AntiAlias& a) { a.cutoff = 0.2; });
        add("perspective, 1 %, far field off (line form)",
            [](render::AntiAlias& a) { a.far_field = false; });
        add("perspective, 1 %, major axis only",
            [](render::AntiAlias& a) { a.anisotropic = false; });
    }
    return rows;
}

/// Every row and the orthographic frame, `o.reps` times after an untimed warm-up, interleaved.
void time_rows(const Options& o, const Scene& sc, const kernels::KernelPyramid& pyr,
               const render::PerspectiveCamera& cam, std::vector<Row>& rows, FrameTimes& ortho) {
    sim::LayerSimulator s(sc.process, nullptr, {}, sc.kernel.radius());
    Buffers ortho_buf;
    std::vector<std::unique_ptr<Buffers>> row_buf;
    for (size_t i = 0; i < rows.size(); ++i) row_buf.push_back(std::make_unique<Buffers>());
    auto camera = [&](const Row& r, int rep) {
        render::PerspectiveCamera c = cam;
        if (r.moving) c.x += 1.0 + rep;
        return c;
    };
    // warm-up (untimed): every row once, so its buffers hold a frame already
    {
        FrameTimes w;
        time_ortho(sc, s, ortho_buf, w);
        for (size_t i = 0; i < rows.size(); ++i)
            time_perspective(pyr, s, camera(rows[i], -1), rows[i].aa, *row_buf[i], w);
    }
    for (int rep = 0; rep < o.reps; ++rep) {
        time_ortho(sc, s, ortho_buf, ortho);
        for (size_t i = 0; i < rows.size(); ++i)
            time_perspective(pyr, s, camera(rows[i], rep), rows[i].aa, *row_buf[i],
                             rows[i].t);
    }
}

void print_csv(const FrameTimes& ortho, const std::vector<Row>& rows) {
    const double ortho_ms = ortho.total.median();
    std::printf(
        "row,impulses,setup_ms_median,generate_ms_median,evaluate_ms_median,total_ms_median,"
        "total_ms_min,total_ms_max,ratio_to_ortho,cpu_ms_median,cpu_ratio_to_ortho,"
        "pixel_evaluations,single,probes,line,far,far_setup_ms,prepare_ms,tiles_ms,far_ms\n");
    std::printf("orthographic,%zu,0,%.3f,%.3f,%.3f,%.3f,%.3f,1,%.3f,1,%.0f,,,,,,,,\n",
                ortho.impulses, ortho.generate.median(), ortho.evaluate.median(), ortho_ms,
                ortho.total.min(), ortho.total.max(), ortho.cpu.median(),
                double(kWidth) * kHeight * 16.0);
    for (const auto& r : rows)
        std::printf(
            "\"%s\",%zu,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%zu,%zu,%zu,%zu,%zu,%.3f,"
            "%.3f,%.3f,%.3f\n",
            r.name.c_str(), r.t.impulses, r.t.setup.median(), r.t.generate.median(),
            r.t.evaluate.median(), r.t.total.median(), r.t.total.min(), r.t.total.max(),
            r.t.total.median() / ortho_ms, r.t.cpu.median(),
            r.t.cpu.median() / ortho.cpu.median(), r.t.stats.pixels, r.t.stats.single,
            r.t.stats.probes, r.t.stats.line, r.t.stats.far, r.t.far_setup.median(),
            r.t.prepare.median(), r.t.tiles.median(), r.t.far.median());
}

void print_table(const Options& o, const render::PerspectiveCamera& cam, const FrameTimes& ortho,
                 const std::vector<Row>& rows, const std::string& load_start,
                 const std::string& load_end) {
    const render::PerspectiveView view(cam);
    const double ortho_ms = ortho.total.median();
    std::printf(
        "impulse_bench_perspective: %dx%d, cosine r = 16, density 16, still, 2 threads, "
        "%d repetitions (ms: median [min-max])\n",
        kWidth, kHeight, o.reps);
    std::printf(
        "perspective camera: height %g, pitch 15, fov 50, heading 0; horizon at row %.1f; "
        "filter 0.5 px\n\n",
        o.height, view.horizon_row());
    std::printf("%-44s %8s %8s %22s %22s %24s %8s %9s %7s %11s\n", "row", "impulses", "far",
                "generate", "evaluate", "total", "x ortho", "cpu ms", "x cpu", "pixel evals");
    std::printf("%-44s %8zu %8s %22s %22s %24s %8s %9.1f %7s %11s\n", "orthographic, scale 1",
                ortho.impulses, "-", cell(ortho.generate).c_str(), cell(ortho.evaluate).c_str(),
                cell(ortho.total).c_str(), "1.00", ortho.cpu.median(), "1.00", "-");
    for (const auto& r : rows)
        std::printf("%-44s %8zu %8zu %22s %22s %24s %8.2f %9.1f %7.2f %11zu\n", r.name.c_str(),
                    r.t.impulses, r.t.stats.far, cell(r.t.generate).c_str(),
                    cell(r.t.evaluate).c_str(), cell(r.t.total).c_str(),
                    r.t.total.median() / ortho_ms, r.t.cpu.median(),
                    r.t.cpu.median() / ortho.cpu.median(), r.t.stats.pixels);
    const auto& d = rows.front().t;
    std::printf(
        "\n(perspective totals include the visible region and the per-pixel texture "
        "coordinates: median %.1f ms for the default row)\n"
        "default row, evaluate in parts (ms, median): far-field set-up %.1f, impulse "
        "preparation %.1f, tiles (near field) %.1f, far field %.1f\n",
        d.setup.median(), d.far_setup.median(), d.prepare.median(), d.tiles.median(),
        d.far.median());
    for (const auto& r : rows)
        if (r.moving)
            std::printf(
                "camera moving (1 texture unit a frame): total %.1f ms = %.2fx ortho, of "
                "which far-field set-up %.1f (a still camera keeps it)\n",
                r.t.total.median(), r.t.total.median() / ortho_ms, r.t.far_setup.median());
    std::printf("load average at start %s, at end %s\n", load_start.c_str(), load_end.c_str());
    const double ratio = rows.front().t.total.median() / ortho_ms;
    std::printf(
        "target: perspective frame <= %.0fx the orthographic frame: %.2fx at the default "
        "cut-off -> %s\n\n",
        kTargetRatio, ratio, ratio <= kTargetRatio ? "PASS" : "MISS");
}

/// Pyramid build: time per level (low_pass of the kernel at sigma_l, as a Sampled kernel with
/// its statistics), and the whole pyramid with the evaluator's tables.
void time_pyramids(const Options& o, tbb::task_arena& arena) {
    struct Kind {
        const char* name;
        kernels::KernelParams p;
    };
    std::vector<Kind> kinds;
    {
        Kind a{"cosine r=16 (radial profiles)", {}};
        a.p.type = kernels::KernelType::Cosine, a.p.radius = 16.0;
        Kind b{"gaussian r=72 sigma=24 (radial)", {}};
        b.p.type = kernels::KernelType::Gaussian, b.p.radius = 72.0, b.p.sigma = 24.0;
        Kind c{"gabor r=16 f=1/16 (2-D grids)", {}};
        c.p.type = kernels::KernelType::Gabor, c.p.radius = 16.0, c.p.frequency = 0.0625;
        Kind e{"gaussian r=72 sigma=24 aspect 1.7 (grids)", {}};
        e.p.type = kernels::KernelType::Gaussian, e.p.radius = 72.0, e.p.sigma = 24.0;
        e.p.aspect = 1.7;
        kinds = {a, b, c, e};
    }
    if (o.csv)
        std::printf(
            "\nkernel,level,sigma,radius,sd_fraction,low_pass_ms_median,low_pass_ms_min,low_pass_"
            "ms_max\n");
    for (const auto& k : kinds) {
        const kernels::Kernel base(k.p);
        Stat whole;
        std::vector<Stat> per;
        int levels = 0;
        arena.execute([&] {
            for (int rep = 0; rep < (o.quick ? 1 : 3); ++rep) {
                const auto t0 = Clock::now();
                const kernels::KernelPyramid p(base);
                whole.v.push_back(ms_since(t0));
                levels = p.levels();
                if (per.empty()) per.resize(size_t(levels));
                for (int l = 1; l < levels; ++l) {
                    const auto t1 = Clock::now();
                    const kernels::Kernel lv = kernels::low_pass(base, p.sigma(l));
                    per[size_t(l)].v.push_back(ms_since(t1));
                }
            }
        });
        const kernels::KernelPyramid p(base);
        if (o.csv) {
            for (int l = 1; l < levels; ++l)
                std::printf("\"%s\",%d,%.4g,%.4g,%.4g,%.3f,%.3f,%.3f\n", k.name, l, p.sigma(l),
                            p.radius(l), std::sqrt(p.variance(l) / p.variance(0)),
                            per[size_t(l)].median(), per[size_t(l)].min(), per[size_t(l)].max());
            continue;
        }
        std::printf("pyramid of %s: %d levels, sigma_0 = %.3g, whole pyramid %s ms\n", k.name,
                    levels, p.sigma(0), cell(whole).c_str());
        std::printf("  %5s %10s %10s %10s %20s\n", "level", "sigma", "radius", "sd frac",
                    "low_pass ms");
        for (int l = 1; l < levels; ++l)
            std::printf("  %5d %10.3g %10.4g %10.3g %20s\n", l, p.sigma(l), p.radius(l),
                        std::sqrt(p.variance(l) / p.variance(0)), cell(per[size_t(l)]).c_str());
    }
}

int run(const Options& o) {
    const std::string load_start = loadavg();
    tbb::task_arena arena(2);
    Scene sc;
    kernels::PyramidParams pp;
    pp.min_sd_fraction =
        0.0025;  // a quarter of the default cut-off, as the scene renderer builds it
    const kernels::KernelPyramid pyr(sc.kernel, pp);
    const render::PerspectiveCamera cam = bench_camera(o);
    std::vector<Row> rows = bench_rows(o);
    FrameTimes ortho;
    arena.execute([&] { time_rows(o, sc, pyr, cam, rows, ortho); });
    const std::string load_end = loadavg();
    if (o.csv)
        print_csv(ortho, rows);
    else
        print_table(o, cam, ortho, rows, load_start, load_end);
    time_pyramids(o, arena);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(parse_args(argc, argv));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "impulse_bench_perspective: %s\n", e.what());
        return 1;
    }
}
