// SPDX-License-Identifier: Apache-2.0
// impulse_bench_volume: volumetric clouds (issue 21 item 9) — one 256^3 cloud frame (the
// scenes/cloudvolume.toml model at 256^3: four octaves from R = 28, density 6, wind plus curl
// noise) from birth (random access) and stepped on from the previous frame (sequential), the
// write of its OpenVDB file, and the ray-marched 1920x1080 preview of it. Median [min-max] ms
// over the runs, all threads. See bench/README.md.

#include <cstdio>
#include <filesystem>
#include <vector>

#include "bench/common.h"
#include "output/volume.h"
#include "volume/volume.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

volume::CloudConfig cloud_256() {
    volume::CloudConfig c;
    c.seed = 7;
    c.size = {256, 256, 256};
    c.kernel.radius = 28.0;
    c.density = 6.0;
    c.octaves = 4;
    c.lifetime_s = 2.0;
    c.fps = 24.0;
    auto sum = std::make_shared<volume::FlowSum3>();
    sum->push(volume::make_uniform_flow3({6.0, 0.0, 0.0}));
    sum->push(volume::make_curl_flow3(7, 40.0, 3.0));
    c.flow = sum;
    c.shape.threshold = 0.45;
    return c;
}

}  // namespace

int main(int argc, char** argv) {
    const int runs = argc > 1 ? std::atoi(argv[1]) : 3;
    const std::string vdb = (std::filesystem::temp_directory_path() / "impulse_bench_cloud.vdb").string();
    // Wall and CPU (all threads) ms per row: on a busy machine the CPU time is the steadier figure.
    std::vector<double> first, next, write, march, cfirst, cnext, cwrite, cmarch;
    auto cpu_ms = [] { return 1e3 * own_cpu_s(); };
    size_t impulses = 0, active = 0;
    volume::DensityGrid g;
    for (int r = 0; r < runs; ++r) {
        volume::CloudVolume cloud(cloud_256());
        auto t0 = Clock::now();
        double c0 = cpu_ms();
        g = cloud.density(48);  // from birth: every live particle integrated over its age
        first.push_back(ms_since(t0)), cfirst.push_back(cpu_ms() - c0);
        t0 = Clock::now(), c0 = cpu_ms();
        g = cloud.density(49);  // one step on
        next.push_back(ms_since(t0)), cnext.push_back(cpu_ms() - c0);
        impulses = cloud.last_impulse_count();
        output::VdbOptions vo;
        vo.sparse = true;
        t0 = Clock::now(), c0 = cpu_ms();
        output::write_vdb(vdb, {g.size, g.values}, "bench", vo);
        write.push_back(ms_since(t0)), cwrite.push_back(cpu_ms() - c0);
        volume::MarchOptions mo;
        mo.width = 1920, mo.height = 1080;
        t0 = Clock::now(), c0 = cpu_ms();
        const std::vector<float> rgb = volume::march(g, mo);
        march.push_back(ms_since(t0)), cmarch.push_back(cpu_ms() - c0);
    }
    active = 0;
    for (float v : g.values) active += v != 0.0f;
    std::printf("impulse_bench_volume: 256^3 cloud, 4 octaves, %zu live impulses, %.1f %% voxels "
                "non-zero, load %s\n", impulses, 100.0 * double(active) / double(g.values.size()),
                loadavg().c_str());
    auto row = [](const char* what, const std::vector<double>& wall, const std::vector<double>& cpu) {
        std::printf("%-34s wall %s ms, cpu %s ms\n", what, cell(summarise(wall)).c_str(),
                    cell(summarise(cpu)).c_str());
    };
    row("frame from birth (random access)", first, cfirst);
    row("next frame (sequential)", next, cnext);
    row("write OpenVDB (sparse)", write, cwrite);
    std::printf("%-34s %.1f MB\n", "  its file", double(std::filesystem::file_size(vdb)) / 1e6);
    row("ray-marched preview 1920x1080", march, cmarch);
    std::filesystem::remove(vdb);
    return 0;
}
