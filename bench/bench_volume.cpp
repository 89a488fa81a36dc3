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
    std::vector<double> first, next, write, march;
    size_t impulses = 0, active = 0;
    volume::DensityGrid g;
    for (int r = 0; r < runs; ++r) {
        volume::CloudVolume cloud(cloud_256());
        auto t0 = Clock::now();
        g = cloud.density(48);  // from birth: every live particle integrated over its age
        first.push_back(ms_since(t0));
        t0 = Clock::now();
        g = cloud.density(49);  // one step on
        next.push_back(ms_since(t0));
        impulses = cloud.last_impulse_count();
        output::VdbOptions vo;
        vo.sparse = true;
        t0 = Clock::now();
        output::write_vdb(vdb, {g.size, g.values}, "bench", vo);
        write.push_back(ms_since(t0));
        volume::MarchOptions mo;
        mo.width = 1920, mo.height = 1080;
        t0 = Clock::now();
        const std::vector<float> rgb = volume::march(g, mo);
        march.push_back(ms_since(t0));
    }
    active = 0;
    for (float v : g.values) active += v != 0.0f;
    std::printf("impulse_bench_volume: 256^3 cloud, 4 octaves, %zu live impulses, %.1f %% voxels "
                "non-zero, load %s\n", impulses, 100.0 * double(active) / double(g.values.size()),
                loadavg().c_str());
    std::printf("%-34s %s ms\n", "frame from birth (random access)", cell(summarise(first)).c_str());
    std::printf("%-34s %s ms\n", "next frame (sequential)", cell(summarise(next)).c_str());
    std::printf("%-34s %s ms (%.1f MB)\n", "write OpenVDB (sparse)", cell(summarise(write)).c_str(),
                double(std::filesystem::file_size(vdb)) / 1e6);
    std::printf("%-34s %s ms\n", "ray-marched preview 1920x1080", cell(summarise(march)).c_str());
    std::filesystem::remove(vdb);
    return 0;
}
