// SPDX-License-Identifier: Apache-2.0
// image.h: what needs no image library is here; the rest forwards to the image and video
// module (output/io_module.h), loaded the first time a file is read or written.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "output/files.h"
#include "output/io_module.h"
#include "output/output.h"

namespace impulse::output {

bool is_image_path(const std::string& path) {
    const std::string e = lower_extension(path);
    return e == ".exr" || e == ".png" || e == ".tif" || e == ".tiff" || e == ".jpg" || e == ".jpeg";
}

bool keeps_metadata(const std::string& path) {
    const std::string e = lower_extension(path);
    return e == ".exr" || e == ".png";
}

void write_image(const std::string& path, const Frame& frame, const ValueMapping& mapping,
                 const Metadata& metadata, bool bits16, const std::string& compression) {
    const IoModule& io = io_module();
    if (lower_extension(path) == ".exr") {
        io.write_pixels(path, frame.width, frame.height, 1, frame.data.data(), metadata, bits16,
                        compression);
        return;
    }
    std::vector<float> mapped(frame.data.size());
    const double scale = 1.0 / (mapping.hi - mapping.lo);
    for (size_t i = 0; i < mapped.size(); ++i)
        mapped[i] = static_cast<float>(
            std::clamp((static_cast<double>(frame.data[i]) - mapping.lo) * scale, 0.0, 1.0));
    io.write_pixels(path, frame.width, frame.height, 1, mapped.data(), metadata, bits16, "");
}

void write_rgb_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                     const Metadata& metadata, bool bits16) {
    io_module().write_pixels(path, width, height, 3, rgb.data(), metadata, bits16, "");
}

void write_named_channels(const std::string& path, int width, int height,
                          const std::vector<std::string>& names, const std::vector<float>& pixels,
                          const Metadata& metadata, bool bits16, const std::string& compression) {
    io_module().write_named_pixels(path, width, height, names, pixels.data(), metadata, bits16,
                                   compression);
}
Frame read_channel(const std::string& path, const std::string& name) {
    return io_module().read_channel(path, name);
}
std::vector<std::string> channel_names(const std::string& path) {
    return io_module().channel_names(path);
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
    return io_module().image_size_problem(width, height, depth, channels);
}
std::string image_mismatch(const std::string& path, int width, int height, int channels,
                           bool bits16, const Metadata& metadata) {
    return io_module().image_mismatch(path, width, height, channels, bits16, metadata);
}
Metadata read_metadata(const std::string& path) { return io_module().read_metadata(path); }
Frame read_image(const std::string& path) { return io_module().read_image(path); }
ImageInfo probe_image(const std::string& path) { return io_module().probe_image(path); }
bool is_readable_image_path(const std::string& path) {
    return io_module().is_readable_image_path(path);
}
bool read_pixels(const std::string& path, Pixels& pixels, std::string& error,
                 const std::function<std::string(int)>& check_channels) {
    return io_module().read_pixels(path, pixels, error, check_channels);
}
void write_exr_stack(const std::string& path, const VolumeGrid& grid,
                     const std::string& description) {
    io_module().write_exr_stack(path, grid, description);
}
void write_vdb(const std::string& path, const VolumeGrid& grid, const std::string& description,
               const VdbOptions& options) {
    io_module().write_vdb(path, grid, description, options);
}
VolumeGrid read_vdb(const std::string& path, const std::string& name) {
    return io_module().read_vdb(path, name);
}
std::vector<VdbGridHeader> list_vdb_grids(const std::string& path) {
    return io_module().list_vdb_grids(path);
}
VdbVectorGrid read_vdb_vectors(const std::string& path, const std::string& name,
                               const VdbIndexBox* box) {
    return io_module().read_vdb_vectors(path, name, box);
}
VdbIndexBox read_vdb_active_box(const std::string& path, const std::string& name) {
    return io_module().read_vdb_active_box(path, name);
}
std::string encode_png(int width, int height, const std::vector<float>& rgb) {
    return io_module().encode_png(width, height, rgb);
}

}  // namespace impulse::output
