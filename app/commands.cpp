// SPDX-License-Identifier: Apache-2.0
// `impulse render`, `impulse scenes`, `impulse info`.

#include "app/commands.h"

#include <tbb/global_control.h>
#include <unistd.h>

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <future>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>

#include "render/render.h"
#include "scenes/scenes.h"
#include "util/errors.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted.store(true); }

/// Progress on a terminal: frames done, rate, time left. Silent when not a terminal or -q.
class Progress {
public:
    Progress(long long total, bool quiet) : m_total(total), m_on(!quiet && ::isatty(2)) {
        m_start = std::chrono::steady_clock::now();
    }
    void update(long long done) {
        if (!m_on) return;
        const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
        const double rate = el > 0 ? done / el : 0.0;
        const double left = rate > 0 ? (m_total - done) / rate : 0.0;
        const int width = 30;
        const int fill = static_cast<int>(width * double(done) / std::max<long long>(1, m_total));
        std::fprintf(stderr, "\r[%s%s] %lld/%lld frames  %.1f fps  %d:%02d left ",
                     std::string(fill, '#').c_str(), std::string(width - fill, '.').c_str(), done,
                     m_total, rate, int(left) / 60, int(left) % 60);
        std::fflush(stderr);
    }
    void done() {
        if (m_on) std::fprintf(stderr, "\n");
    }

private:
    long long m_total;
    bool m_on;
    std::chrono::steady_clock::time_point m_start;
};

std::vector<std::string> overrides_for(const std::vector<std::string>& sets, const std::string& size,
                                       const std::string& seed) {
    std::vector<std::string> o = sets;
    if (!size.empty()) {
        static const std::regex re(R"((\d+)x(\d+))");
        std::smatch m;
        if (!std::regex_match(size, m, re))
            throw ValueError("--size " + size + ": expected WxH in pixels, e.g. 1920x1080");
        o.push_back("output.size=[" + m[1].str() + "," + m[2].str() + "]");
    }
    if (!seed.empty())
        o.push_back("seed=" + std::to_string(whole_number(
                                  "--seed", seed, seed, "an integer in [0, 9223372036854775807]")));
    return o;
}

void ensure_directory(const std::string& path) {
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw IoError(path + ": output directory " + dir.string() + " does not exist");
    const std::string d = dir.empty() ? "." : dir.string();
    if (::access(d.c_str(), W_OK) != 0)
        throw IoError(path + ": output directory " + d + " is not writable");
}

/// True when the scene's shading gives colour (a ramp or relief at some time), not plain grey.
bool colour_shading(const scenes::Scene& s) {
    return !s.shading.ramp.empty() || s.shading_keys.relief.max() != 0.0;
}

}  // namespace

long long whole_number(const std::string& option, const std::string& text, const std::string& digits,
                       const std::string& expected) {
    long long v = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ec != std::errc() || end != digits.data() + digits.size() || v < 0)
        throw ValueError(option + " " + text + ": expected " + expected);
    return v;
}

std::string expand_pattern(const std::string& pattern, long long frame) {
    static const std::regex hashes("#+");
    static const std::regex printf_like("%0?(\\d*)d");
    std::smatch m;
    if (std::regex_search(pattern, m, hashes)) {
        std::ostringstream s;
        s << std::setw(static_cast<int>(m.length(0))) << std::setfill('0') << frame;
        return m.prefix().str() + s.str() + m.suffix().str();
    }
    if (std::regex_search(pattern, m, printf_like)) {
        const int w = m[1].length() ? std::stoi(m[1].str()) : 0;
        std::ostringstream s;
        s << std::setw(w) << std::setfill('0') << frame;
        return m.prefix().str() + s.str() + m.suffix().str();
    }
    return "";
}

std::pair<long long, long long> parse_frame_range(const std::string& text, long long frames) {
    static const std::regex re(R"((\d+)(?:-(\d+))?)");
    std::smatch m;
    if (!std::regex_match(text, m, re))
        throw ValueError("--frames " + text + ": expected A-B or A (inclusive, 0-based frame numbers)");
    const std::string expected = "frame numbers in [0, 9223372036854775807]";
    const long long a = whole_number("--frames", text, m[1].str(), expected);
    const long long b = m[2].matched ? whole_number("--frames", text, m[2].str(), expected) : a;
    if (a > b) throw ValueError("--frames " + text + ": expected A <= B");
    if (b >= frames)
        throw ValueError("--frames " + text + ": outside [0, " + std::to_string(frames) +
                         ") (the scene has output.frames = " + std::to_string(frames) + ")");
    return {a, b};
}

int run_render(const RenderOptions& opt) {
    const std::string path = scenes::resolve_scene(opt.scene);
    auto overrides = overrides_for(opt.sets, opt.size, opt.seed);
    if (!opt.codec.empty()) overrides.push_back("output.codec=\"" + opt.codec + "\"");
    scenes::Scene scene = scenes::load_scene(path, overrides);
    for (const auto& w : scene.warnings) std::cerr << w << "\n";
    long long first = 0, last = scene.output.frames - 1;
    if (!opt.frames.empty()) std::tie(first, last) = parse_frame_range(opt.frames, scene.output.frames);

    const bool video = render::is_video_path(opt.output);
    const bool sequence = !video && !expand_pattern(opt.output, 0).empty();
    if (!video && !sequence) {
        if (!render::is_image_path(opt.output))
            throw ValueError(opt.output + ": unknown output type: expected an image (.exr .png .tif), "
                             "a pattern (frame_####.png) or a video (.mp4 .mov .mkv .webm)");
        if (last != first)
            throw ValueError(opt.output + ": one image but " + std::to_string(last - first + 1) +
                             " frames requested: use a pattern like frame_####.png, a video, or --frames N");
    }
    if (opt.resume && video)
        throw ValueError("--resume: applies to image sequences; a video is always written whole");
    ensure_directory(sequence ? expand_pattern(opt.output, first) : opt.output);

    // Held by pointer so it can be freed before the encoder's flush (below).
    auto renderer = std::make_unique<scenes::Renderer>(std::move(scene));
    const scenes::Scene& sc = renderer->scene();
    const scenes::OutputConfig& out = sc.output;
    const int width = out.width, height = out.height;
    const render::ValueMapping mapping = renderer->mapping();
    render::EvalOptions eo;
    eo.tile_size = opt.tile;

    std::string layer_seeds;
    for (const auto& l : sc.layers) layer_seeds += (layer_seeds.empty() ? "" : " ") + std::to_string(l.process.seed);
    render::Metadata meta = {{"seed", std::to_string(sc.seed)},
                             {"layer_seeds", layer_seeds},
                             {"scene", sc.path},
                             {"scene_hash", sc.hash},
                             {"fps", std::to_string(out.fps)},
                             {"range", std::to_string(mapping.lo) + " " + std::to_string(mapping.hi)}};

    render::VideoWriter writer;
    if (video) {
        render::quiet_video_logs();
        render::VideoOptions vo;
        vo.width = out.width, vo.height = out.height, vo.fps = out.fps;
        vo.codec = render::video_codec_from_string(out.codec);
        vo.crf = out.crf, vo.preset = out.preset;
        vo.metadata = meta;
        writer.open(opt.output, vo);
    }

    g_interrupted = false;
    auto previous = std::signal(SIGINT, on_sigint);
    Progress progress(last - first + 1, opt.quiet);
    // Frame f + 1 renders while frame f is written: on two cores the encoder and the renderer
    // overlap instead of taking turns. Images: two float frames, f + 1 renders while f is
    // shaded and saved. Video: one float frame, shaded band by band straight into the
    // encoder's 8-bit input (no float RGB frame: 100 MiB at 4K) before f + 1 renders into it;
    // the conversion and encoding of f overlap the rendering of f + 1.
    render::Frame frames[2];
    std::vector<float> rgb;
    long long written = 0, skipped = 0;
    // --threads caps TBB's workers process-wide (a task arena would serialise the two threads
    // of the pipeline: an arena admits one outside thread at a time by default).
    std::unique_ptr<tbb::global_control> cap;
    if (opt.threads > 0)
        cap = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    opt.threads);
    auto emit = [&](const render::Frame& frame, long long f, const std::string& target) {
        const double t = sc.frame_time(f);
        const render::Shading shading = sc.shading_at(t);  // keyframed shading at the frame time
        render::Metadata m = meta;
        m.emplace_back("frame", std::to_string(f));
        m.emplace_back("time", std::to_string(t));
        // EXR keeps the raw field; display formats get the shading (grey by default).
        const bool exr = fs::path(target).extension() == ".exr";
        if (!exr && colour_shading(sc)) {
            render::shade(frame, mapping, shading, rgb);
            render::write_rgb_image(target, out.width, out.height, rgb, m, out.bits == 16);
        } else {
            render::write_image(target, frame, mapping, m, out.bits == 16);
        }
    };
    std::future<void> pending;  // the previous frame's output
    auto finish_pending = [&] {
        if (!pending.valid()) return;
        pending.get();  // rethrows an output error
        ++written;
        progress.update(written + skipped);
    };
    int slot = 0;
    for (long long f = first; f <= last; ++f) {
        if (g_interrupted) break;
        const std::string target = sequence ? expand_pattern(opt.output, f) : opt.output;
        if (sequence && opt.resume && fs::exists(target)) {
            ++skipped;
            continue;
        }
        renderer->render(f, frames[slot], eo);
        finish_pending();
        if (video) {
            const render::Frame& frame = frames[slot];
            const render::Shader shader(mapping, sc.shading_at(sc.frame_time(f)));
            writer.stage_frame([&](int y0, int y1, float* band) { shader.rows(frame, y0, y1, band); });
            pending = std::async(std::launch::async, [&] { writer.encode_staged(); });
            continue;  // the frame is free again: f + 1 renders into it
        }
        pending = std::async(std::launch::async,
                             [&, s = slot, f, target] { emit(frames[s], f, target); });
        slot ^= 1;
    }
    finish_pending();
    progress.done();
    std::signal(SIGINT, previous);
    if (video) {
        // Closing flushes the encoder, which then encodes every frame it still holds (x264's
        // lookahead): the peak of a short render. The renderer and the float frames are no
        // longer needed (sc and out refer into the renderer: not used below).
        frames[0] = {}, frames[1] = {};
        renderer.reset();
        writer.close();  // on interruption too: what was encoded stays playable
    }
    if (g_interrupted) {
        std::cerr << "interrupted: " << written << " frames written to " << opt.output << "\n";
        return 130;
    }
    std::cout << "wrote " << opt.output << " (" << written << " frame" << (written == 1 ? "" : "s");
    if (skipped) std::cout << ", " << skipped << " already present";
    std::cout << ", " << width << "x" << height << ")\n";
    return 0;
}

int run_scenes() {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(scenes::builtin_scene_dir(), ec))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& p : files) {
        // The first comment line of a scene file is its one-line description.
        std::ifstream in(p);
        std::string line, desc;
        while (std::getline(in, line))
            if (line.rfind("# ", 0) == 0) {
                desc = line.substr(2);
                break;
            }
        std::printf("%-10s %s\n", p.stem().c_str(), desc.c_str());
    }
    return 0;
}

namespace {

/// A layer's composition for `impulse info`: what differs from a plainly added layer.
std::string composition_text(const scenes::LayerConfig& l) {
    const scenes::Composition& c = l.compose;
    std::ostringstream s;
    if (!c.name.empty()) s << " name=\"" << c.name << "\"";
    if (!c.visible) s << " hidden";
    if (c.blend != scenes::Blend::Add) s << " blend=" << scenes::kBlendNames[size_t(c.blend)];
    if (!c.opacity.is_constant())
        s << " opacity=keyframed";
    else if (c.opacity.value(0.0) != 1.0)
        s << " opacity=" << c.opacity.value(0.0);
    if (c.warp)
        s << " warp=layer[" << c.warp->source[0] << "],layer[" << c.warp->source[1] << "]";
    if (c.orientation) s << " orientation=layer[" << c.orientation->source << "]";
    for (size_t j : c.flow_sources) s << " flow=layer[" << j << "]";
    return s.str();
}

}  // namespace

int run_info(const InfoOptions& opt) {
    const std::string path = scenes::resolve_scene(opt.scene);
    scenes::Scene scene = scenes::load_scene(path, overrides_for(opt.sets, opt.size, ""));
    for (const auto& w : scene.warnings) std::cerr << w << "\n";
    scenes::Renderer r(scene);
    const auto t = scenes::scene_theory(scene);
    std::printf("scene      %s (hash %s)\n", path.c_str(), scene.hash.c_str());
    std::printf("output     %dx%d, %lld frames at %g fps\n", scene.output.width, scene.output.height,
                static_cast<long long>(scene.output.frames), scene.output.fps);
    bool keyframed = false;
    for (const auto& l : scene.layers) keyframed = keyframed || l.keyframed();
    std::printf("mean       %.6g\nvariance   %.6g (%s%s)\n", t.mean, t.variance,
                scenes::is_sum_of_layers(scene)
                    ? "Campbell's theorem"
                    : "Campbell's theorem, layers composed: docs/scenes.md \"Composition\"",
                keyframed ? ", at t = 0: layers are keyframed" : "");
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const auto& l = scene.layers[i];
        const auto lt = scenes::layer_theory(l);
        std::printf("layer[%zu]   %s r=%g density=%g lambda=%.4g/unit^2 variance=%.6g%s%s%s\n", i,
                    std::string(kernels::to_string(l.kernel.type)).c_str(), l.kernel.radius,
                    l.density.value(0.0), l.process.intensity, lt.variance,
                    l.process.lifetime_s > 0 ? " (animated)" : " (still)",
                    l.keyframed() ? " (keyframed)" : "", composition_text(l).c_str());
    }
    std::printf("impulses   ~%.3g per frame, ~%.0f MiB\n", r.estimated_impulses(), r.estimated_memory_mib());
    return 0;
}

}  // namespace impulse::app
