// SPDX-License-Identifier: Apache-2.0
// impulse_bench_mesh: vertices per second of solid texturing (wood, Lewis 1989 §5.1) and
// stochastic deformation (§5.3) of a 10^6-vertex mesh generated here (a 1000 x 1000 grid of
// quads wrapped on a unit sphere), median of several runs, all threads; and of writing it as
// PLY through assimp. See bench/README.md.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "bench/common.h"
#include "mesh/mesh.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

/// n x n vertices on the unit sphere (latitude-longitude), (n-1)^2 quads.
mesh::Mesh sphere_grid(int n) {
    mesh::Mesh m;
    m.positions.reserve(size_t(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double th = std::numbers::pi * (j + 0.5) / n, ph = 2 * std::numbers::pi * i / n;
            m.positions.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
        }
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const auto v = uint32_t(j * n + i);
            m.add_face({v, v + 1, v + uint32_t(n) + 1, v + uint32_t(n)});
        }
    return m;
}

/// Wall milliseconds (median of runs) and CPU seconds of this process per run (all threads: not
/// inflated when other processes take the cores, which wall time is on a loaded machine).
struct Timing {
    Stats wall;
    Stats cpu;
};

template <class F>
Timing time_runs(int runs, const F& f) {
    std::vector<double> ms, cpu;
    for (int r = 0; r < runs; ++r) {
        const auto t0 = Clock::now();
        const double c0 = own_cpu_s();
        f();
        ms.push_back(ms_since(t0));
        cpu.push_back(own_cpu_s() - c0);
    }
    return {summarise(ms), summarise(cpu)};
}

void row(const char* name, double verts, const Timing& t) {
    std::printf("%-32s %9.3f %11.3f   %s\n", name, verts / t.wall.med / 1e3, verts / t.cpu.med / 1e6,
                cell(t.wall).c_str());
}

}  // namespace

int main(int argc, char** argv) {
    const int n = argc > 1 ? std::atoi(argv[1]) : 1000;
    const int runs = argc > 2 ? std::atoi(argv[2]) : 3;
    mesh::Mesh m = sphere_grid(n);
    const double verts = double(m.vertex_count());
    mesh::SolidTexture wood;
    wood.noise.kernel.radius = 0.33;
    wood.transform.type = output::FieldTransform::Type::Wood;
    wood.transform.ring_width = 0.1;
    mesh::DeformParams deform;
    deform.noise.kernel.radius = 0.33;
    deform.amount = 0.05;
    std::printf("# mesh, %.0f vertices on a unit sphere, noise R = 0.33 (cosine, 16 per kernel volume); load %s\n",
                verts, loadavg().c_str());
    std::printf("%-32s %9s %11s   %s\n", "", "Mvert/s", "Mvert/cpu-s", "wall ms median [min-max]");
    row("texture (wood: 1 noise + ramp)", verts, time_runs(runs, [&] { mesh::texture_mesh(wood, m); }));
    row("deform (3 noise components)", verts, time_runs(runs, [&] { mesh::deform_mesh(deform, m); }));
    const std::string path = (std::filesystem::temp_directory_path() / "impulse_bench_mesh.ply").string();
    row("write ASCII PLY (assimp)", verts, time_runs(runs, [&] { mesh::write_mesh(path, m); }));
    std::filesystem::remove(path);
    return 0;
}
