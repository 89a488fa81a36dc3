// SPDX-License-Identifier: Apache-2.0
#pragma once
// Images through OpenImageIO (part of impulse::output; loaded when first used: io_module.h): frames written atomically (a
// temporary file renamed into place), read as single-channel float, probed from headers.

#include <cstddef>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "numeric/frame.h"

namespace impulse::output {

using numeric::Frame;

/// Linear map from field values to display [0, 1]: v -> (v - lo) / (hi - lo), then clamped to
/// [0, 1] and quantised with rounding for 8/16-bit formats. EXR stores the raw values.
struct ValueMapping {
    double lo = -1.0, hi = 1.0;
};

/// Loads the image and video module (OpenImageIO, libav, OpenVDB: ~260 libraries, ~0.3 s;
/// io_module.h) on a thread of its own while the caller goes on, so a process that will write
/// a still overlaps that load with its scene set-up and render instead of paying them in turn
/// (docs/design.md §2). The destructor waits for the load; a load that failed is tried again,
/// and its error thrown, where the module is first used.
class IoPreload {
public:
    IoPreload();
    ~IoPreload();
    IoPreload(const IoPreload&) = delete;
    IoPreload& operator=(const IoPreload&) = delete;

private:
    std::thread m_thread;
};

/// Metadata written into images and videos.
using Metadata = std::vector<std::pair<std::string, std::string>>;

/// EXR compression when none is chosen (output.compression): see kExrCompressions.
inline constexpr const char* kDefaultExrCompression = "none";
/// The EXR compressions output.compression accepts, as OpenImageIO names OpenEXR's: lossless
/// none, rle, zips (one scanline a block), zip (16), piz (wavelet); pxr24 (float to 24 bits),
/// b44, b44a, dwaa, dwab (lossy).
inline constexpr const char* kExrCompressions[] = {"none", "rle",  "zips", "zip",  "piz",
                                                   "pxr24", "b44", "b44a", "dwaa", "dwab"};

/// Writes a frame with OpenImageIO, format from the extension (.exr float; .png 8-bit, or
/// 16-bit when `bits16`; .tif/.tiff 16-bit). The file is written to a temporary name in the
/// same directory and renamed, so a partial file never appears under `path`. `compression`
/// is an EXR's (one of kExrCompressions; "" for kDefaultExrCompression), ignored by other
/// formats. Throws IoError with OIIO's message.
void write_image(const std::string& path, const Frame& frame, const ValueMapping& mapping,
                 const Metadata& metadata, bool bits16 = false,
                 const std::string& compression = "");
/// Same for an RGB float frame (3 floats per pixel, display values in [0, 1] already mapped).
void write_rgb_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                     const Metadata& metadata, bool bits16 = false);
/// Writes `names.size()` named channels (interleaved floats, `names` in order) as one image:
/// a multi-channel EXR (float, `compression` as write_image's), or a PNG/TIFF of at most four
/// channels whose values are display values in [0, 1] already (`bits16` as write_image's).
/// A channel named "A" is the alpha channel. Atomic as write_image; throws IoError.
void write_named_channels(const std::string& path, int width, int height,
                          const std::vector<std::string>& names, const std::vector<float>& pixels,
                          const Metadata& metadata, bool bits16 = false,
                          const std::string& compression = "");
/// The channel `name` of an image (a multi-channel EXR's "value", "N.X" ...) as float. Throws
/// IoError naming the file and listing its channels when it has none of that name.
Frame read_channel(const std::string& path, const std::string& name);
/// The channel names of an image, in the order OpenImageIO reads them. Throws IoError.
std::vector<std::string> channel_names(const std::string& path);
/// Reads an image as single-channel float (luminance of RGB; raw floats for EXR, [0,1] for
/// integer formats). Throws IoError.
Frame read_image(const std::string& path);
/// "" when every value of an image's pixels (`channels` interleaved, rows of `width`) is finite,
/// else "expected finite pixel values, found nan at pixel (x, y) channel c" for the first that
/// is not: image inputs are refused with it (a NaN breaks the sorts and sums they go through).
std::string nonfinite_pixel(const float* px, size_t count, int width, int channels);

/// "" when an image header's size (any values: a corrupt or hostile file can claim anything) is
/// one this program reads: a 2-D image (depth 1) with width, height and channels > 0 whose pixels
/// as floats fit within OpenImageIO's limits:imagesize_MB (32 GB by default; OIIO::attribute
/// raises or lowers it); else what is wrong. Every image reader checks it before allocating.
std::string image_size_problem(int width, int height, int depth, int channels);

/// Why the image file `path` is not the frame write_image (or write_rgb_image) would write with
/// these arguments, or "" when it is, for --resume: it must decode completely (a truncated file
/// does not), have `width` x `height` pixels, `channels` channels and the sample type of the
/// extension (and `bits16`), and carry each of `metadata`'s keys as impulse:KEY with the same
/// value in the formats that store them (EXR, PNG; TIFF and JPEG keep no metadata here). The
/// reason is one line ("truncated or unreadable: ...", "impulse:seed is 7, expected 8").
std::string image_mismatch(const std::string& path, int width, int height, int channels,
                           bool bits16, const Metadata& metadata);
/// The impulse:KEY attributes of an image's header (KEY without the prefix, string values), in
/// the header's order; empty for a file without them. Throws IoError with OIIO's message.
Metadata read_metadata(const std::string& path);
/// True when files of this extension keep write_image's metadata (.exr, .png).
bool keeps_metadata(const std::string& path);

/// True for extensions OIIO writes here (.exr .png .tif .tiff .jpg .jpeg).
bool is_image_path(const std::string& path);

/// What an image file holds, read from its header only (no pixels).
struct ImageInfo {
    int width = 0, height = 0, channels = 0;
    bool is_float = false;  ///< float or half samples: raw field values, not display values
    int bits = 8;           ///< bits per sample (8, 16, 32 ...)
};
/// Header of an image in any format OIIO reads. Throws IoError with OIIO's message.
ImageInfo probe_image(const std::string& path);
/// True when the extension belongs to a format this OIIO build can read (case-insensitive;
/// e.g. .exr .hdr .png .tif .jpg .bmp .tga .dpx).
bool is_readable_image_path(const std::string& path);

}  // namespace impulse::output
