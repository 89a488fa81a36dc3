// SPDX-License-Identifier: Apache-2.0
// impulse_bench_solid: solid noise (issue 17 item 6) — sparse convolution (cosine kernel, 16
// impulses per kernel volume, R = 8) against this project's Perlin and value noise (lattice
// spacing 8), side by side in one run: a N^3 grid and 10^6 random points in the same cube,
// points per second (median of the runs, all threads) as wall time and as the process's CPU
// time (all threads: steadier when other work shares the cores), and the sparse / Perlin ratios.
// The noises take turns within each round, so a change of load hits them alike.
// See bench/README.md.

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench/common.h"
#include "synth/synth.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

/// Wall and CPU milliseconds of each run of one case.
struct Timings {
    std::vector<double> wall, cpu;
};

template <class F>
void time_once(Timings& t, const F& f) {
    const double c0 = own_cpu_s();
    const auto t0 = Clock::now();
    f();
    t.wall.push_back(ms_since(t0));
    t.cpu.push_back(1e3 * (own_cpu_s() - c0));
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 256;
    const int runs = argc > 2 ? std::atoi(argv[2]) : 3;
    // For profiles (callgrind: bench/README.md): only one noise, and fewer random points.
    const std::string only = argc > 3 ? argv[3] : "all";
    const size_t npts = argc > 4 ? size_t(std::atol(argv[4])) : 1000000;
    const bool with_grid = argc <= 5 || std::string(argv[5]) != "points";  // "points": no grid
    synth::SolidParams sp;
    sp.kernel.radius = 8.0;
    sp.density = 16.0;
    const synth::SolidNoise sparse(sp);
    synth::LatticeParams lp;
    lp.spacing = 8.0;
    lp.method = synth::LatticeMethod::Perlin;
    const synth::LatticeNoise perlin(lp);
    lp.method = synth::LatticeMethod::Value;
    const synth::LatticeNoise value(lp);

    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(0.0, n);
    std::vector<synth::SolidPoint> pts(npts);
    for (auto& p : pts) p = {u(rng), u(rng), u(rng), 0.0};
    std::vector<float> out;

    const char* names[3] = {"sparse cosine R=8, 16/kernel vol", "perlin (Hermite), spacing 8",
                            "value (Hermite), spacing 8"};
    auto wanted = [&](int i) { return only == "all" || std::string(names[i]).rfind(only, 0) == 0; };
    Timings grid_t[3], pts_t[3];
    auto one = [&](int i, const auto& noise) {
        if (!wanted(i)) return;
        if (with_grid) time_once(grid_t[i], [&] { out = noise.grid(n, n, n, {}); });
        time_once(pts_t[i], [&] { noise.evaluate(pts, out); });
    };
    const std::string load0 = loadavg();
    for (int r = 0; r < runs; ++r) {  // the noises in turn, round after round
        one(0, sparse);
        one(1, perlin);
        one(2, value);
    }
    const double grid_pts = double(n) * n * n;
    std::printf("# solid noise, %d^3 grid and %zu random points in [0, %d)^3, %d runs; load %s -> %s\n",
                n, npts, n, runs, load0.c_str(), loadavg().c_str());
    std::printf("%-34s %12s %12s %12s %12s\n", "Mpts/s (median)", "grid wall", "grid cpu",
                "points wall", "points cpu");
    double med[3][4] = {};
    for (int i = 0; i < 3; ++i) {
        if (!wanted(i)) continue;
        const Timings* t[4] = {&grid_t[i], &grid_t[i], &pts_t[i], &pts_t[i]};
        for (int c = 0; c < 4; ++c) med[i][c] = summarise(c % 2 ? t[c]->cpu : t[c]->wall).med;
        auto rate = [](double count, double ms) { return ms > 0 ? count / ms / 1e3 : 0.0; };
        std::printf("%-34s %12.2f %12.2f %12.2f %12.2f\n", names[i], rate(grid_pts, med[i][0]),
                    rate(grid_pts, med[i][1]), rate(double(npts), med[i][2]),
                    rate(double(npts), med[i][3]));
    }
    if (wanted(0) && wanted(1))
        std::printf("sparse / perlin time per point: grid %.2fx wall %.2fx cpu, random points %.2fx "
                    "wall %.2fx cpu (target <= 2x)\n",
                    med[0][0] / med[1][0], med[0][1] / med[1][1], med[0][2] / med[1][2],
                    med[0][3] / med[1][3]);
    return 0;
}
