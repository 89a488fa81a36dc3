// SPDX-License-Identifier: Apache-2.0
// impulse_bench_region: what birth regions and field transforms cost.
//  * Births for a 4096 x 4096 still view (cosine r = 16, density 16) confined to a disc of
//    radius 256 with a feather of 32 (1.3 % of the view): the simulator as it is (cells outside
//    the region's box skipped), the same region without culling (every cell generated, every
//    birth thinned), and no region at all.
//  * The marble and wood transforms (and wood with random ring widths) on a 1280 x 720 frame,
//    one thread.
// Rows are interleaved run by run; times are medians [min-max] in ms over the timed runs after
// one untimed warm-up: wall (std::chrono::steady_clock) and the thread's CPU time
// (CLOCK_THREAD_CPUTIME_ID, not inflated when other processes take the core; every row runs on
// the calling thread). See bench/README.md.

#include <tbb/task_arena.h>

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "bench/common.h"
#include "output/output.h"
#include "render/render.h"
#include "sim/sim.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

struct Row {
    Row(std::string n, std::function<size_t()> f) : name(std::move(n)), run(std::move(f)) {}
    std::string name;
    std::function<size_t()> run;  ///< returns a count to print (impulses) or 0
    std::vector<double> ms, cpu_ms;
    size_t count = 0;
};

void time_rows(std::vector<Row>& rows, int reps) {
    for (auto& r : rows) r.count = r.run();  // warm-up
    for (int i = 0; i < reps; ++i)
        for (auto& r : rows) {
            const auto t0 = Clock::now();
            const double c0 = thread_cpu_ms();
            r.run();
            r.cpu_ms.push_back(thread_cpu_ms() - c0);
            r.ms.push_back(ms_since(t0));
        }
}

}  // namespace

int main(int argc, char** argv) {
    const int reps = argc > 2 && std::string(argv[1]) == "--reps" ? std::atoi(argv[2]) : 15;
    std::printf("impulse_bench_region: %d timed runs per row, load average %s\n\n", reps,
                loadavg().c_str());

    // Births.
    sim::ProcessConfig c;
    c.seed = 1;
    c.cell_size = 16.0;
    c.intensity = 16.0 / (std::numbers::pi * 256.0);
    const numeric::Box view{0, 0, 4096, 4096};
    const auto region =
        sim::make_shape_region(sim::make_circle_shape(2048, 2048, 256), 32.0, false);
    sim::ProcessConfig culled = c, unculled = c;
    culled.region = region;
    unculled.region = sim::without_support(region);
    auto births = [&](const sim::ProcessConfig& cfg) {
        return [cfg, &view]() {
            sim::LayerSimulator s(cfg, nullptr, {}, 16.0);
            sim::Impulses imp;
            s.impulses_at(0, view, imp);
            return imp.size();
        };
    };
    std::vector<Row> gen = {{"region, culled", births(culled)},
                            {"region, every cell", births(unculled)},
                            {"no region", births(c)}};
    time_rows(gen, reps);
    std::printf("births for a 4096^2 still view, cosine r = 16, density 16, disc r = 256:\n");
    std::printf("%-20s %10s %24s %24s\n", "row", "impulses", "wall ms", "cpu ms");
    for (auto& r : gen)
        std::printf("%-20s %10zu %24s %24s\n", r.name.c_str(), r.count,
                    cell(summarise(r.ms)).c_str(), cell(summarise(r.cpu_ms)).c_str());
    const double culled_ms = summarise(gen[0].cpu_ms).med, every_ms = summarise(gen[1].cpu_ms).med,
                 none_ms = summarise(gen[2].cpu_ms).med;
    std::printf("cpu time: culling is %.1fx faster than generating every cell; %.1fx faster than no region\n\n",
                every_ms / culled_ms, none_ms / culled_ms);

    // Transforms.
    render::View v;
    v.width = 1280, v.height = 720;
    render::Frame field;
    field.resize(v.width, v.height);
    for (size_t i = 0; i < field.data.size(); ++i)
        field.data[i] = static_cast<float>((i * 2654435761u % 1000) / 500.0 - 1.0);
    render::Frame work = field;
    output::FieldTransform marble, wood, growth;
    marble.type = output::FieldTransform::Type::Marble;
    wood.type = growth.type = output::FieldTransform::Type::Wood;
    wood.center_x = growth.center_x = 400, wood.center_y = growth.center_y = 500;
    growth.growth = 0.4;
    tbb::task_arena one(1);  // on the calling thread, so its CPU time is the transform's
    auto transform = [&](const output::FieldTransform& t) {
        return [&, t]() {
            work.data = field.data;  // same input each run (copy inside the timer for every row)
            one.execute([&] { output::apply_transform(t, v, 0.0, 1.0, work); });
            return size_t(0);
        };
    };
    std::vector<Row> tr = {{"copy only", [&]() { work.data = field.data; return size_t(0); }},
                           {"marble", transform(marble)},
                           {"wood", transform(wood)},
                           {"wood, growth 0.4", transform(growth)}};
    time_rows(tr, reps);
    std::printf("transforms of a 1280x720 frame, 1 thread (the copy of the input included):\n");
    std::printf("%-20s %24s %24s\n", "row", "wall ms", "cpu ms");
    for (auto& r : tr)
        std::printf("%-20s %24s %24s\n", r.name.c_str(), cell(summarise(r.ms)).c_str(),
                    cell(summarise(r.cpu_ms)).c_str());
    std::printf("\nload average after: %s\n", loadavg().c_str());
    return 0;
}
