// SPDX-License-Identifier: Apache-2.0
#pragma once
// Inside libimpulse_io.so (output/io_module.h): the implementations the table points to, in
// namespace io so that a program linking both them and impulse::output's forwarders (image.h,
// video.h) has one definition of each name. Documented where they are declared in image.h,
// video.h and io_module.h.

#include "output/io_module.h"

namespace impulse::output::io {

void write_pixels(const std::string& path, int width, int height, int channels,
                  const float* pixels, const Metadata& metadata, bool bits16,
                  const std::string& compression);
Frame read_image(const std::string& path);
void write_named_pixels(const std::string& path, int width, int height,
                        const std::vector<std::string>& names, const float* pixels,
                        const Metadata& metadata, bool bits16, const std::string& compression);
Frame read_channel(const std::string& path, const std::string& name);
std::vector<std::string> channel_names(const std::string& path);
std::string image_size_problem(int width, int height, int depth, int channels);
std::string image_mismatch(const std::string& path, int width, int height, int channels,
                           bool bits16, const Metadata& metadata);
Metadata read_metadata(const std::string& path);
ImageInfo probe_image(const std::string& path);
bool is_readable_image_path(const std::string& path);
bool read_pixels(const std::string& path, Pixels& pixels, std::string& error,
                 const std::function<std::string(int)>& check_channels);
void write_exr_stack(const std::string& path, const VolumeGrid& grid,
                     const std::string& description);
void write_vdb(const std::string& path, const VolumeGrid& grid, const std::string& description,
               const VdbOptions& options);
VolumeGrid read_vdb(const std::string& path, const std::string& name);
std::vector<VdbGridHeader> list_vdb_grids(const std::string& path);
VdbVectorGrid read_vdb_vectors(const std::string& path, const std::string& name,
                               const VdbIndexBox* box);
VdbIndexBox read_vdb_active_box(const std::string& path, const std::string& name);
std::string encode_png(int width, int height, const std::vector<float>& rgb);
std::unique_ptr<VideoSink> make_video_sink();
void quiet_video_logs();
VideoInfo probe_video(const std::string& path);
std::vector<std::vector<float>> decode_video_luma(const std::string& path, int& width,
                                                  int& height);

}  // namespace impulse::output::io
