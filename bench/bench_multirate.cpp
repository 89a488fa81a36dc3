// SPDX-License-Identifier: Apache-2.0
// impulse_bench_multirate: what multi-rate evaluation (docs/multirate.md) saves on a 1080p
// frame, side by side with direct evaluation in one run, interleaved run by run: still layers
// of one kernel (generation + evaluation, 2 threads), and whole scenes through the Renderer
// (sequential frames, the field before shading). Each row prints the lattice spacing, the
// predicted and the measured rms error (against direct evaluation, / the layer's sd), and the
// work counted: kernel evaluations (impulses x pixels within their radius) and pixels
// reconstructed. See bench/README.md.

#include <tbb/task_arena.h>

#include <cmath>
#include <numbers>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/common.h"
#include "kernels/kernels.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

constexpr int kWidth = 1920, kHeight = 1080;

struct Layer {
    const char* name;
    kernels::KernelParams kernel;
    double density;  ///< impulses per kernel area
    bool turned;     ///< random orientation per impulse
};

double rms_error(const render::Frame& a, const render::Frame& b, double sd) {
    double s = 0.0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - b.data[i];
        s += d * d;
    }
    return std::sqrt(s / double(a.data.size())) / sd;
}

void still_row(const Layer& L, double tolerance, int reps, tbb::task_arena& two) {
    const kernels::Kernel k(L.kernel);
    sim::ProcessConfig pc;
    pc.seed = 1;
    pc.intensity = L.density / k.support_area();
    pc.amplitude = sim::Amplitude::Normal;
    pc.cell_size = k.radius();
    pc.orientation = L.turned ? sim::OrientationMode::Random : sim::OrientationMode::Fixed;
    sim::LayerSimulator simulator(pc, nullptr, sim::Timing{}, k.radius());
    const render::View view{kWidth, kHeight, 0.0, 0.0, 1.0};
    const render::LatticeRule rule = render::choose_lattice(k, 1.0, tolerance);
    const render::View lattice = render::lattice_view(view, rule);
    sim::Impulses direct_imp, lattice_imp;
    render::Frame direct, approx;
    std::vector<double> td, tl;
    for (int r = 0; r <= reps; ++r) {  // run 0 is the untimed warm-up
        direct.resize(kWidth, kHeight), approx.resize(kWidth, kHeight);
        two.execute([&] {
            auto t0 = Clock::now();
            simulator.impulses_at(0, view.box(), direct_imp);
            render::accumulate(k, direct_imp, view, direct);
            const double d = ms_since(t0);
            t0 = Clock::now();
            simulator.impulses_at(0, lattice.box(), lattice_imp);
            render::accumulate_lattice(k, lattice_imp, view, rule, approx);
            const double l = ms_since(t0);
            if (r > 0) td.push_back(d), tl.push_back(l);
        });
    }
    const double sd = std::sqrt(pc.intensity * k.integral_sq());  // Campbell, E[a^2] = 1
    const Stats d = summarise(td), l = summarise(tl);
    const double r_px = k.radius();
    const double direct_evals = double(direct_imp.size()) * std::numbers::pi * r_px * r_px;
    const double node_evals = double(lattice_imp.size()) * std::numbers::pi * (r_px / rule.spacing) * (r_px / rule.spacing);
    std::printf("%-34s %3d %9.2g %9.2g  %-19s %-19s %6.2fx  %9.3g %9.3g\n", L.name, rule.spacing,
                rule.predicted_error, rms_error(direct, approx, sd), cell(d).c_str(),
                cell(l).c_str(), d.med / l.med, direct_evals, node_evals);
    std::fflush(stdout);
}

void scene_row(const std::string& name, int frames, int reps, tbb::task_arena& two) {
    const std::string path = scenes::resolve_scene(name);
    scenes::Renderer direct(scenes::load_scene(path, {"render.tolerance=0"}));
    scenes::Renderer lattice(scenes::load_scene(path, {"render.tolerance=0.005"}));
    render::Frame a, b;
    std::vector<double> td, tl;
    double err = 0.0, predicted = 0.0;
    const auto th = scenes::scene_theory(lattice.scene());
    for (size_t i = 0; i < lattice.scene().layers.size(); ++i)
        if (auto rule = lattice.lattice(i)) predicted = std::max(predicted, rule->predicted_error);
    two.execute([&] {
        direct.render(0, a), lattice.render(0, b);  // from birth: untimed
        for (int r = 0; r < reps; ++r)
            for (int f = 1; f <= frames; ++f) {
                const int frame = r * frames + f;
                auto t0 = Clock::now();
                direct.render(frame, a);
                td.push_back(ms_since(t0));
                t0 = Clock::now();
                lattice.render(frame, b);
                tl.push_back(ms_since(t0));
                err = std::max(err, rms_error(a, b, std::sqrt(th.variance)));
            }
    });
    const Stats d = summarise(td), l = summarise(tl);
    std::printf("%-34s %3s %9.2g %9.2g  %-19s %-19s %6.2fx\n", ("scene " + name).c_str(), "-",
                predicted, err, cell(d).c_str(), cell(l).c_str(), d.med / l.med);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
    int reps = 9;
    bool quick = argc > 1 && std::string(argv[1]) == "--quick";
    if (quick) reps = 3;
    tbb::task_arena two(2);
    const double tol = render::kRecommendedLatticeTolerance;
    std::printf("impulse_bench_multirate: 1920x1080, 2 threads, render.tolerance %g; times in ms, "
                "median [min-max] of %d runs; load %s\n",
                tol, reps, loadavg().c_str());
    std::printf("%-34s %3s %9s %9s  %-19s %-19s %7s  %9s %9s\n", "layer (still: generate + evaluate)",
                "h", "predicted", "measured", "direct", "multi-rate", "ratio", "evals", "node evals");
    kernels::KernelParams cos16;
    cos16.type = kernels::KernelType::Cosine, cos16.radius = 16;
    kernels::KernelParams gauss8;
    gauss8.type = kernels::KernelType::Gaussian, gauss8.sigma = 8, gauss8.radius = 3.7169 * 8;
    kernels::KernelParams gabor16;
    gabor16.type = kernels::KernelType::Gabor, gabor16.radius = 16, gabor16.frequency = 2.0 / 16;
    kernels::KernelParams cos32 = cos16;
    cos32.radius = 32;
    for (const Layer& L : {Layer{"cosine r16 d16", cos16, 16, false},
                           Layer{"cosine r32 d16", cos32, 16, false},
                           Layer{"gaussian sigma 8 d16", gauss8, 16, false},
                           Layer{"gabor r16 f 1/8 d16 (random turns)", gabor16, 16, true}})
        still_row(L, tol, reps, two);
    std::printf("\nscenes through the Renderer (frames 1.. after frame 0, sequential; the field "
                "before shading; error: the largest frame's rms / the scene's sd)\n");
    for (const char* s : {"drift", "still", "eddies", "ink"}) scene_row(s, quick ? 2 : 4, quick ? 1 : 3, two);
    return 0;
}
