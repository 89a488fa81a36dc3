// SPDX-License-Identifier: Apache-2.0
// impulse_bench_solid: solid noise (issue 17 item 6) — sparse convolution (cosine kernel, 16
// impulses per kernel volume, R = 8) against this project's Perlin and value noise (lattice
// spacing 8), side by side in one run: a 256^3 grid and 10^6 random points in the same cube,
// points per second (median of several runs, all threads) and the sparse / Perlin cost ratio.
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

template <class F>
Stats time_runs(int runs, const F& f) {
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r) {
        const auto t0 = Clock::now();
        f();
        ms.push_back(ms_since(t0));
    }
    return summarise(ms);
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 256;
    const int runs = argc > 2 ? std::atoi(argv[2]) : 3;
    // For profiles (callgrind: bench/README.md): only one noise, and fewer random points.
    const std::string only = argc > 3 ? argv[3] : "all";
    const size_t npts = argc > 4 ? size_t(std::atol(argv[4])) : 1000000;
    const bool grid = argc <= 5 || std::string(argv[5]) != "points";  // "points": skip the grid
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

    const double grid_pts = double(n) * n * n;
    std::printf("# solid noise, %d^3 grid and 10^6 random points in [0, %d)^3; load %s\n", n, n,
                loadavg().c_str());
    std::printf("%-34s %14s %14s\n", "", "grid Mpts/s", "points Mpts/s");
    auto row = [&](const char* name, const auto& noise) {
        if (only != "all" && std::string(name).rfind(only, 0) != 0) return std::pair<double, double>{1.0, 1.0};
        const Stats g = time_runs(grid ? runs : 0, [&] { out = noise.grid(n, n, n, {}); });
        const Stats p = time_runs(runs, [&] { noise.evaluate(pts, out); });
        std::printf("%-34s %14.2f %14.2f\n", name, grid_pts / g.med / 1e3, double(npts) / p.med / 1e3);
        return std::pair<double, double>{g.med, p.med};
    };
    const auto s = row("sparse cosine R=8, 16/kernel vol", sparse);
    const auto pe = row("perlin (Hermite), spacing 8", perlin);
    row("value (Hermite), spacing 8", value);
    std::printf("sparse / perlin time per point: grid %.2fx, random points %.2fx (target <= 2x)\n",
                s.first / pe.first, s.second / pe.second);
    return 0;
}
