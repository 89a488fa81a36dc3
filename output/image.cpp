// SPDX-License-Identifier: Apache-2.0
// Image output and input through OpenImageIO; every write goes to a temporary file that is
// renamed into place (design.md §4: no half-written frames).

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <system_error>

#include "output/output.h"
#include "numeric/errors.h"

namespace impulse::output {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
    return e;
}

/// Temporary name beside the target that keeps the extension (OIIO picks the format from it).
std::string temp_name(const std::string& path) {
    const fs::path p(path);
    return (p.parent_path() / ("." + p.stem().string() + ".partial-" + std::to_string(::getpid()) +
                               p.extension().string()))
        .string();
}

void check_directory(const std::string& path) {
    const fs::path dir = fs::path(path).parent_path();
    std::error_code ec;
    if (!dir.empty() && !fs::is_directory(dir, ec))
        throw IoError(path + ": cannot write: directory " + dir.string() + " does not exist");
}

void write_pixels(const std::string& path, int width, int height, int channels,
                  const float* pixels, const Metadata& metadata, bool bits16) {
    check_directory(path);
    const std::string ext = lower_extension(path);
    OIIO::TypeDesc type = OIIO::TypeDesc::UINT8;
    if (ext == ".exr")
        type = OIIO::TypeDesc::FLOAT;
    else if (ext == ".tif" || ext == ".tiff" || bits16)
        type = OIIO::TypeDesc::UINT16;
    const std::string tmp = temp_name(path);
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) throw IoError(path + ": cannot write: " + OIIO::geterror());
    OIIO::ImageSpec spec(width, height, channels, type);
    if (channels == 1) spec.channelnames = {"Y"};
    for (const auto& [k, v] : metadata) spec.attribute("impulse:" + k, v);
    spec.attribute("Software", "impulse");
    if (ext == ".exr") spec.attribute("compression", "zip");
    // OIIO stamps files with the wall-clock time unless told otherwise; a frame must be a pure
    // function of the scene (design.md §4), so the stamp is a fixed value.
    spec.attribute("DateTime", "1970:01:01 00:00:00");
    if (!out->open(tmp, spec)) {
        std::string err = out->geterror();
        throw IoError(path + ": cannot write: " + (err.empty() ? OIIO::geterror() : err));
    }
    // Quantisation to integer formats is OIIO's: clamp to [0, 1], scale, round to nearest.
    const bool ok = out->write_image(OIIO::TypeDesc::FLOAT, pixels);
    std::string err = ok ? std::string() : out->geterror();
    if (!out->close() && ok) err = out->geterror();
    if (!ok || !err.empty()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(path + ": write failed: " + err);
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot rename temporary file into place: " + ec.message());
    }
}

}  // namespace

bool is_image_path(const std::string& path) {
    const std::string e = lower_extension(path);
    return e == ".exr" || e == ".png" || e == ".tif" || e == ".tiff" || e == ".jpg" || e == ".jpeg";
}

void write_image(const std::string& path, const Frame& frame, const ValueMapping& mapping,
                 const Metadata& metadata, bool bits16) {
    if (lower_extension(path) == ".exr") {
        write_pixels(path, frame.width, frame.height, 1, frame.data.data(), metadata, bits16);
        return;
    }
    std::vector<float> mapped(frame.data.size());
    const double scale = 1.0 / (mapping.hi - mapping.lo);
    for (size_t i = 0; i < mapped.size(); ++i)
        mapped[i] = static_cast<float>(
            std::clamp((static_cast<double>(frame.data[i]) - mapping.lo) * scale, 0.0, 1.0));
    write_pixels(path, frame.width, frame.height, 1, mapped.data(), metadata, bits16);
}

void write_rgb_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                     const Metadata& metadata, bool bits16) {
    write_pixels(path, width, height, 3, rgb.data(), metadata, bits16);
}

std::string nonfinite_pixel(const float* px, size_t count, int width, int channels) {
    for (size_t i = 0; i < count; ++i)
        if (!std::isfinite(px[i])) {
            const size_t p = i / size_t(channels);
            std::ostringstream s;
            s << "expected finite pixel values, found " << px[i] << " at pixel ("
              << p % size_t(width) << ", " << p / size_t(width) << ") channel "
              << i % size_t(channels);
            return s.str();
        }
    return "";
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

Frame read_image(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw IoError(path + ": cannot read: " + OIIO::geterror());
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
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw IoError(path + ": cannot read: " + OIIO::geterror());
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

}  // namespace impulse::output
