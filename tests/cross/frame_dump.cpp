// SPDX-License-Identifier: Apache-2.0
// impulse_frame_dump: frames of a scene as raw float32, for comparing builds bit for bit across
// CPUs and instruction sets (scripts/arm64_check.sh; docs/contributing.md "Other CPUs"). It
// links only the core libraries (no image or video library), so it cross-builds where the
// tool's I/O libraries are not wanted.
//
//   impulse_frame_dump SCENE WxH FRAMES OUT [key=value...]
//
// SCENE: a built-in scene's name or a file; WxH: render's --size; FRAMES: comma-separated frame
// numbers in increasing order (output.frames is raised to reach the last, as a still scene has
// one frame); key=value: render's --set. Frame f goes to OUT-f<f>.f32: the
// float field (width x height, rows top first), then the display RGB (3 floats a pixel) that
// `render -o x.png` would quantise. For a volume scene: the density grid, then the ray-marched
// preview's RGB. Native byte order (little-endian on x86-64 and arm64 Linux).
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/scenes.h"
#include "scenes/volume_scene.h"

namespace {

using namespace impulse;

struct Request {
    std::string scene;
    scenes::OutputSize size;
    std::vector<long long> frames;
    std::string out;
    std::vector<std::string> overrides;
};

[[noreturn]] void refuse(const std::string& what) { throw ValueError(what); }

scenes::OutputSize parse_size(const std::string& s) {
    int w = 0, h = 0;
    char x = 0, rest = 0;
    if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &rest) != 3 || x != 'x' || w < 1 || h < 1 ||
        w > 32768 || h > 32768)
        refuse("size " + s + ": expected WxH in pixels, each in [1, 32768], e.g. 96x54");
    return {w, h};
}

std::vector<long long> parse_frames(const std::string& s) {
    std::vector<long long> frames;
    size_t at = 0;
    while (at <= s.size()) {
        const size_t comma = std::min(s.find(',', at), s.size());
        const std::string item = s.substr(at, comma - at);
        size_t used = 0;
        long long f = -1;
        try {
            f = std::stoll(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == 0 || used != item.size() || f < 0 || (!frames.empty() && f <= frames.back()))
            refuse("frames " + s + ": expected frame numbers >= 0 in increasing order, e.g. 0,7");
        frames.push_back(f);
        at = comma + 1;
    }
    return frames;
}

Request parse(int argc, char** argv) {
    if (argc < 5)
        refuse("usage: impulse_frame_dump SCENE WxH FRAMES OUT [key=value...]");
    Request r{argv[1], parse_size(argv[2]), parse_frames(argv[3]), argv[4], {}};
    for (int i = 5; i < argc; ++i) r.overrides.emplace_back(argv[i]);
    return r;
}

/// Writes the floats of `parts` one after another to `path`, through a temporary file renamed
/// into place, so a failed run leaves no half-written frame.
void write_floats(const std::string& path, const std::vector<const std::vector<float>*>& parts) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
        for (const auto* p : parts)
            f.write(reinterpret_cast<const char*>(p->data()), std::streamsize(p->size() * 4));
        if (!f.flush()) {
            std::filesystem::remove(tmp);
            throw IoError(path + ": cannot write");
        }
    }
    std::filesystem::rename(tmp, path);
}

std::string frame_path(const Request& r, long long f) {
    return r.out + "-f" + std::to_string(f) + ".f32";
}

void dump_volume(const scenes::Scene& scene, const Request& r) {
    const scenes::VolumeSceneConfig& cfg = *scene.volume;
    volume::CloudVolume cloud(cfg.cloud);
    const long long start = std::llround(scene.output.start_s * scene.output.fps);
    for (long long f : r.frames) {  // increasing: the cloud steps its particles on
        const volume::DensityGrid g = cloud.density(start + f);
        const std::vector<float> rgb = volume::march(g, cfg.march);
        write_floats(frame_path(r, f), {&g.values, &rgb});
    }
}

void dump_layers(scenes::Scene scene, const Request& r) {
    scenes::Renderer renderer(std::move(scene));
    const scenes::Scene& sc = renderer.scene();
    const output::ValueMapping mapping = renderer.mapping();
    render::Frame field;
    std::vector<float> rgb;
    for (long long f : r.frames) {
        renderer.render(f, field);
        output::shade(field, mapping, sc.shading_at(sc.frame_time(f)), rgb);
        write_floats(frame_path(r, f), {&field.data, &rgb});
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const Request r = parse(argc, argv);
        const std::string path = scenes::resolve_scene(r.scene);
        scenes::Scene scene = scenes::load_scene(path, r.overrides, r.size);
        if (r.frames.back() >= scene.output.frames) {  // a still scene's one frame: make room
            std::vector<std::string> more = r.overrides;
            more.push_back("output.frames=" + std::to_string(r.frames.back() + 1));
            scene = scenes::load_scene(path, more, r.size);
        }
        if (scene.volume)
            dump_volume(scene, r);
        else
            dump_layers(std::move(scene), r);
        return 0;
    } catch (const std::exception& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
}
