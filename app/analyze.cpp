// SPDX-License-Identifier: Apache-2.0
// `impulse analyze` on the command line: read the input (an image, a sequence pattern or a
// video), hand the frames to analysis::analyze_frames, print text or JSON and write the report
// and the variance map. The measurements, the theory and the report are in analysis/.

#include "app/analyze.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "app/commands.h"
#include "numeric/errors.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/closed_form.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;
using analysis::Image;

std::string one_line(std::string s) {
    for (char& c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
}

// ---------------------------------------------------------------------------------------------
// Reading the input

struct Loaded {
    std::vector<Image> frames;
    std::string kind;
    bool raw = true;
    int bits = 32;
    long long first = 0;
};

Image to_image(render::Frame&& f) {
    Image im;
    im.width = f.width;
    im.height = f.height;
    im.data = std::move(f.data);
    return im;
}

std::string unknown_type_message(const std::string& path) {
    const std::string ext = fs::path(path).extension().string();
    return path + ": unknown input type" + (ext.empty() ? std::string() : " \"" + ext + "\"") +
           ": expected an image in a format OpenImageIO reads (.exr .hdr .png .tif .jpg ...), a "
           "sequence pattern (frame_####.exr, frame_%04d.png) or a video (.mp4 .mov .mkv .webm)";
}

/// The field of an image: `channel` when given; a multi-channel EXR's `value` (render
/// --channels, docs/channels.md); else the luminance (output::read_image).
Image read_frame(const std::string& path, const std::string& channel) {
    try {
        if (!channel.empty()) return to_image(output::read_channel(path, channel));
        if (output::lower_extension(path) == ".exr") {
            const auto names = output::channel_names(path);
            if (std::find(names.begin(), names.end(), "value") != names.end())
                return to_image(output::read_channel(path, "value"));
        }
        return to_image(output::read_image(path));
    } catch (const IoError& e) {
        throw IoError(one_line(e.what()));
    }
}

output::ImageInfo probe(const std::string& path) {
    try {
        return output::probe_image(path);
    } catch (const IoError& e) {
        throw IoError(one_line(e.what()));
    }
}

Loaded load_input(const AnalyzeOptions& opt) {
    const std::string& in = opt.input;
    if (in.empty()) throw ValueError("analyze: no input given");
    const long long cap = opt.max_frames > 0 ? opt.max_frames : LLONG_MAX;
    if (opt.max_frames < 0)
        throw ValueError("--max-frames " + std::to_string(opt.max_frames) + ": must be >= 1");
    long long a = 0, b = LLONG_MAX;
    const bool ranged = !opt.frames.empty();
    if (ranged) std::tie(a, b) = parse_frame_range(opt.frames, LLONG_MAX);
    Loaded L;
    L.first = a;
    std::error_code ec;

    if (output::is_video_path(in)) {
        if (!opt.channel.empty())
            throw ValueError("--channel " + opt.channel + ": " + in + " is a video (one picture a "
                             "frame): channels are read from multi-channel images (EXR)");
        if (!fs::exists(in, ec)) throw IoError(in + ": no such file");
        output::quiet_video_logs();
        int w = 0, h = 0;
        std::vector<std::vector<float>> luma;
        try {
            luma = output::decode_video_luma(in, w, h);
        } catch (const IoError& e) {
            throw IoError(one_line(e.what()));
        }
        const long long n = static_cast<long long>(luma.size());
        if (n == 0) throw IoError(in + ": no frames could be decoded");
        if (ranged && b >= n)
            throw ValueError("--frames " + opt.frames + ": outside [0, " + std::to_string(n) +
                             ") (" + in + " has " + std::to_string(n) + " frames)");
        const long long last = std::min(b, n - 1);
        for (long long f = a; f <= last && static_cast<long long>(L.frames.size()) < cap; ++f) {
            Image im;
            im.width = w;
            im.height = h;
            im.data = std::move(luma[static_cast<size_t>(f)]);
            L.frames.push_back(std::move(im));
        }
        L.kind = "video";
        L.raw = false;
        L.bits = 8;
        return L;
    }

    // A sequence rendered with --frames 100-199 starts at 100: without --frames, analyse from
    // the first frame present.
    if (!ranged && !expand_pattern(in, 0).empty() && !fs::exists(expand_pattern(in, 0), ec))
        if (const long long first = first_frame_present(in); first > 0) a = L.first = first;
    const std::string first_name = expand_pattern(in, a);
    if (!first_name.empty()) {
        if (!fs::exists(first_name, ec))
            throw IoError(first_name + ": no such file (frame " + std::to_string(a) + " of " + in +
                          ")");
        if (!output::is_readable_image_path(first_name)) throw ValueError(unknown_type_message(in));
        const output::ImageInfo info = probe(first_name);
        for (long long f = a; f <= b && static_cast<long long>(L.frames.size()) < cap; ++f) {
            const std::string name = expand_pattern(in, f);
            if (!fs::exists(name, ec)) break;  // the sequence ends at the first missing frame
            L.frames.push_back(read_frame(name, opt.channel));
            const Image& im = L.frames.back();
            if (im.width != L.frames.front().width || im.height != L.frames.front().height)
                throw ValueError(name + ": frame is " + std::to_string(im.width) + "x" +
                                 std::to_string(im.height) + ", " + first_name + " is " +
                                 std::to_string(L.frames.front().width) + "x" +
                                 std::to_string(L.frames.front().height));
        }
        L.kind = "sequence";
        L.raw = info.is_float;
        L.bits = info.bits;
        return L;
    }

    if (!fs::exists(in, ec)) throw IoError(in + ": no such file");
    if (!output::is_readable_image_path(in)) throw ValueError(unknown_type_message(in));
    if (ranged && (a != 0 || b != 0))
        throw ValueError("--frames " + opt.frames + ": " + in + " is one image (frame 0)");
    const output::ImageInfo info = probe(in);
    L.frames.push_back(read_frame(in, opt.channel));
    L.kind = "image";
    L.raw = info.is_float;
    L.bits = info.bits;
    return L;
}


void write_atomically(const std::string& path, const std::string& text) {
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw IoError(path + ": cannot write: directory " + dir.string() + " does not exist");
    output::write_file_atomic(path, text.data(), text.size());
}

/// The first file of the input (an image or a sequence's first frame present; "" for a video).
std::string first_file(const AnalyzeOptions& opt, long long first) {
    if (output::is_video_path(opt.input)) return "";
    const std::string name = expand_pattern(opt.input, first);
    return name.empty() ? opt.input : name;
}

/// The framing the theory is taken at: --size, else what the frames' metadata records
/// (impulse:size, impulse:crop: render's --size and --crop); `sets` gains the crop.
scenes::OutputSize framing(const AnalyzeOptions& opt, const std::string& file,
                           std::vector<std::string>& sets, std::vector<std::string>& notes) {
    if (!opt.size.empty()) return parse_size("--size", opt.size);
    if (file.empty() || !output::keeps_metadata(file)) return {};
    std::string size, crop;
    for (const auto& [k, v] : output::read_metadata(file)) {
        if (k == "size") size = v;
        if (k == "crop") crop = v;
    }
    if (!crop.empty()) {
        const scenes::OutputSize c = parse_size(file + ": impulse:crop", crop);
        sets.push_back("output.size=[" + std::to_string(c.width) + "," + std::to_string(c.height) + "]");
        notes.push_back("theory at the frames' --crop " + crop + " (their impulse:crop)");
    }
    if (size.empty()) return {};
    notes.push_back("theory at the frames' --size " + size + " (their impulse:size)");
    return parse_size(file + ": impulse:size", size);
}

}  // namespace

AnalysisResult analyze_input(const AnalyzeOptions& options) {
    Loaded L = load_input(options);
    std::vector<std::string> sets = options.sets, notes;
    std::unique_ptr<analysis::ClosedForm> theory;
    if (!options.scene.empty()) {
        const scenes::OutputSize size = framing(options, first_file(options, L.first), sets, notes);
        theory = scenes::closed_form(options.scene, sets, size);
    }
    AnalysisResult r = analyze_frames(std::move(L.frames), options, L.kind, L.raw, L.bits, L.first,
                                      theory.get());
    r.notes.insert(r.notes.begin(), notes.begin(), notes.end());
    return r;
}

int run_analyze(const AnalyzeOptions& options) {
    if (!options.variance_map.empty() && !output::is_image_path(options.variance_map))
        throw ValueError("--variance-map " + options.variance_map + ": expected an image path "
                         "(.exr for the raw variances)");
    // The chart library first: without it, fail before the analysis and write nothing.
    const std::string charts = options.report.empty() ? "" : load_chart_library();
    const AnalysisResult r = analyze_input(options);
    if (!options.report.empty()) write_atomically(options.report, to_html(r, charts));
    if (r.variance_map) {
        const auto& v = *r.variance_map;
        const auto [lo, hi] = std::minmax_element(v.data.begin(), v.data.end());
        output::write_image(options.variance_map, numeric::Frame{v.width, v.height, v.data},
                            {*lo, *hi > *lo ? *hi : *lo + 1.0}, {{"analysis", "pixel variance"}},
                            true);
    }
    if (!options.json_file.empty()) write_atomically(options.json_file, to_json(r));
    std::cout << (options.json && options.json_file.empty() ? to_json(r) : to_text(r));
    if (!options.report.empty() && !options.json) std::cout << "wrote " << options.report << "\n";
    if (!options.json_file.empty()) std::cout << "wrote " << options.json_file << "\n";
    return 0;
}

}  // namespace impulse::app
