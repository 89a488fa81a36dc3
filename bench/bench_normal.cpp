// SPDX-License-Identifier: Apache-2.0
// impulse_bench_normal: ns per normal amplitude, Box–Muller sqrt(-2 ln u) cos(2 pi v) rounded
// to float, over 2^20 pairs of Philox uniforms (the simulator's), on the calling thread:
//  * `libm`: std::log and std::cos (the simulator before sim/normal.h);
//  * `own, scalar`: sim::detail::normal_from_uniforms (cell_birth's, and the fallback);
//  * `own, AVX2`: sim::detail::normals_from_uniforms_avx2 (the still path's batches).
// Rows are interleaved run by run; medians [min-max] of the thread's CPU time over the timed
// runs after one untimed warm-up. See bench/README.md.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "bench/common.h"
#include "sim/normal.h"
#include "numeric/rng.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

struct Row {
    Row(std::string n, std::function<void()> f) : name(std::move(n)), run(std::move(f)) {}
    std::string name;
    std::function<void()> run;
    std::vector<double> ns;
};

}  // namespace

int main(int argc, char** argv) {
    const int reps = argc > 2 && std::string(argv[1]) == "--reps" ? std::atoi(argv[2]) : 15;
    constexpr size_t kN = size_t(1) << 20;
    std::printf(
        "impulse_bench_normal: %zu amplitudes per run, %d timed runs per row, load average %s\n\n",
        kN, reps, loadavg().c_str());
    const numeric::CounterRng rng(1, 0);
    std::vector<double> u(kN), v(kN);
    for (size_t j = 0; j < kN; ++j) {
        const auto r = rng.uniforms(int64_t(j), 0, 0, 0);
        u[j] = r[0];
        v[j] = r[1];
    }
    std::vector<float> out(kN);
    std::vector<Row> rows = {
        {"libm",
         [&] {
             for (size_t j = 0; j < kN; ++j)
                 out[j] = static_cast<float>(std::sqrt(-2.0 * std::log(u[j])) *
                                             std::cos(2.0 * std::numbers::pi * v[j]));
         }},
        {"own, scalar", [&] {
             for (size_t j = 0; j < kN; ++j)
                 out[j] = static_cast<float>(sim::detail::normal_from_uniforms(u[j], v[j]));
         }}};
    if (numeric::cpu_has_avx2())
        rows.push_back(
            {"own, AVX2",
             [&] { sim::detail::normals_from_uniforms_avx2(kN, u.data(), v.data(), out.data()); }});
    double sink = 0;
    for (auto& r : rows) r.run(), sink += out[kN / 2];  // warm-up
    for (int i = 0; i < reps; ++i)
        for (auto& r : rows) {
            const double c0 = thread_cpu_ms();
            r.run();
            r.ns.push_back((thread_cpu_ms() - c0) * 1e6 / double(kN));
            sink += out[i];
        }
    std::printf("%-14s %24s\n", "row", "cpu ns per amplitude");
    for (auto& r : rows) std::printf("%-14s %24s\n", r.name.c_str(), cell(summarise(r.ns)).c_str());
    if (!numeric::cpu_has_avx2()) std::printf("(no AVX2 on this CPU)\n");
    std::printf("(checksum %g)\n", sink);
}
