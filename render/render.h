// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::render — frame evaluation: tiled sparse convolution of the live impulses with the
// kernel (Lewis 1986 eq. 2), the naive per-pixel reference, the value mapping to display, and
// image and video output. Depends on kernels and sim; knows nothing of scene files or the CLI.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "kernels/kernels.h"
#include "render/shading.h"
#include "render/video.h"
#include "sim/sim.h"
#include "util/errors.h"

namespace impulse::render {

/// Orthographic view: pixel (i, j) (row j from the top) has its centre at texture point
/// (x0 + (i + 0.5) * scale, y0 + (j + 0.5) * scale).
struct View {
    int width = 0;
    int height = 0;
    double x0 = 0.0, y0 = 0.0;
    double scale = 1.0;  ///< texture units per pixel, > 0
    /// Texture-space box covered by the pixels.
    sim::Box box() const { return {x0, y0, x0 + width * scale, y0 + height * scale}; }
};

/// A single-channel float frame, row-major, top row first.
struct Frame {
    int width = 0, height = 0;
    std::vector<float> data;
    void resize(int w, int h) { width = w, height = h, data.assign(size_t(w) * h, 0.0f); }
    float at(int x, int y) const { return data[size_t(y) * width + x]; }
};

struct EvalOptions {
    int tile_size = 128;  ///< square tiles in pixels, >= 8; the result does not depend on it
    bool parallel = true;  ///< false: the serial path through the same code (debugging)
    bool use_avx2 = true;  ///< false: baseline SSE2 loops (bit-identical; for tests)
    /// > 0: a perspective frame (accumulate_perspective) whose impulses' pixel boxes add up to
    /// more than this is refused with render::PixelBudgetError before any pixel is evaluated.
    /// The impulse count alone does not bound the work: a footprint blurred isotropically
    /// (anisotropic = false) spreads a far impulse over a row of hundreds of pixels.
    double max_pixel_evaluations = 0.0;
};

/// Thrown by accumulate_perspective when EvalOptions::max_pixel_evaluations is exceeded.
class PixelBudgetError : public BudgetError {
public:
    PixelBudgetError(double needed, double budget);
    double needed, budget;
};

/// Adds sum_k w_k h_{theta_k}(x - x_k) to `out` (sized to the view; not cleared) for every
/// pixel centre. Deterministic: each pixel sums its impulses in their canonical order, so the
/// bits do not depend on the thread count or the tile size. Uses AVX2 where the CPU has it,
/// with the same arithmetic (no FMA contraction) as the baseline path. Throws ValueError naming
/// the first impulse whose position (in pixels, as a float), orientation or weight is not
/// finite; accumulate_region too.
void accumulate(const kernels::Kernel& kernel, const sim::Impulses& impulses, const View& view,
                Frame& out, const EvalOptions& options = {});

/// Evaluates only the pixel rectangle [x0, x0+w) x [y0, y0+h) of the view into `tile`
/// (w*h floats, added to). Equal bits to the same pixels of `accumulate` (tiling independence).
void accumulate_region(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                       const View& view, int x0, int y0, int w, int h, float* tile,
                       const EvalOptions& options = {});

/// The naive reference (Lewis 1989 §4.1, and how shading-language sparse convolution noise
/// works): for every pixel, regenerate the impulses of the 3x3 neighbouring cells from the
/// counter-based generator and evaluate the kernel exactly in double. Still processes only;
/// needs config.cell_size >= kernel radius. Adds to `out`.
void accumulate_naive(const kernels::Kernel& kernel, const sim::ProcessConfig& config,
                      const View& view, Frame& out);

// ---------------------------------------------------------------------------------------------
// Output

/// Linear map from field values to display [0, 1]: v -> (v - lo) / (hi - lo), then clamped to
/// [0, 1] and quantised with rounding for 8/16-bit formats. EXR stores the raw values.
struct ValueMapping {
    double lo = -1.0, hi = 1.0;
};

/// Metadata written into images and videos.
using Metadata = std::vector<std::pair<std::string, std::string>>;

/// Writes a frame with OpenImageIO, format from the extension (.exr float; .png 8-bit, or
/// 16-bit when `bits16`; .tif/.tiff 16-bit). The file is written to a temporary name in the
/// same directory and renamed, so a partial file never appears under `path`. Throws IoError
/// with OIIO's message.
void write_image(const std::string& path, const Frame& frame, const ValueMapping& mapping,
                 const Metadata& metadata, bool bits16 = false);
/// Same for an RGB float frame (3 floats per pixel, display values in [0, 1] already mapped).
void write_rgb_image(const std::string& path, int width, int height, const std::vector<float>& rgb,
                     const Metadata& metadata, bool bits16 = false);
/// Why the image file `path` is not the frame write_image (or write_rgb_image) would write with
/// these arguments, or "" when it is, for --resume: it must decode completely (a truncated file
/// does not), have `width` x `height` pixels, `channels` channels and the sample type of the
/// extension (and `bits16`), and carry each of `metadata`'s keys as impulse:KEY with the same
/// value in the formats that store them (EXR, PNG; TIFF and JPEG keep no metadata here). The
/// reason is one line ("truncated or unreadable: ...", "impulse:seed is 7, expected 8").
std::string image_mismatch(const std::string& path, int width, int height, int channels,
                           bool bits16, const Metadata& metadata);
/// True when files of this extension keep write_image's metadata (.exr, .png).
bool keeps_metadata(const std::string& path);
/// Reads an image as single-channel float (luminance of RGB; raw floats for EXR, [0,1] for
/// integer formats). Throws IoError.
Frame read_image(const std::string& path);
/// "" when every value of an image's pixels (`channels` interleaved, rows of `width`) is finite,
/// else "expected finite pixel values, found nan at pixel (x, y) channel c" for the first that
/// is not: image inputs are refused with it (a NaN breaks the sorts and sums they go through).
std::string nonfinite_pixel(const float* px, size_t count, int width, int channels);

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

}  // namespace impulse::render

#include "render/perspective.h"  // cameras with anti-aliasing (kernel pyramid)
#include "render/transform.h"    // marble and wood field transforms
