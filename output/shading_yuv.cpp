// SPDX-License-Identifier: Apache-2.0
// Shading straight into the encoder's 8-bit YUV 4:2:0 planes (output/shading.h): BT.709 limited
// range in one pass from the field, without a float RGB frame or a swscale pass. Plain loops over
// arrays the compiler vectorises; -ffp-contract=off and a fixed order of operations keep the bytes
// the same on every SIMD path.

#include <algorithm>
#include <vector>

#include "output/output.h"

namespace impulse::output {
namespace {

// ITU-R BT.709-6 item 3.2: E'y = Kr E'r + Kg E'g + Kb E'b with Kr = 0.2126, Kb = 0.0722; item
// 3.3: E'cb = (E'b - E'y) / 1.8556, E'cr = (E'r - E'y) / 1.5748; item 3.4 (8 bits, limited range):
// Y' = 16 + 219 E'y, Cb = 128 + 224 E'cb, Cr = 128 + 224 E'cr.
constexpr double kKr = 0.2126, kKb = 0.0722, kKg = 1.0 - kKr - kKb;
constexpr double kCbScale = 224.0 / 1.8556, kCrScale = 224.0 / 1.5748;

/// The rows of BT.709's matrix in code units: Y' - 16, Cb - 128, Cr - 128 from R'G'B' in [0, 1].
struct Bt709Matrix {
    double y[3] = {219.0 * kKr, 219.0 * kKg, 219.0 * kKb};
    double cb[3] = {-kCbScale * kKr, -kCbScale * kKg, kCbScale * (1.0 - kKb)};
    double cr[3] = {kCrScale * (1.0 - kKr), -kCrScale * kKg, -kCrScale * kKb};
};
constexpr Bt709Matrix kBt709;

/// One row of the matrix in float, for the per-pixel loops.
struct Weights {
    float r, g, b;
    constexpr explicit Weights(const double (&w)[3])
        : r(float(w[0])), g(float(w[1])), b(float(w[2])) {}
    float operator()(float R, float G, float B) const { return r * R + g * G + b * B; }
};
constexpr Weights kY(kBt709.y), kCb(kBt709.cb), kCr(kBt709.cr);

/// Nearest 8-bit code of `v` (half up; clamped to 0..255, NaN -> 0).
inline uint8_t to_code(float v) {
    v += 0.5f;
    v = v > 0.0f ? (v < 255.0f ? v : 255.0f) : 0.0f;
    return static_cast<uint8_t>(static_cast<int>(v));
}

/// The planes moved down to luma row `dy` (even) of the band.
Yuv420Planes planes_at(const Yuv420Planes& p, int dy) {
    Yuv420Planes q = p;
    q.y += size_t(dy) * p.y_stride;
    q.cb += size_t(dy / 2) * p.cb_stride;
    q.cr += size_t(dy / 2) * p.cr_stride;
    return q;
}

/// The table entry of field value v: Shader::rows's clamp to [0, last] (NaN -> 0) and nearest
/// entry.
inline int table_index(float v, float lo, float scale, float last) {
    float fi = (v - lo) * scale;
    fi = fi > 0.0f ? (fi < last ? fi : last) : 0.0f;
    return static_cast<int>(fi + 0.5f);
}

}  // namespace

void rgb_rows_to_yuv420(const float* rgb, int width, int rows, const Yuv420Planes& planes) {
    const size_t row_values = size_t(width) * 3;
    for (int r = 0; r + 1 < rows; r += 2) {
        const Yuv420Planes p = planes_at(planes, r);
        const float* top = rgb + size_t(r) * row_values;
        const float* bottom = top + row_values;
        for (int x = 0; x < width; ++x) {
            p.y[x] = to_code(16.0f + kY(top[3 * x], top[3 * x + 1], top[3 * x + 2]));
            p.y[p.y_stride + x] =
                to_code(16.0f + kY(bottom[3 * x], bottom[3 * x + 1], bottom[3 * x + 2]));
        }
        // Centre-sited chroma: the mean colour of each 2x2 block (the matrix is linear, so this
        // is the mean of the four pixels' Cb and Cr).
        for (int k = 0; k < width / 2; ++k) {
            float m[3];
            for (int c = 0; c < 3; ++c)
                m[c] = ((top[6 * k + c] + top[6 * k + 3 + c]) +
                        (bottom[6 * k + c] + bottom[6 * k + 3 + c])) * 0.25f;
            p.cb[k] = to_code(128.0f + kCb(m[0], m[1], m[2]));
            p.cr[k] = to_code(128.0f + kCr(m[0], m[1], m[2]));
        }
    }
}

/// The RGBA table in Y'CbCr: compositing a colour c of opacity a over the sky s gives
/// a c + (1 - a) s, and the matrix M is linear, so M(a c + (1 - a) s) = M(a c) + (1 - a) M s: the
/// table holds M(a c) (with the offsets 16 and 128) and 1 - a, a row holds M s.
void Shader::build_yuv_tables() {
    const size_t n = m_lut.size() / 4;
    m_lut_y.resize(n), m_lut_cb.resize(n), m_lut_cr.resize(n), m_lut_clear.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const float* c = m_lut.data() + 4 * i;
        const double a = c[3], r = a * c[0], g = a * c[1], b = a * c[2];
        m_lut_y[i] = float(16.0 + kBt709.y[0] * r + kBt709.y[1] * g + kBt709.y[2] * b);
        m_lut_cb[i] = float(128.0 + kBt709.cb[0] * r + kBt709.cb[1] * g + kBt709.cb[2] * b);
        m_lut_cr[i] = float(128.0 + kBt709.cr[0] * r + kBt709.cr[1] * g + kBt709.cr[2] * b);
        m_lut_clear[i] = float(1.0 - a);
    }
}


/// Rows y and y + 1 through the Y'CbCr table, in chunks whose indices stay in L1.
void Shader::rows_yuv420_table(const Frame& field, int y, const Yuv420Planes& p) const {
    const int w = field.width;
    const float* f0 = field.data.data() + size_t(y) * w;
    const float* f1 = f0 + w;
    float sky0[3], sky1[3];
    background_row(y, field.height, sky0);
    background_row(y + 1, field.height, sky1);
    const float y_sky0 = kY(sky0[0], sky0[1], sky0[2]), y_sky1 = kY(sky1[0], sky1[1], sky1[2]);
    const float cb_sky0 = kCb(sky0[0], sky0[1], sky0[2]), cb_sky1 = kCb(sky1[0], sky1[1], sky1[2]);
    const float cr_sky0 = kCr(sky0[0], sky0[1], sky0[2]), cr_sky1 = kCr(sky1[0], sky1[1], sky1[2]);
    const float* ly = m_lut_y.data();
    const float* lcb = m_lut_cb.data();
    const float* lcr = m_lut_cr.data();
    const float* clear = m_lut_clear.data();
    const float lo = m_lo, scale = m_scale, last = m_last;
    constexpr int kChunk = 512;  // even, so every chunk holds whole 2x2 blocks
    int i0[kChunk], i1[kChunk];
    for (int x0 = 0; x0 < w; x0 += kChunk) {
        const int n = std::min(kChunk, w - x0);
        for (int x = 0; x < n; ++x) i0[x] = table_index(f0[x0 + x], lo, scale, last);
        for (int x = 0; x < n; ++x) i1[x] = table_index(f1[x0 + x], lo, scale, last);
        uint8_t* y0 = p.y + x0;
        uint8_t* y1 = p.y + p.y_stride + x0;
        for (int x = 0; x < n; ++x) y0[x] = to_code(ly[i0[x]] + clear[i0[x]] * y_sky0);
        for (int x = 0; x < n; ++x) y1[x] = to_code(ly[i1[x]] + clear[i1[x]] * y_sky1);
        uint8_t* cb = p.cb + x0 / 2;
        uint8_t* cr = p.cr + x0 / 2;
        for (int k = 0; k < n / 2; ++k) {
            const int a = i0[2 * k], b = i0[2 * k + 1], c = i1[2 * k], d = i1[2 * k + 1];
            const float clear0 = clear[a] + clear[b], clear1 = clear[c] + clear[d];
            cb[k] = to_code(((lcb[a] + lcb[b]) + (lcb[c] + lcb[d]) + clear0 * cb_sky0 +
                             clear1 * cb_sky1) * 0.25f);
            cr[k] = to_code(((lcr[a] + lcr[b]) + (lcr[c] + lcr[d]) + clear0 * cr_sky0 +
                             clear1 * cr_sky1) * 0.25f);
        }
    }
}

void Shader::rows_yuv420(const Frame& field, int y0, int y1, const Yuv420Planes& planes) const {
    if (m_relief != 0.0f || m_levels) {
        // Lighting multiplies the colour and goes through the shoulder per channel: not linear
        // in the colour, so two rows at a time through rows() (the exact RGB) and the matrix.
        // So do rows whose averaged ramp differs by row (docs/shading.md "The averaged ramp").
        thread_local std::vector<float> pair;
        pair.resize(size_t(field.width) * 6);
        for (int y = y0; y + 1 < y1; y += 2) {
            rows(field, y, y + 2, pair.data());
            rgb_rows_to_yuv420(pair.data(), field.width, 2, planes_at(planes, y - y0));
        }
        return;
    }
    for (int y = y0; y + 1 < y1; y += 2) rows_yuv420_table(field, y, planes_at(planes, y - y0));
}

}  // namespace impulse::output
