// SPDX-License-Identifier: Apache-2.0
// impulse_bench_sequence: a 1920x1080 layer advected by a 128^3 OpenVDB velocity sequence
// ([[layer.flow]] type = "sequence", a slice of the grid) against the same scene with an
// analytic curl flow of the same RMS speed and scale, rendered side by side (each row once per
// repetition, in turn) through scenes::Renderer with 2 threads, frames in order (each frame
// moves the live impulses one frame and, for the sequence, reads the frames it comes to). The
// sequence is written first to a temporary directory: 24 frames of a divergence-free
// Taylor-Green-like field drifting in time, voxel 16 texture units. Figures are the median
// [min-max] over the repetitions after an untimed warm-up (frame 0: every impulse moved from
// its birth). See bench/README.md.

#include <openvdb/openvdb.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <string_view>
#include <vector>

#include "bench/common.h"
#include "render/render.h"
#include "scenes/scenes.h"

namespace {

using namespace impulse;
using namespace impulse::bench;
namespace fs = std::filesystem;

constexpr int kN = 128, kFrames = 24;

/// Frame n: v = A (sin kx cos ky, -cos kx sin ky, 0) shifted by 2 n voxels along x, k = 2 pi /
/// 64 voxels: divergence-free, RMS speed A / sqrt(2) in the plane.
void write_frames(const fs::path& dir, double amplitude) {
    openvdb::initialize();
    const double k = 2.0 * std::numbers::pi / 64.0;
    for (int n = 1; n <= kFrames; ++n) {
        auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        grid->setName("velocity");
        auto acc = grid->getAccessor();
        for (int z = 0; z < kN; ++z)
            for (int y = 0; y < kN; ++y)
                for (int x = 0; x < kN; ++x) {
                    const double X = k * (x + 2.0 * n), Y = k * y;
                    acc.setValue({x, y, z}, openvdb::Vec3s(float(amplitude * std::sin(X) * std::cos(Y)),
                                                           float(-amplitude * std::cos(X) * std::sin(Y)),
                                                           0.0f));
                }
        char name[64];
        std::snprintf(name, sizeof name, "fluid_data_%04d.vdb", n);
        openvdb::io::File file((dir / name).string());
        file.write({grid});
        file.close();
    }
}

std::string scene(const std::string& flow) {
    return "[output]\nsize = [1920, 1080]\nframes = 1000\nfps = 24\n"
           "[camera]\ncenter = [960.0, 540.0]\n"
           "[[layer]]\nseed = 3\nlifetime = 2.0\n[layer.kernel]\nradius = 16.0\n" + flow;
}

struct Row {
    std::string name;
    std::string text;
    std::unique_ptr<scenes::Renderer> renderer;
    std::vector<double> ms;
    double load_ms = 0.0;
};

}  // namespace

int main(int argc, char** argv) try {
    int reps = 12;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "--quick")
            reps = 4;
        else if (a == "--reps" && i + 1 < argc)
            reps = std::max(1, std::atoi(argv[++i]));
        else
            throw std::invalid_argument(std::string(a) + ": usage: impulse_bench_sequence [--quick] [--reps N]");
    }
    const fs::path dir = fs::temp_directory_path() / ("impulse_bench_sequence_" + std::to_string(getpid()));
    fs::create_directories(dir);
    // 30 texture units/s RMS: the in-plane RMS of the field is A / sqrt(2) voxel units, times
    // 16 texture units a voxel
    const double voxel = 16.0, amplitude = 30.0 * std::sqrt(2.0) / voxel;
    write_frames(dir, amplitude);
    std::vector<Row> rows;
    rows.push_back({"curl flow", scene("[[layer.flow]]\ntype = \"curl\"\nscale = 240.0\nspeed = 30.0\n")});
    rows.push_back({"vdb sequence 128^3", scene("[[layer.flow]]\ntype = \"sequence\"\npath = \"" +
                                                (dir / "fluid_data_####.vdb").string() +
                                                "\"\nscale = 16.0\noffset = [0.0, 0.0]\n")});
    tbb::task_arena arena(2);
    render::Frame out;
    arena.execute([&] {
        for (auto& r : rows) {
            const auto t0 = Clock::now();
            r.renderer = std::make_unique<scenes::Renderer>(scenes::load_scene_string(r.text, r.name));
            r.load_ms = ms_since(t0);
            r.renderer->render(0, out);  // warm-up: every impulse moved from its birth
        }
        for (int rep = 1; rep <= reps; ++rep)
            for (auto& r : rows) {
                const auto t0 = Clock::now();
                r.renderer->render(rep, out);
                r.ms.push_back(ms_since(t0));
            }
    });
    fs::remove_all(dir);
    std::printf("1920x1080, 2 threads, %d frames in order; load average before: %s\n", reps,
                loadavg().c_str());
    std::printf("%-20s %-22s %-8s %s\n", "row", "ms per frame", "ratio", "load ms");
    const double ref = summarise(rows[0].ms).med;
    for (const auto& r : rows) {
        const Stats s = summarise(r.ms);
        std::printf("%-20s %-22s %-8.2f %.0f\n", r.name.c_str(), cell(s).c_str(), s.med / ref, r.load_ms);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
}
