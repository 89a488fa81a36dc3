// SPDX-License-Identifier: Apache-2.0
#pragma once
// The image and video module of impulse::output. OpenImageIO, FFmpeg's libav* and OpenVDB pull
// ~260 shared libraries into a process (0.2-0.35 s of dynamic loading and relocation on a
// 2-core machine), so the code that calls them is built into a separate shared module,
// libimpulse_io.so, loaded with dlopen the first time a command reads or writes an image, a
// video or a volume: `impulse --help`, `scenes` and `info` never load it. The functions of
// image.h, video.h and volume.h forward to the table below; a program that links the module's objects
// (impulse::output_io: the tests, the benchmarks, the Python module) uses them directly.

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "output/image.h"
#include "output/video.h"
#include "output/volume.h"

namespace impulse::output {

/// An image's pixels as floats, every channel interleaved (OIIO's conversion: [0, 1] for
/// integer formats, raw values for float and half).
struct Pixels {
    int width = 0, height = 0, channels = 0;
    bool is_float = false;  ///< the file stores float or half samples
    std::vector<float> values;
    std::vector<std::string> channel_names;  ///< as the file names them ("R", "vel.x", ...)
};

/// Reads an image given by a scene (orientation, velocity, colour ramp): refuses a hostile
/// header first (image_input.h). `check_channels(n)` (when given) judges the channel count from
/// the header before any pixel is read: "" accepts, else the reason. False with `error` set
/// (one line) when anything fails.
bool read_pixels(const std::string& path, Pixels& pixels, std::string& error,
                 const std::function<std::string(int)>& check_channels = {});

/// An 8-bit RGB PNG of `rgb` (3 floats a pixel in [0, 1]) in memory, zlib level 3. Throws
/// IoError.
std::string encode_png(int width, int height, const std::vector<float>& rgb);

/// The encoder behind a VideoWriter (video.h documents each call).
class VideoSink {
public:
    virtual ~VideoSink() = default;
    virtual void open(const std::string& path, const VideoOptions& options) = 0;
    virtual void write_frame(const float* rgb) = 0;
    virtual void stage_frame(const VideoWriter::RowSource& rows) = 0;
    virtual void encode_staged() = 0;
    virtual bool takes_yuv420() const = 0;
    virtual void stage_yuv420(const VideoWriter::Yuv420Source& rows) = 0;
    virtual void close() = 0;
    virtual void abort() = 0;
    virtual int frames_written() const = 0;
    virtual bool is_open() const = 0;
};

/// What libimpulse_io.so exports: one function per call that needs OIIO, libav or OpenVDB.
/// Built with the same compiler and headers as the program in the same build, so C++ types
/// cross the boundary; `abi` guards against a module left over from another build.
struct IoModule {
    int abi;
    void (*write_pixels)(const std::string& path, int width, int height, int channels,
                         const float* pixels, const Metadata& metadata, bool bits16,
                         const std::string& compression);
    Frame (*read_image)(const std::string& path);
    std::string (*image_size_problem)(int width, int height, int depth, int channels);
    std::string (*image_mismatch)(const std::string& path, int width, int height, int channels,
                                  bool bits16, const Metadata& metadata);
    Metadata (*read_metadata)(const std::string& path);
    ImageInfo (*probe_image)(const std::string& path);
    bool (*is_readable_image_path)(const std::string& path);
    bool (*read_pixels)(const std::string& path, Pixels& pixels, std::string& error,
                        const std::function<std::string(int)>& check_channels);
    void (*write_exr_stack)(const std::string& path, const VolumeGrid& grid,
                            const std::string& description);
    void (*write_vdb)(const std::string& path, const VolumeGrid& grid,
                      const std::string& description, const VdbOptions& options);
    VolumeGrid (*read_vdb)(const std::string& path, const std::string& name);
    std::vector<VdbGridHeader> (*list_vdb_grids)(const std::string& path);
    VdbVectorGrid (*read_vdb_vectors)(const std::string& path, const std::string& name,
                                      const VdbIndexBox* box);
    std::string (*encode_png)(int width, int height, const std::vector<float>& rgb);
    std::unique_ptr<VideoSink> (*make_video_sink)();
    void (*quiet_video_logs)();
    VideoInfo (*probe_video)(const std::string& path);
    std::vector<std::vector<float>> (*decode_video_luma)(const std::string& path, int& width,
                                                         int& height);
    void (*write_named_pixels)(const std::string& path, int width, int height,
                               const std::vector<std::string>& names, const float* pixels,
                               const Metadata& metadata, bool bits16,
                               const std::string& compression);
    Frame (*read_channel)(const std::string& path, const std::string& name);
    std::vector<std::string> (*channel_names)(const std::string& path);
    VdbIndexBox (*read_vdb_active_box)(const std::string& path, const std::string& name);
};

/// Bumped whenever IoModule or a type it passes changes.
constexpr int kIoModuleAbi = 5;

/// The module: the linked-in table when the program carries impulse::output_io, else
/// libimpulse_io.so loaded on first use from beside the executable, from ../lib/impulse/ next
/// to it (an installed tree) or from the install prefix. Thread-safe. Throws IoError naming
/// the places looked in and dlerror's reason.
const IoModule& io_module();

}  // namespace impulse::output

/// The module's one exported symbol (C linkage, so dlsym finds it by this name).
extern "C" const impulse::output::IoModule* impulse_io_module();
