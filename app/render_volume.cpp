// SPDX-License-Identifier: Apache-2.0
#include "app/render_volume.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "app/commands.h"
#include "numeric/errors.h"
#include "output/output.h"
#include "scenes/scenes.h"
#include "scenes/volume_scene.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

/// What the job writes, checked before any frame is rendered (nothing written on bad input).
struct Target {
    bool vdb = false, video = false, sequence = false;
};

Target classify(const VolumeJob& job) {
    Target t;
    t.vdb = output::lower_extension(job.output) == ".vdb";
    t.video = output::is_video_path(job.output);
    t.sequence = !t.video && !expand_pattern(job.output, 0).empty();
    if (!t.vdb && !t.video && !output::is_image_path(job.output))
        throw ValueError(job.output + ": unknown output type for a volume scene: expected OpenVDB "
                         "frames (cloud_####.vdb), a preview image (.png .exr .tif), an image "
                         "pattern or a video (.mp4 .mov .mkv .webm)");
    if (!t.video && !t.sequence && job.last != job.first)
        throw ValueError(job.output + ": one file but " + std::to_string(job.last - job.first + 1) +
                         " frames requested: use a pattern like " +
                         (t.vdb ? "cloud_####.vdb" : "frame_####.png") + ", a video, or --frames N");
    if (t.video && job.resume)
        throw ValueError("--resume: applies to sequences; a video is always written whole");
    const fs::path dir = fs::path(t.sequence ? expand_pattern(job.output, job.first) : job.output).parent_path();
    const std::string d = dir.empty() ? "." : dir.string();
    std::error_code ec;
    if (!fs::is_directory(d, ec) || ::access(d.c_str(), W_OK) != 0)
        throw IoError(job.output + ": output directory " + d + " does not exist or is not writable");
    return t;
}

std::string description(const scenes::Scene& s, long long frame) {
    std::ostringstream d;
    d << "impulse volume scene " << s.path << " (hash " << s.hash << ") seed " << s.seed
      << " frame " << frame << " time " << s.frame_time(frame) << " s";
    return d.str();
}

}  // namespace

int run_volume_render(const scenes::Scene& scene, const VolumeJob& job) {
    const Target t = classify(job);
    const scenes::VolumeSceneConfig& cfg = *scene.volume;
    volume::CloudVolume cloud(cfg.cloud);  // validates; refuses an impulse budget it cannot meet
    const output::Metadata meta = {{"seed", std::to_string(scene.seed)},
                                   {"scene", scene.path},
                                   {"scene_hash", scene.hash}};
    output::VideoWriter writer;
    if (t.video) {
        output::quiet_video_logs();
        output::VideoOptions vo;
        vo.width = cfg.march.width, vo.height = cfg.march.height, vo.fps = scene.output.fps;
        vo.codec = output::video_codec_from_string(scene.output.codec);
        vo.crf = scene.output.crf, vo.preset = scene.output.preset;
        vo.metadata = meta;
        writer.open(job.output, vo);
    }
    const bool progress = !job.quiet && ::isatty(2);
    long long written = 0, skipped = 0;
    // Frames in increasing order: the cloud steps its particles on from the previous frame.
    const long long start = std::llround(scene.output.start_s * scene.output.fps);
    for (long long f = job.first; f <= job.last; ++f) {
        const std::string target = t.sequence ? expand_pattern(job.output, f) : job.output;
        std::error_code ec;
        if (t.sequence && job.resume && fs::exists(target, ec)) {
            ++skipped;
            continue;
        }
        const volume::DensityGrid g = cloud.density(start + f);
        if (t.vdb) {
            output::VdbOptions vo;
            vo.voxel_size = cfg.voxel_size;
            vo.sparse = true;
            output::write_vdb(target, {g.size, g.values}, description(scene, f), vo);
        } else {
            const std::vector<float> rgb = volume::march(g, cfg.march);
            if (t.video) {
                writer.write_frame(rgb.data());
            } else {
                output::Metadata m = meta;
                m.emplace_back("frame", std::to_string(f));
                output::write_rgb_image(target, cfg.march.width, cfg.march.height, rgb, m,
                                        scene.output.bits == 16);
            }
        }
        ++written;
        if (progress)
            std::fprintf(stderr, "\r%lld/%lld frames, %zu impulses ", written + skipped,
                         job.last - job.first + 1, cloud.last_impulse_count());
    }
    if (progress) std::fprintf(stderr, "\n");
    if (t.video) writer.close();
    std::cout << "wrote " << job.output << " (" << written << " frame" << (written == 1 ? "" : "s");
    if (skipped) std::cout << ", " << skipped << " already present";
    if (t.vdb)
        std::cout << ", " << cfg.cloud.size[0] << "x" << cfg.cloud.size[1] << "x" << cfg.cloud.size[2]
                  << " voxels)\n";
    else
        std::cout << ", " << cfg.march.width << "x" << cfg.march.height << ")\n";
    return 0;
}

}  // namespace impulse::app
