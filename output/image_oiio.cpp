// SPDX-License-Identifier: Apache-2.0
// Image output and input through OpenImageIO (part of libimpulse_io.so, output/io_module.h):
// every write goes to a temporary file that is
// renamed into place (design.md §4: no half-written frames).

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <system_error>

#include "output/detail/image_input.h"
#include "output/files.h"
#include "output/detail/io_impl.h"
#include "output/output.h"
#include "numeric/errors.h"

namespace impulse::output {
namespace {

namespace fs = std::filesystem;

/// A library message on one line (libjpeg's and libpng's can span several).
std::string one_line(std::string text) {
    std::replace(text.begin(), text.end(), '\n', ' ');
    while (!text.empty() && text.back() == ' ') text.pop_back();
    return text.empty() ? "unknown error" : text;
}

/// Sends stderr to /dev/null while alive (a library that prints on its own).
class QuietStderr {
public:
    QuietStderr() : m_saved(::dup(2)) {
        const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
        if (null >= 0) ::dup2(null, 2), ::close(null);
    }
    ~QuietStderr() {
        if (m_saved >= 0) ::dup2(m_saved, 2), ::close(m_saved);
    }
    QuietStderr(const QuietStderr&) = delete;
    QuietStderr& operator=(const QuietStderr&) = delete;

private:
    int m_saved;
};

void check_directory(const std::string& path) {
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw IoError(path + ": cannot write: directory " + dir.string() + " does not exist");
}

/// The sample type asked of OIIO for an extension: float EXR, 16-bit TIFF (and others with
/// `bits16`), else 8-bit. JPEG stores 8 bits whatever it is given.
OIIO::TypeDesc sample_type(const std::string& ext, bool bits16) {
    if (ext == ".exr") return OIIO::TypeDesc::FLOAT;
    if (ext == ".tif" || ext == ".tiff" || bits16) return OIIO::TypeDesc::UINT16;
    return OIIO::TypeDesc::UINT8;
}

OIIO::TypeDesc stored_type(const std::string& ext, bool bits16) {
    return ext == ".jpg" || ext == ".jpeg" ? OIIO::TypeDesc::UINT8 : sample_type(ext, bits16);
}

/// Encodes `spec` and `pixels` (floats) with OIIO into memory, as the extension of `path` says.
/// The file is encoded in memory and written by save_atomically: OIIO's PNG, TIFF and JPEG
/// writers do not all report a failed write (a full disk gave a truncated PNG and exit 0), and a
/// library's own message on stderr names no file.
std::vector<unsigned char> encode(const std::string& path, const OIIO::ImageSpec& spec,
                                  const float* pixels) {
    OIIO::Filesystem::IOVecOutput memory;
    auto out = OIIO::ImageOutput::create(path, &memory);
    if (!out) throw IoError(path + ": cannot write: " + one_line(OIIO::geterror()));
    const bool ok = out->open(path, spec) && out->write_image(OIIO::TypeDesc::FLOAT, pixels);
    std::string err = ok ? std::string() : out->geterror();
    if (!out->close() && err.empty()) err = out->geterror();
    if (!ok || !err.empty() || memory.buffer().empty())
        throw IoError(path + ": cannot encode: " + one_line(err.empty() ? OIIO::geterror() : err));
    return std::move(memory.buffer());
}

/// A temporary beside the target, renamed into place: never a half-written file.
void save_atomically(const std::string& path, const std::vector<unsigned char>& bytes) {
    write_file_atomic(path, bytes.data(), bytes.size());
}

}  // namespace

namespace io {

/// The spec write_pixels and write_named_pixels encode with: the sample type of the
/// extension, the metadata, and each format's settings.
OIIO::ImageSpec output_spec(const std::string& path, int width, int height, int channels,
                            const Metadata& metadata, bool bits16, const std::string& compression) {
    check_directory(path);
    const std::string ext = lower_extension(path);
    OIIO::ImageSpec spec(width, height, channels, sample_type(ext, bits16));
    for (const auto& [k, v] : metadata) spec.attribute("impulse:" + k, v);
    spec.attribute("Software", "impulse");
    if (ext == ".exr")
        spec.attribute("compression", compression.empty() ? kDefaultExrCompression : compression);
    // zlib level 1 (OIIO's default is 6): a 1080p still of noise is 3 % larger and its deflate
    // takes ~40 ms instead of ~215 ms, most of a whole still render to PNG (measured,
    // bench/startup.sh).
    if (ext == ".png") spec.attribute("png:compressionLevel", 1);
    // libpng's default tries every row filter and keeps the best guess; on noise the "up" filter
    // alone gives the smallest file and the fastest write (1080p still: 1.32 MB in 359 CPU-ms
    // against 1.43 MB in 390 with every filter, none 2.63 MB; whole oiiotool runs, 5 each).
    constexpr int kPngFilterUp = 0x20;  // PNG_FILTER_UP
    if (ext == ".png") spec.attribute("png:filter", kPngFilterUp);
    // OIIO stamps files with the wall-clock time unless told otherwise; a frame must be a pure
    // function of the scene (design.md §4), so the stamp is a fixed value.
    spec.attribute("DateTime", "1970:01:01 00:00:00");
    return spec;
}

void write_pixels(const std::string& path, int width, int height, int channels,
                  const float* pixels, const Metadata& metadata, bool bits16,
                  const std::string& compression) {
    OIIO::ImageSpec spec = output_spec(path, width, height, channels, metadata, bits16, compression);
    if (channels == 1) spec.channelnames = {"Y"};
    // Quantisation to integer formats is OIIO's: clamp to [0, 1], scale, round to nearest.
    save_atomically(path, encode(path, spec, pixels));
}

void write_named_pixels(const std::string& path, int width, int height,
                        const std::vector<std::string>& names, const float* pixels,
                        const Metadata& metadata, bool bits16, const std::string& compression) {
    OIIO::ImageSpec spec =
        output_spec(path, width, height, int(names.size()), metadata, bits16, compression);
    spec.channelnames = names;
    const auto a = std::find(names.begin(), names.end(), "A");
    spec.alpha_channel = a == names.end() ? -1 : int(a - names.begin());
    save_atomically(path, encode(path, spec, pixels));
}

Frame read_channel(const std::string& path, const std::string& name) {
    std::string error;
    auto in = open_image_input(path, error);
    if (!in) throw IoError(path + ": " + error);
    const OIIO::ImageSpec& spec = in->spec();
    if (const std::string bad = image_size_problem(spec.width, spec.height, spec.depth, 1);
        !bad.empty())
        throw IoError(path + ": " + bad);
    const auto& names = spec.channelnames;
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : " ") + n;
        throw IoError(path + ": no channel \"" + name + "\": the file has " + list);
    }
    const int c = int(it - names.begin());
    Frame f;
    f.resize(spec.width, spec.height);
    if (!in->read_image(0, 0, c, c + 1, OIIO::TypeDesc::FLOAT, f.data.data()))
        throw IoError(path + ": cannot read: " + one_line(in->geterror()));
    if (const std::string bad = nonfinite_pixel(f.data.data(), f.data.size(), f.width, 1);
        !bad.empty())
        throw IoError(path + ": channel " + name + ": " + bad);
    return f;
}

std::vector<std::string> channel_names(const std::string& path) {
    std::string error;
    auto in = open_image_input(path, error);
    if (!in) throw IoError(path + ": " + error);
    return in->spec().channelnames;
}

std::string encode_png(int width, int height, const std::vector<float>& rgb) {
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("png:compressionLevel", 3);  // fast: a preview, not a master
    const std::vector<unsigned char> png = encode("preview.png", spec, rgb.data());
    return std::string(png.begin(), png.end());
}

bool read_pixels(const std::string& path, Pixels& px, std::string& error,
                 const std::function<std::string(int)>& check_channels) {
    auto in = open_image_input(path, error);
    if (!in) return false;
    const OIIO::ImageSpec& spec = in->spec();
    error = image_size_problem(spec.width, spec.height, spec.depth, spec.nchannels);
    if (error.empty() && check_channels) error = check_channels(spec.nchannels);
    if (!error.empty()) return false;
    px.width = spec.width, px.height = spec.height, px.channels = spec.nchannels;
    px.is_float = spec.format == OIIO::TypeDesc::FLOAT || spec.format == OIIO::TypeDesc::HALF;
    px.channel_names = spec.channelnames;
    px.values.resize(size_t(px.width) * px.height * px.channels);
    if (!in->read_image(0, 0, 0, px.channels, OIIO::TypeDesc::FLOAT, px.values.data())) {
        error = "cannot read: " + one_line(in->geterror());
        return false;
    }
    return true;
}

std::string image_size_problem(int width, int height, int depth, int channels) {
    std::ostringstream s;
    s << "the header claims " << width << "x" << height;
    if (depth != 1) s << "x" << depth;
    s << " pixels of " << channels << " channels";
    if (width <= 0 || height <= 0 || channels <= 0 || depth != 1) {
        s << ": expected a 2-D image with pixels and channels";
        return s.str();
    }
    const double mib = double(width) * height * channels * sizeof(float) / (1024.0 * 1024.0);
    const int limit = OIIO::get_int_attribute("limits:imagesize_MB", 32768);
    if (limit <= 0 || mib <= limit) return "";
    s << ", " << mib << " MiB as floats: over OpenImageIO's limits:imagesize_MB = " << limit;
    return s.str();
}

Metadata read_metadata(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw IoError(path + ": cannot read: " + one_line(OIIO::geterror()));
    Metadata m;
    for (const OIIO::ParamValue& p : in->spec().extra_attribs)
        if (p.name().string().rfind("impulse:", 0) == 0 && p.type() == OIIO::TypeDesc::STRING)
            m.emplace_back(p.name().string().substr(8), p.get_string());
    return m;
}

std::string image_mismatch(const std::string& path, int width, int height, int channels,
                           bool bits16, const Metadata& metadata) {
    std::string error;
    auto in = open_image_input(path, error);
    if (!in) return "unreadable: " + error;
    const OIIO::ImageSpec& spec = in->spec();
    std::ostringstream why;
    if (spec.width != width || spec.height != height)
        why << spec.width << "x" << spec.height << " pixels, expected " << width << "x" << height;
    else if (spec.nchannels != channels)
        why << spec.nchannels << " channels, expected " << channels;
    else if (const OIIO::TypeDesc t = stored_type(lower_extension(path), bits16); spec.format != t)
        why << spec.format << " samples, expected " << t;
    if (!why.str().empty()) return why.str();
    if (keeps_metadata(path))
        for (const auto& [k, v] : metadata) {
            const std::string have = spec.get_string_attribute("impulse:" + k, "(none)");
            if (have != v) return "impulse:" + k + " is " + have + ", expected " + v;
        }
    // Every pixel decoded: a file cut short by a full disk or a killed copy fails here. libpng
    // prints its own line on stderr before OIIO reports the error: silenced, the reason is
    // returned.
    std::vector<float> px(size_t(width) * height * channels);
    bool ok = false;
    {
        const QuietStderr quiet;
        ok = in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, px.data());
    }
    if (!ok) {
        const std::string err = in->geterror();
        return "truncated or unreadable: " + one_line(err.substr(0, err.find('\n')));
    }
    return "";
}

Frame read_image(const std::string& path) {
    std::string error;
    auto in = open_image_input(path, error);
    if (!in) throw IoError(path + ": " + error);
    const OIIO::ImageSpec& spec = in->spec();
    const int w = spec.width, h = spec.height, nc = spec.nchannels;
    if (const std::string bad = image_size_problem(w, h, spec.depth, nc); !bad.empty())
        throw IoError(path + ": " + bad);
    std::vector<float> px(size_t(w) * h * nc);
    if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, px.data()))
        throw IoError(path + ": cannot read: " + in->geterror());
    in->close();
    if (const std::string bad = nonfinite_pixel(px.data(), px.size(), w, nc); !bad.empty())
        throw IoError(path + ": " + bad);
    Frame f;
    f.resize(w, h);
    for (size_t i = 0; i < size_t(w) * h; ++i) {
        if (nc >= 3)  // Rec. 709 luma
            f.data[i] = 0.2126f * px[i * nc] + 0.7152f * px[i * nc + 1] + 0.0722f * px[i * nc + 2];
        else
            f.data[i] = px[i * nc];
    }
    return f;
}

ImageInfo probe_image(const std::string& path) {
    std::string error;
    auto in = open_image_input(path, error);
    if (!in) throw IoError(path + ": " + error);
    const OIIO::ImageSpec& spec = in->spec();
    ImageInfo info;
    info.width = spec.width;
    info.height = spec.height;
    info.channels = spec.nchannels;
    info.is_float = spec.format.is_floating_point();
    info.bits = spec.get_int_attribute("oiio:BitsPerSample", static_cast<int>(spec.format.size()) * 8);
    in->close();
    return info;
}

bool is_readable_image_path(const std::string& path) {
    std::string e = lower_extension(path);
    if (e.size() < 2) return false;
    e = e.substr(1);
    // "format:ext,ext;format:ext..." as OIIO reports it for the plugins it was built with.
    const std::string list = OIIO::get_string_attribute("extension_list");
    size_t pos = 0;
    while (pos < list.size()) {
        size_t end = list.find(';', pos);
        if (end == std::string::npos) end = list.size();
        const std::string entry = list.substr(pos, end - pos);
        const size_t colon = entry.find(':');
        std::string exts = colon == std::string::npos ? entry : entry.substr(colon + 1);
        size_t p = 0;
        while (p <= exts.size()) {
            size_t comma = exts.find(',', p);
            if (comma == std::string::npos) comma = exts.size();
            if (exts.compare(p, comma - p, e) == 0 && comma - p == e.size()) return true;
            p = comma + 1;
        }
        pos = end + 1;
    }
    return false;
}

}  // namespace io
}  // namespace impulse::output
