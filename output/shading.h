// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shading: from a float field to display RGB — colour ramps, height-field lighting (Lewis's
// figures shade noise "as an obliquely illuminated height field"), and alpha over a sky
// gradient. Part of impulse::output; included by output/output.h.

#include <cstdint>
#include <memory>
#include <vector>

#include "numeric/frame.h"

namespace impulse::output {

using numeric::Frame;
struct ValueMapping;

/// One stop of a colour ramp: at display value t (0..1 after the value mapping) the colour
/// (r, g, b) and opacity a, all in [0, 1]; linear interpolation between stops.
struct ColorStop {
    double t = 0.0;
    float r = 0, g = 0, b = 0, a = 1;
};

struct Shading {
    /// Empty: grey (r = g = b = display value, opaque).
    std::vector<ColorStop> ramp;
    /// Height-field lighting: the field is a height map scaled by `relief` (height units per
    /// field unit per pixel); 0 disables. Lambert with `ambient`, light from azimuth/elevation.
    double relief = 0.0;
    double light_azimuth_deg = 135.0;   ///< direction the light comes from, in the image plane
    double light_elevation_deg = 35.0;  ///< above the plane
    double ambient = 0.25;
    /// Filmic tone curve (see `tone_curve`) between the linear value mapping and the ramp:
    /// `toe` and `shoulder` are the widths, in display units, of the exponential roll-offs
    /// towards black and white, each in [0, 0.5]; 0 and 0 is the hard clip.
    double toe = 0.0;
    double shoulder = 0.0;
    /// Background behind transparent parts (ramp alpha < 1): a vertical gradient.
    float top[3] = {0.25f, 0.45f, 0.85f};
    float bottom[3] = {0.70f, 0.82f, 0.95f};
    /// Non-empty: the background instead of the top-bottom gradient, RGB triples at n evenly
    /// spaced heights from the top row (0) to the bottom row (1), linear between (a scene's
    /// horizon and sea: scenes/frame/sea.cpp). Resolution-independent, like the gradient.
    std::vector<float> background;
    /// Filtering after shading (docs/shading.md "Filtering after shading"): a scene's
    /// `[shading] filter = "after"` (true, the default) has Scene::shading_at fill
    /// `subpixel_sd`; "before" (false) leaves it empty, so the filtered field is shaded as is.
    bool filter_after = true;
    /// The standard deviation, in field units, of the field within a pixel's filter that the
    /// filtered field does not show (var = int S(f) (1 - |G(f)|^2) df for the pixel filter G at
    /// the footprint), at n evenly spaced heights from the top row (0) to the bottom row (1),
    /// linear between (one value: every row). The ramp, after the tone curve, is averaged over
    /// N(value, sd^2), so the shaded pixel is the mean of the shading over the pixel's filter
    /// (docs/shading.md "The averaged ramp"). Empty or all 0: each pixel shaded at its value.
    std::vector<float> subpixel_sd;
};

/// The filmic tone curve from a linear display value x (any real; 0 and 1 where the value
/// mapping puts its lo and hi) to [0, 1]: the identity on [toe, 1 - shoulder], and exponential
/// roll-offs outside that meet it with the same value and slope (C1):
///     y = toe exp((x - toe) / toe)                                 for x < toe,
///     y = 1 - shoulder exp(-(x - (1 - shoulder)) / shoulder)       for x > 1 - shoulder,
/// so values past the mapping's ends are compressed instead of clipped: a tail of field values
/// that would sit on the top code value (a flat plate) keeps its gradation and reaches 1 only
/// in the limit. toe = 0 or shoulder = 0 is the hard clip at that end. Monotonic.
double tone_curve(double x, double toe, double shoulder);

/// Display RGB (3 floats per pixel in [0, 1]) of `field` under `mapping` and `shading`.
/// Deterministic; per-pixel work only (parallel over rows).
void shade(const Frame& field, const ValueMapping& mapping, const Shading& shading,
           std::vector<float>& rgb);

/// The coverage of each pixel of `field` under `shading`: the ramp's alpha at the pixel's
/// display value (through the tone curve), 1 without a ramp; one float per pixel into `alpha`.
/// With `subpixel_sd`, the averaged ramp's alpha (Shader::alpha_rows), as `shade` composites.
/// `shade` with a black background gives the matching premultiplied colour.
void shading_alpha(const Frame& field, const ValueMapping& mapping, const Shading& shading,
                   std::vector<float>& alpha);

/// Where the rows of an 8-bit YUV 4:2:0 picture go: three planes (the encoder's input picture,
/// or any buffer laid out like it), each pointer at the band's first row (its luma row y0 and
/// chroma row y0 / 2). Strides in bytes.
struct Yuv420Planes {
    uint8_t* y = nullptr;
    uint8_t* cb = nullptr;
    uint8_t* cr = nullptr;
    int y_stride = 0, cb_stride = 0, cr_stride = 0;
};

/// Display RGB rows (3 floats per pixel in [0, 1], `width` * 3 per row) as 8-bit YUV 4:2:0 in
/// one pass: BT.709 (ITU-R BT.709-6 item 3.2: Kr = 0.2126, Kb = 0.0722) limited range (Y' 16..235,
/// Cb Cr 16..240), rounded to nearest; each chroma sample is the mean of its 2x2 block of pixels
/// (centre-sited, AVCHROMA_LOC_CENTER, what swscale writes by default). `width` and `rows` even.
/// Deterministic: the same bytes on every SIMD path.
void rgb_rows_to_yuv420(const float* rgb, int width, int rows, const Yuv420Planes& planes);

/// `shade` prepared once for a mapping and a shading (the ramp table, the light), applied to
/// any band of rows: so a caller can shade a frame band by band into a small buffer instead of
/// holding the whole float RGB frame (the video path quantises each band to 8 or 16 bits at
/// once). Every pixel gets exactly the value `shade` gives it. Thread-safe once built.
class Shader {
public:
    Shader(const ValueMapping& mapping, const Shading& shading);
    /// Rows [y0, y1) of `field` (0 <= y0 <= y1 <= height) as display RGB into `rgb`: 3 floats
    /// per pixel, field.width * 3 per row, row y0 first.
    void rows(const Frame& field, int y0, int y1, float* rgb) const;
    /// Rows [y0, y1) of `field` shaded straight into 8-bit YUV 4:2:0 (y0 even; y1 even, the
    /// field's width even): what rgb_rows_to_yuv420 makes of `rows`, within one code value,
    /// without a float RGB frame. Without relief the ramp table is held in Y'CbCr (the
    /// conversion is linear, so it commutes with the compositing over the sky): a clamp, a
    /// lookup and a multiply-add per sample. With relief (lighting is not linear in the colour)
    /// two rows at a time go through `rows` and rgb_rows_to_yuv420. Deterministic; thread-safe.
    void rows_yuv420(const Frame& field, int y0, int y1, const Yuv420Planes& planes) const;
    /// Rows [y0, y1) of `field` as the coverage `rows` composites with: the ramp's alpha (the
    /// averaged ramp's, with sub-pixel sd), one float per pixel into `alpha`.
    void alpha_rows(const Frame& field, int y0, int y1, float* alpha) const;
    /// The predicted largest error, in display units (per channel, premultiplied), of shading a
    /// row by interpolating the averaged ramp's tables bracketing its sub-pixel sd instead of the
    /// table at that sd: an eighth of the largest second difference of neighbouring tables
    /// (docs/shading.md "The averaged ramp"). 0 with one table (one sub-pixel sd per frame).
    double level_error() const { return m_levels ? m_levels->error : 0.0; }
    /// The number of averaged ramp tables (0 without sub-pixel sd, or with one sd).
    int levels() const { return m_levels ? int(m_levels->tables.size()) : 0; }

private:
    void rows_yuv420_table(const Frame& field, int y, const Yuv420Planes& planes) const;
    void build_yuv_tables();
    void build_levels(const std::vector<float>& subpixel_sd);

    static constexpr int kLut = 4096;  ///< entries per unit of linear display value
    std::vector<float> m_lut;  ///< RGBA over the linear display values [x0, x1] the curve needs
    /// The same table premultiplied by alpha in Y'CbCr code units (Y' with its offset of 16, Cb
    /// and Cr with 128), and 1 - alpha: structure of arrays for rows_yuv420.
    std::vector<float> m_lut_y, m_lut_cb, m_lut_cr, m_lut_clear;
    float m_lo = 0, m_scale = 1, m_last = kLut - 1;
    float m_shoulder = 0;
    float m_lx = 0, m_ly = 0, m_lz = 1, m_relief = 0, m_ambient = 0;
    float m_top[3] = {}, m_bottom[3] = {};
    std::vector<float> m_background;
    bool m_plain_grey = true;
    /// The averaged ramp (docs/shading.md "The averaged ramp"): tables of m_lut's layout, each
    /// the table averaged over N(0, sd^2) for the sd in m_level_sd (table entries, rising by
    /// 2^(1/8)); m_row_sd the sub-pixel sd in table entries at m_row_sd.size() heights. One
    /// table: it is m_lut itself (m_levels empty).
    struct Levels {
        std::vector<std::vector<float>> tables;
        double error = 0.0;  ///< level_error
    };
    /// Shared with the Shaders of other frames built from the same table and sds (a cache).
    std::shared_ptr<const Levels> m_levels;
    std::vector<float> m_level_sd, m_row_sd;
    /// The RGBA tables of row y of h: m_lut, or the averaged tables bracketing the row's sd and
    /// the upper one's weight (hi null: lo alone).
    struct RowTables {
        const float* lo;
        const float* hi;
        float weight;
    };
    RowTables row_tables(int y, int h) const;
    /// The background of row y of h (the gradient, or the table).
    void background_row(int y, int h, float bg[3]) const;
};

}  // namespace impulse::output
