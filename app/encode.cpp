// SPDX-License-Identifier: Apache-2.0
// `impulse encode` (app/encode.h): a finished EXR sequence to a video.

#include "app/encode.h"

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "app/commands.h"
#include "numeric/errors.h"
#include "output/output.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

/// What one frame's header says (read before any pixel).
struct FrameHeader {
    std::string path, scene_hash, scene;
    int width = 0, height = 0, channels = 0;
    output::Display display;
};

std::string value_of(const output::Metadata& m, const std::string& key) {
    for (const auto& [k, v] : m)
        if (k == key) return v;
    return "";
}

/// The "range" metadata of frames written before impulse:display: grey over that range.
output::Display display_from_range(const std::string& path, const std::string& range) {
    output::Display d;
    std::istringstream in(range);
    if (!(in >> d.mapping.lo >> d.mapping.hi))
        throw ValueError(path +
                         ": no impulse:display or impulse:range metadata: expected a frame "
                         "written by `impulse render`");
    return d;
}

FrameHeader read_header(const std::string& path, long long f) {
    FrameHeader h;
    h.path = path;
    const output::ImageInfo info = output::probe_image(path);
    h.width = info.width, h.height = info.height, h.channels = info.channels;
    if (!info.is_float || info.channels != 1)
        throw ValueError(path + ": " + std::to_string(info.channels) + " channel" +
                         (info.channels == 1 ? "" : "s") +
                         (info.is_float ? " of floats" : " of integers") +
                         ": expected one channel of raw floats (an EXR from `impulse render`)");
    const output::Metadata m = output::read_metadata(path);
    h.scene_hash = value_of(m, "scene_hash");
    h.scene = value_of(m, "scene");
    if (h.scene_hash.empty())
        throw ValueError(path +
                         ": no impulse:scene_hash metadata: expected a frame written by "
                         "`impulse render`");
    if (const std::string frame = value_of(m, "frame"); frame != std::to_string(f))
        throw ValueError(path + ": impulse:frame is " + (frame.empty() ? "missing" : frame) +
                         ", expected " + std::to_string(f) + " (a renamed or copied frame?)");
    const std::string display = value_of(m, "display");
    h.display = display.empty() ? display_from_range(path, value_of(m, "range"))
                                : output::parse_display(display, path);
    return h;
}

/// Every frame of [first, last] must be present: else the missing ones, named.
void check_complete(const std::string& pattern, long long first, long long last,
                    const std::vector<long long>& present) {
    std::vector<long long> missing;
    auto it = present.begin();
    for (long long f = first; f <= last && missing.size() < 1000; ++f) {
        while (it != present.end() && *it < f) ++it;
        if (it == present.end() || *it != f) missing.push_back(f);
    }
    if (missing.empty()) return;
    throw ValueError(pattern + ": frame" + (missing.size() == 1 ? " " : "s ") +
                     frame_list(missing) + " missing from " + std::to_string(first) + "-" +
                     std::to_string(last) + " (e.g. " + expand_pattern(pattern, missing.front()) +
                     "): render them with `impulse render SCENE -o " + pattern +
                     " --frames A-B --resume`");
}

/// All frames of one scene and one size: else the scenes (hash, file, frames) or the frame
/// of another size, named.
void check_one_scene(const std::string& pattern, const std::vector<FrameHeader>& headers,
                     long long first) {
    std::map<std::string, std::vector<long long>> by_hash;
    for (size_t i = 0; i < headers.size(); ++i)
        by_hash[headers[i].scene_hash].push_back(first + (long long)i);
    if (by_hash.size() > 1) {
        std::string what;
        for (const auto& [hash, frames] : by_hash) {
            const FrameHeader& h = headers[size_t(frames.front() - first)];
            what += std::string(what.empty() ? "" : "; ") + hash + " (" +
                    (h.scene.empty() ? "?" : h.scene) + ") frames " + frame_list(frames, 4);
        }
        throw ValueError(pattern + ": frames of " + std::to_string(by_hash.size()) +
                         " scenes (impulse:scene_hash): " + what);
    }
    for (const FrameHeader& h : headers)
        if (h.width != headers[0].width || h.height != headers[0].height)
            throw ValueError(h.path + ": " + std::to_string(h.width) + "x" +
                             std::to_string(h.height) + " pixels, but " + headers[0].path +
                             " has " + std::to_string(headers[0].width) + "x" +
                             std::to_string(headers[0].height));
}

/// "codec=auto crf=18 preset=medium" (impulse:encoder) into the options not given.
void encoder_defaults(const std::string& encoder, std::string& codec, std::string& crf,
                      std::string& preset) {
    std::istringstream in(encoder);
    for (std::string field; in >> field;) {
        const size_t eq = field.find('=');
        if (eq == std::string::npos) continue;
        const std::string key = field.substr(0, eq), value = field.substr(eq + 1);
        std::string* slot = key == "codec"    ? &codec
                            : key == "crf"    ? &crf
                            : key == "preset" ? &preset
                                              : nullptr;
        if (slot && slot->empty()) *slot = value;
    }
}

double parse_fps(const std::string& text, const std::string& what) {
    char* end = nullptr;
    const double fps = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !(fps > 0) || fps > 1000)
        throw ValueError(what + " " + text + ": expected frames per second in (0, 1000]");
    return fps;
}

/// The video's options: the command line's, else the first frame's metadata, else defaults.
output::VideoOptions video_options(const EncodeOptions& opt, const FrameHeader& h0) {
    const output::Metadata m = output::read_metadata(h0.path);
    std::string codec = opt.codec, crf = opt.crf, preset = opt.preset;
    encoder_defaults(value_of(m, "encoder"), codec, crf, preset);
    output::VideoOptions vo;
    vo.width = h0.width, vo.height = h0.height;
    const std::string fps = opt.fps.empty() ? value_of(m, "fps") : opt.fps;
    vo.fps =
        fps.empty() ? 30.0 : parse_fps(fps, opt.fps.empty() ? h0.path + ": impulse:fps" : "--fps");
    vo.codec = output::video_codec_from_string(codec.empty() ? "auto" : codec);
    if (!crf.empty()) vo.crf = int(whole_number("--crf", crf, crf, "an integer in [0, 63]"));
    if (vo.crf > 63) throw ValueError("--crf " + crf + ": expected an integer in [0, 63]");
    if (!preset.empty()) vo.preset = preset;
    // The container carries what `impulse render -o X.mp4` writes into it.
    for (const char* key : {"seed", "layer_seeds", "scene", "scene_hash", "fps", "range"})
        if (const std::string v = value_of(m, key); !v.empty()) vo.metadata.emplace_back(key, v);
    return vo;
}

}  // namespace

std::string frame_list(const std::vector<long long>& frames, size_t limit) {
    std::string text;
    size_t items = 0;
    for (size_t i = 0; i < frames.size(); ++items) {
        size_t j = i;
        while (j + 1 < frames.size() && frames[j + 1] == frames[j] + 1) ++j;
        if (items == limit) return text + ", ...";
        text += std::string(text.empty() ? "" : ", ") + std::to_string(frames[i]) +
                (j > i ? "-" + std::to_string(frames[j]) : "");
        i = j + 1;
    }
    return text;
}

CLI::App* add_encode(CLI::App& app, EncodeOptions& o) {
    CLI::App* c = app.add_subcommand(
        "encode",
        "Assemble a finished EXR sequence into a video with the scene's display mapping "
        "(from the frames' metadata); refuses gaps and frames of mixed scenes");
    c->add_option("input", o.input, "The sequence pattern, e.g. frames/f_####.exr")->required();
    c->add_option("-o,--output", o.output, "The video (.mp4 .mov .mkv .webm)")->required();
    c->add_option("--frames", o.frames,
                  "Inclusive range A-B that must be complete (default: first to last present)");
    c->add_option("--codec", o.codec,
                  "auto, h264, prores, ffv1, vp9 (default: the scene's output.codec)");
    c->add_option("--fps", o.fps, "Frames per second (default: the scene's, from impulse:fps)");
    c->add_option("--crf", o.crf,
                  "Quality for h264 (0..51) and vp9 (0..63) (default: the scene's)");
    c->add_option("--preset", o.preset, "x264 preset (default: the scene's output.preset)");
    c->add_flag("-q,--quiet", o.quiet, "No summary line");
    return c;
}

int run_encode(const EncodeOptions& opt) {
    if (!output::is_video_path(opt.output))
        throw ValueError("-o " + opt.output + ": expected a video (.mp4 .mov .mkv .webm)");
    const PatternSpot spot = find_pattern(fs::path(opt.input).filename().string());
    if (!spot.found || fs::path(opt.input).extension() != ".exr")
        throw ValueError(opt.input +
                         ": expected an EXR sequence pattern in the file name, e.g. "
                         "frames/f_####.exr");
    const std::vector<long long> present = frames_present(opt.input);
    if (present.empty()) throw IoError(opt.input + ": no frames found");
    long long first = present.front(), last = present.back();
    if (!opt.frames.empty())
        std::tie(first, last) =
            parse_frame_range(opt.frames, std::numeric_limits<long long>::max());
    check_complete(opt.input, first, last, present);

    std::vector<FrameHeader> headers;
    for (long long f = first; f <= last; ++f)
        headers.push_back(read_header(expand_pattern(opt.input, f), f));
    check_one_scene(opt.input, headers, first);

    output::quiet_video_logs();
    output::VideoWriter writer;
    const output::VideoOptions vo = video_options(opt, headers[0]);
    writer.open(opt.output, vo);
    for (const FrameHeader& h : headers) {
        const output::Frame frame = output::read_image(h.path);
        if (frame.width != vo.width || frame.height != vo.height)
            throw IoError(h.path + ": changed while encoding");
        const output::Shader shader(h.display.mapping, h.display.shading);
        writer.stage_shaded(frame, shader);
        writer.encode_staged();
    }
    writer.close();
    if (!opt.quiet)
        std::cout << "wrote " << opt.output << " (" << headers.size() << " frames " << first << "-"
                  << last << ", " << vo.width << "x" << vo.height << ", " << vo.fps << " fps)\n";
    return 0;
}

}  // namespace impulse::app
