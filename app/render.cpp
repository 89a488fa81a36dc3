// SPDX-License-Identifier: Apache-2.0
// `impulse render`: a scene to an image, an image sequence or a video (docs/scenes.md; the
// channels of app/channels.cpp, volumes by app/render_volume.cpp).

#include "app/commands.h"
#include "app/channels.h"
#include "app/parse.h"
#include "app/render_volume.h"

#include <tbb/global_control.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <future>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <regex>
#include <sstream>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "scenes/volume_scene.h"
#include "numeric/errors.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

// The first stop signal received (0: none): the render loop stops between frames, the video
// is closed so what was encoded plays, and the exit status is 128 + its number.
std::atomic<int> g_signal{0};
extern "C" void on_stop_signal(int signo) {
    int none = 0;
    g_signal.compare_exchange_strong(none, signo);
}

/// Catches SIGINT (Ctrl-C), SIGTERM (timeout, kill, Slurm, container stop) and SIGHUP (a closed
/// terminal or ssh session) while alive. A signal the caller ignores stays ignored (nohup, a
/// background job of a non-interactive shell).
class StopSignals {
public:
    static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
    StopSignals() {
        g_signal = 0;
        struct sigaction sa {};
        sa.sa_handler = on_stop_signal;
        sigemptyset(&sa.sa_mask);
        for (int i = 0; i < 3; ++i) {
            ::sigaction(kSignals[i], nullptr, &m_old[i]);
            if (m_old[i].sa_handler != SIG_IGN) ::sigaction(kSignals[i], &sa, nullptr);
        }
    }
    ~StopSignals() {
        for (int i = 0; i < 3; ++i) ::sigaction(kSignals[i], &m_old[i], nullptr);
    }
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;
    static const char* name(int signo) {
        return signo == SIGINT ? "SIGINT" : signo == SIGTERM ? "SIGTERM" : signo == SIGHUP ? "SIGHUP" : "a signal";
    }

private:
    struct sigaction m_old[3];
};

std::string regex_escape(const std::string& text) {
    static const std::regex special(R"([.^$|()\[\]{}*+?\\])");
    return std::regex_replace(text, special, R"(\$&)");
}

/// A regex matching the file names of `name`'s frames (the pattern's digits captured), where
/// `spot` is the pattern in `name`.
std::regex frame_name_regex(const std::string& name, const PatternSpot& spot) {
    return std::regex(regex_escape(name.substr(0, spot.pos)) + "(\\d+)" +
                      regex_escape(name.substr(spot.pos + spot.length)));
}

/// Removes the temporaries (.NAME.partial-PID.EXT, render/image_io.cpp) of `pattern`'s frames
/// that a killed run left behind: those whose process is gone and that have not been written
/// for a minute (on storage shared by a farm, a PID from another machine may not exist here,
/// but its temporary lives only while one frame's bytes are written). Says what it removes.
void remove_stale_temporaries(const std::string& pattern) {
    const fs::path p(pattern);
    const std::string name = p.filename().string();
    const PatternSpot spot = find_pattern(name);
    if (!spot.found) return;  // the pattern is in the directory part: no names to match
    const std::regex frame = frame_name_regex(name, spot);
    static const std::regex temporary(R"(\.(.+)\.partial-(\d{1,9})(\.[^.]+))");
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string entry = e.path().filename().string();
        std::smatch m;
        if (!std::regex_match(entry, m, temporary) || !std::regex_match(m[1].str() + m[3].str(), frame))
            continue;
        const pid_t pid = static_cast<pid_t>(std::stol(m[2].str()));
        const bool gone = ::kill(pid, 0) != 0 && errno == ESRCH;
        std::error_code tec;
        const auto age = fs::file_time_type::clock::now() - fs::last_write_time(e.path(), tec);
        if (!gone || tec || age < std::chrono::minutes(1)) {
            std::cerr << e.path().string() << ": left in place: "
                      << (gone ? "written less than a minute ago" : "process " + m[2].str() + " is running")
                      << "\n";
            continue;
        }
        if (fs::remove(e.path(), tec))
            std::cerr << "removed " << e.path().string() << ": a stale temporary (process " << m[2].str()
                      << " is gone)\n";
    }
}


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

}  // namespace

scenes::OutputSize parse_size(const std::string& option, const std::string& text) {
    if (text.empty()) return {};
    const std::vector<long long> n = parse_dimensions(text);
    const auto in_range = [](long long v) { return v >= 1 && v <= 32768; };
    if (n.size() != 2 || !in_range(n[0]) || !in_range(n[1]))
        throw ValueError(option + " " + text.substr(0, 40) +
                         ": expected WxH in pixels, each in [1, 32768], e.g. 1920x1080");
    return {static_cast<int>(n[0]), static_cast<int>(n[1])};
}

std::vector<std::string> overrides_for(const std::vector<std::string>& sets, const std::string& crop,
                                       const std::string& seed) {
    std::vector<std::string> o = sets;
    if (const scenes::OutputSize c = parse_size("--crop", crop); c.width > 0)
        o.push_back("output.size=[" + std::to_string(c.width) + "," + std::to_string(c.height) + "]");
    if (!seed.empty())
        o.push_back("seed=" + std::to_string(whole_number(
                                  "--seed", seed, seed, "an integer in [0, 9223372036854775807]")));
    return o;
}

namespace {

/// Why the file `target` present for --resume is not frame `f` of `sc` as this run would
/// write it ("" when it is): output::image_mismatch with the run's size, channels and metadata.
std::string present_frame_mismatch(const std::string& target, const scenes::Scene& sc, long long f,
                                   const ChannelPlan& plan) {
    const bool exr = fs::path(target).extension() == ".exr";
    const int channels = plan.active ? int(plan.names.size()) : !exr && colour_shading(sc) ? 3 : 1;
    const output::Metadata expected = {
        {"seed", std::to_string(sc.seed)}, {"frame", std::to_string(f)}, {"scene_hash", sc.hash}};
    return output::image_mismatch(target, sc.output.width, sc.output.height, channels,
                                  sc.output.bits == 16, expected);
}

}  // namespace

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
    return !s.shading.ramp.empty() || s.shading_keys.relief.max() != 0.0 || s.shading.toe > 0.0 ||
           s.shading.shoulder > 0.0;
}

long long whole_number(const std::string& option, const std::string& text, const std::string& digits,
                       const std::string& expected) {
    long long v = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (ec != std::errc() || end != digits.data() + digits.size() || v < 0)
        throw ValueError(option + " " + text + ": expected " + expected);
    return v;
}


PatternSpot find_pattern(const std::string& path) {
    static const std::regex token("#+|%0?(\\d*)d");
    PatternSpot spot;
    for (auto it = std::sregex_iterator(path.begin(), path.end(), token); it != std::sregex_iterator();
         ++it) {
        const std::smatch& m = *it;
        if (spot.found)
            throw ValueError(path + ": two frame-number patterns (\"" + path.substr(spot.pos, spot.length) +
                             "\" and \"" + m.str(0) + "\"): expected one, e.g. frame_####.png");
        spot.found = true;
        spot.pos = size_t(m.position(0)), spot.length = size_t(m.length(0));
        const bool hashes = m.str(0)[0] == '#';
        // A single # is 4 digits (Shake's and Nuke's convention): frame_#.png sorts as it plays.
        const size_t width = hashes ? (m.length(0) == 1 ? 4 : size_t(m.length(0)))
                             : m[1].length() > 2 ? 100
                             : m[1].length()     ? size_t(std::stoi(m[1].str()))
                                                 : 0;
        if (width > 19)
            throw ValueError(path.substr(0, std::min<size_t>(path.size(), 200)) +
                             ": frame-number pattern wider than 19 digits (2^63 has 19)");
        spot.width = int(width);
    }
    return spot;
}

std::string expand_pattern(const std::string& pattern, long long frame) {
    const PatternSpot spot = find_pattern(pattern);
    if (!spot.found) return "";
    std::ostringstream s;
    s << std::setw(spot.width) << std::setfill('0') << frame;
    return pattern.substr(0, spot.pos) + s.str() + pattern.substr(spot.pos + spot.length);
}

std::vector<long long> frames_present(const std::string& pattern) {
    const fs::path p(pattern);
    const std::string name = p.filename().string();
    const PatternSpot spot = find_pattern(name);
    if (!spot.found) return {};
    const std::regex frame = frame_name_regex(name, spot);
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::vector<long long> found;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string entry = e.path().filename().string();
        std::smatch m;
        if (!std::regex_match(entry, m, frame) || m[1].length() > 18) continue;
        const long long f = std::stoll(m[1].str());
        // Only names the pattern gives (f_0007.png, not f_7.png for ####).
        if (expand_pattern(name, f) == entry) found.push_back(f);
    }
    std::sort(found.begin(), found.end());
    return found;
}

long long first_frame_present(const std::string& pattern) {
    const std::vector<long long> found = frames_present(pattern);
    return found.empty() ? -1 : found.front();
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

scenes::Scene load_render_scene(const RenderOptions& opt) {
    const std::string path = scenes::resolve_scene(opt.scene);
    auto overrides = overrides_for(opt.sets, opt.crop, opt.seed);
    if (!opt.codec.empty()) overrides.push_back("output.codec=\"" + opt.codec + "\"");
    scenes::Scene scene = scenes::load_scene(path, overrides, parse_size("--size", opt.size));
    for (const auto& w : scene.warnings) std::cerr << w << "\n";
    return scene;
}

/// -o, or without it out/SCENE.mp4 (out/SCENE.png for one frame: README's first command works).
std::string render_output(const RenderOptions& opt, const std::string& scene_path, bool one_frame) {
    if (!opt.output.empty()) return opt.output;
    const std::string output =
        "out/" + fs::path(scene_path).stem().string() + (one_frame ? ".png" : ".mp4");
    std::error_code ec;
    fs::create_directories("out", ec);
    std::cerr << "output: " << output << " (-o to choose)\n";
    return output;
}

struct OutputKind {
    bool video = false, sequence = false;
};

/// A video, an image sequence or one image; refuses what cannot hold the frames asked for.
OutputKind output_kind(const std::string& output, long long first, long long last, bool resume) {
    OutputKind k;
    k.video = output::is_video_path(output);
    k.sequence = !k.video && !expand_pattern(output, 0).empty();
    if (!k.video && !k.sequence) {
        if (!output::is_image_path(output))
            throw ValueError(output + ": unknown output type: expected an image (.exr .png .tif), "
                             "a pattern (frame_####.png) or a video (.mp4 .mov .mkv .webm)");
        if (last != first)
            throw ValueError(output + ": one image but " + std::to_string(last - first + 1) +
                             " frames requested: use a pattern like frame_####.png, a video, or --frames N");
    }
    if (resume && k.video)
        throw ValueError("--resume: applies to image sequences; a video is always written whole");
    return k;
}

/// The metadata every frame of the run carries (frame and time are added per frame).
output::Metadata run_metadata(const scenes::Scene& sc, const output::ValueMapping& mapping,
                              const RenderOptions& opt) {
    std::string layer_seeds;
    for (const auto& l : sc.layers) layer_seeds += (layer_seeds.empty() ? "" : " ") + std::to_string(l.process.seed);
    output::Metadata m = {{"seed", std::to_string(sc.seed)},
                          {"layer_seeds", layer_seeds},
                          {"scene", sc.path},
                          {"scene_hash", sc.hash},
                          {"fps", std::to_string(sc.output.fps)},
                          {"range", std::to_string(mapping.lo) + " " + std::to_string(mapping.hi)}};
    // The framing the frames were rendered at, for `impulse analyze --scene` (its theory is
    // taken at the same --size and --crop; docs/channels.md "Camera metadata").
    if (sc.resized.width > 0)
        m.emplace_back("size", std::to_string(sc.resized.width) + "x" + std::to_string(sc.resized.height));
    if (!opt.crop.empty()) m.emplace_back("crop", opt.crop);
    return m;
}

/// Frame f's own metadata: frame number, time and the camera that saw it.
void add_frame_metadata(const scenes::Scene& sc, long long f, output::Metadata& m) {
    const double t = sc.frame_time(f);
    m.emplace_back("frame", std::to_string(f));
    m.emplace_back("time", std::to_string(t));
    m.emplace_back("camera", scenes::camera_text(sc, t));
}

/// How each layer is evaluated (docs/multirate.md §5), for the frames' metadata:
/// "tolerance 0.005; layer 0 h=16 error 0.00033 spectral 0.00056; layer 1 h=1 ..." ("direct" for layers the
/// camera's pyramid draws, "source" for source layers).
std::string lattice_text(scenes::Renderer& r) {
    const scenes::Scene& sc = r.scene();
    std::ostringstream s;
    s << "tolerance " << sc.render.tolerance;
    for (size_t i = 0; i < sc.layers.size(); ++i) {
        s << "; layer " << i << " ";
        if (const auto rule = r.lattice(i))
            s << "h=" << rule->spacing << " error " << rule->predicted_error << " spectral "
              << rule->spectral_error;
        else
            s << (sc.layers[i].source ? "source" : "direct");
    }
    return s.str();
}

void open_video(output::VideoWriter& writer, const std::string& path,
                const scenes::OutputConfig& out, const output::Metadata& meta) {
    output::quiet_video_logs();
    output::VideoOptions vo;
    vo.width = out.width, vo.height = out.height, vo.fps = out.fps;
    vo.codec = output::video_codec_from_string(out.codec);
    vo.crf = out.crf, vo.preset = out.preset;
    vo.metadata = meta;
    writer.open(path, vo);
}

void prepare_resume(const std::string& output) {
    remove_stale_temporaries(output);
    if (!output::keeps_metadata(output))
        std::cerr << output << ": --resume: this format keeps no metadata; a present frame is "
                     "kept if it decodes whole with the run's size, channels and sample type "
                     "(EXR and PNG also check seed, frame and scene hash)\n";
}

/// Writes frame f as one image: EXR keeps the raw field; display formats get the shading (grey
/// by default), with what `impulse encode` needs to make the video render would have made.
void write_frame_image(const scenes::Scene& sc, const render::Frame& frame, long long f,
                       const std::string& target, const output::ValueMapping& mapping,
                       output::Metadata m, std::vector<float>& rgb) {
    const auto& out = sc.output;
    const double t = sc.frame_time(f);
    const output::Shading shading = sc.shading_at(t);  // keyframed shading at the frame time
    add_frame_metadata(sc, f, m);
    m.emplace_back("display", output::format_display({mapping, shading}));
    m.emplace_back("encoder", "codec=" + out.codec + " crf=" + std::to_string(out.crf) +
                                  " preset=" + out.preset);
    const bool exr = fs::path(target).extension() == ".exr";
    if (!exr && colour_shading(sc)) {
        output::shade(frame, mapping, shading, rgb);
        output::write_rgb_image(target, out.width, out.height, rgb, m, out.bits == 16);
    } else {
        output::write_image(target, frame, mapping, m, out.bits == 16, out.compression);
    }
}

/// The run's last line: interrupted (exit status 128 + signal) or what was written.
int report_render(const std::string& output, long long written, long long skipped,
                  long long redone, int width, int height) {
    if (const int signo = g_signal) {
        std::cerr << "interrupted by " << StopSignals::name(signo) << ": " << written << " frame"
                  << (written == 1 ? "" : "s") << " written to " << output << " (exit status "
                  << 128 + signo << ")\n";
        return 128 + signo;
    }
    std::cout << "wrote " << output << " (" << written << " frame" << (written == 1 ? "" : "s");
    if (skipped) std::cout << ", " << skipped << " already present";
    if (redone) std::cout << ", " << redone << " replaced (present but did not check out)";
    std::cout << ", " << width << "x" << height << ")\n";
    return 0;
}

int run_render(const RenderOptions& opt) {
    scenes::Scene scene = load_render_scene(opt);
    long long first = 0, last = scene.output.frames - 1;
    if (!opt.frames.empty()) std::tie(first, last) = parse_frame_range(opt.frames, scene.output.frames);
    const std::string output = render_output(opt, scene.path, first == last);
    if (scene.volume) {  // impulses in 3-D: OpenVDB frames or a ray-marched preview
        std::unique_ptr<tbb::global_control> cap;  // --threads, as below
        if (opt.threads > 0)
            cap = std::make_unique<tbb::global_control>(
                tbb::global_control::max_allowed_parallelism, opt.threads);
        return run_volume_render(scene, {output, first, last, opt.quiet, opt.resume});
    }
    const auto [video, sequence] = output_kind(output, first, last, opt.resume);
    ensure_directory(sequence ? expand_pattern(output, first) : output);
    // Every path below writes images or a video: their module loads while the renderer is
    // made and the first frame renders (on an error below, this waits for the load: ~0.3 s).
    const output::IoPreload io_preload;
    const ChannelPlan plan =
        plan_channels(scene, opt.channels, sequence ? expand_pattern(output, first) : output, video);

    // Held by pointer so it can be freed before the encoder's flush (below).
    auto renderer = std::make_unique<scenes::Renderer>(std::move(scene));
    const scenes::Scene& sc = renderer->scene();
    const scenes::OutputConfig& out = sc.output;
    const int width = out.width, height = out.height;
    const output::ValueMapping mapping = renderer->mapping();
    render::EvalOptions eo;
    eo.tile_size = opt.tile;

    const output::Metadata meta = run_metadata(sc, mapping, opt);
    // Images also say how their layers were evaluated (a video's metadata stays what `impulse
    // encode` rebuilds from the frames).
    output::Metadata image_meta = meta;
    image_meta.push_back({"lattice", lattice_text(*renderer)});

    StopSignals stop_signals;  // from here a stop signal keeps what was written
    output::VideoWriter writer;
    if (video) open_video(writer, output, out, meta);
    if (sequence && opt.resume) prepare_resume(output);
    Progress progress(last - first + 1, opt.quiet);
    // Frame f + 1 renders (simulation, then evaluation) while frame f is written on another
    // thread: on two cores the output and the renderer overlap instead of taking turns. Two
    // float frames. Images: f is shaded and saved. Video: f is shaded band by band straight
    // into the encoder's YUV 4:2:0 planes (no float RGB frame, no swscale: output::Shader::
    // rows_yuv420) and encoded; frames reach the encoder in order, one at a time, so the file
    // does not depend on the overlap or on --threads (x264's own threads: output::
    // kEncoderThreads, fixed).
    render::Frame frames[2];
    scenes::FrameChannels channels[2];
    std::vector<float> rgb;
    long long written = 0, skipped = 0, redone = 0;
    // --threads caps TBB's workers process-wide (a task arena would serialise the two threads
    // of the pipeline: an arena admits one outside thread at a time by default).
    std::unique_ptr<tbb::global_control> cap;
    if (opt.threads > 0)
        cap = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    opt.threads);
    std::future<void> pending;  // the previous frame's output
    auto finish_pending = [&] {
        if (!pending.valid()) return;
        pending.get();  // rethrows an output error
        ++written;
        progress.update(written + skipped);
    };
    int slot = 0;
    for (long long f = first; f <= last; ++f) {
        if (g_signal) break;
        const std::string target = sequence ? expand_pattern(output, f) : output;
        if (sequence && opt.resume && fs::exists(target)) {
            const std::string why = present_frame_mismatch(target, sc, f, plan);
            if (why.empty()) {
                ++skipped;
                continue;
            }
            std::cerr << target << ": rendering again: " << why << "\n";
            ++redone;
        }
        if (plan.active) {  // channels beside the field (docs/channels.md)
            renderer->render_channels(f, plan.set, channels[slot], eo, plan.what);
            finish_pending();
            pending = std::async(std::launch::async, [&, s = slot, f, target] {
                output::Metadata m = meta;
                add_frame_metadata(sc, f, m);
                std::string names;
                for (const auto& n : plan.names) names += (names.empty() ? "" : " ") + n;
                m.emplace_back("channels", names);
                write_channel_frame(sc, plan, channels[s], f, target, mapping, m);
            });
            slot ^= 1;
            continue;
        }
        renderer->render(f, frames[slot], eo);
        finish_pending();
        if (video) {
            pending = std::async(std::launch::async, [&, s = slot, f] {
                const output::Shader shader(mapping, sc.shading_at(sc.frame_time(f)));
                writer.stage_shaded(frames[s], shader);
                writer.encode_staged();
            });
        } else {
            pending = std::async(std::launch::async, [&, s = slot, f, target] {
                write_frame_image(sc, frames[s], f, target, mapping, image_meta, rgb);
            });
        }
        slot ^= 1;
    }
    finish_pending();
    progress.done();
    if (video) {
        // Closing flushes the encoder, which then encodes every frame it still holds (x264's
        // lookahead): the peak of a short render. The renderer and the float frames are no
        // longer needed (sc and out refer into the renderer: not used below).
        frames[0] = {}, frames[1] = {};
        renderer.reset();
        writer.close();  // on interruption too: what was encoded stays playable
    }
    return report_render(output, written, skipped, redone, width, height);
}

}  // namespace impulse::app
