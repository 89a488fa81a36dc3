// SPDX-License-Identifier: Apache-2.0
// Colour ramps, height-field lighting and alpha compositing.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "output/output.h"
#include "numeric/check.h"

namespace impulse::output {
namespace {

/// Ramp colour at display value t (stops sorted by t; clamped at the ends).
void ramp_at(const std::vector<ColorStop>& ramp, double t, float out[4]) {
    if (t <= ramp.front().t) {
        out[0] = ramp.front().r, out[1] = ramp.front().g, out[2] = ramp.front().b, out[3] = ramp.front().a;
        return;
    }
    for (size_t i = 1; i < ramp.size(); ++i) {
        if (t <= ramp[i].t) {
            const ColorStop& a = ramp[i - 1];
            const ColorStop& b = ramp[i];
            const float s = static_cast<float>((t - a.t) / std::max(1e-12, b.t - a.t));
            out[0] = a.r + s * (b.r - a.r);
            out[1] = a.g + s * (b.g - a.g);
            out[2] = a.b + s * (b.b - a.b);
            out[3] = a.a + s * (b.a - a.a);
            return;
        }
    }
    out[0] = ramp.back().r, out[1] = ramp.back().g, out[2] = ramp.back().b, out[3] = ramp.back().a;
}

/// How far past 0 (toe) or 1 (shoulder) the tone curve's roll-off of width w is still more
/// than 1/8192 from its limit (an eighth of a 10-bit step): the table ends there.
double roll_off_span(double w) {
    return w > 0.0 ? std::max(0.0, w * std::log(w * 8192.0) - w) : 0.0;
}

}  // namespace

double tone_curve(double x, double toe, double shoulder) {
    if (x < toe) return toe > 0.0 ? toe * std::exp((x - toe) / toe) : 0.0;
    const double knee = 1.0 - shoulder;
    if (x > knee) return shoulder > 0.0 ? 1.0 - shoulder * std::exp(-(x - knee) / shoulder) : 1.0;
    return x;
}

Shader::Shader(const ValueMapping& mapping, const Shading& sh) {
    // The tone curve and the ramp as a table of linear display value -> RGBA, 4096 entries per
    // unit (finer than 8- and 10-bit output can show), so the per-pixel work is a clamp, a
    // lookup and the compositing. Without a toe or shoulder the table spans [0, 1] (the clip).
    const double x0 = -roll_off_span(sh.toe), x1 = 1.0 + roll_off_span(sh.shoulder);
    const int n = static_cast<int>(std::lround((x1 - x0) * (kLut - 1))) + 1;
    m_lut.resize(size_t(n) * 4);
    for (int i = 0; i < n; ++i) {
        const double t = tone_curve(x0 + (x1 - x0) * i / (n - 1), sh.toe, sh.shoulder);
        float* c = m_lut.data() + size_t(i) * 4;
        if (sh.ramp.empty()) {
            c[0] = c[1] = c[2] = float(t), c[3] = 1.0f;
        } else {
            ramp_at(sh.ramp, t, c);
        }
    }
    const double span = mapping.hi - mapping.lo;
    m_lo = static_cast<float>(mapping.lo + x0 * span);
    m_scale = static_cast<float>((n - 1) / ((x1 - x0) * span));
    m_last = float(n - 1);
    m_shoulder = static_cast<float>(sh.shoulder);
    const double az = sh.light_azimuth_deg * std::numbers::pi / 180.0;
    const double el = sh.light_elevation_deg * std::numbers::pi / 180.0;
    // Light direction in image coordinates (x right, y down, z out of the screen).
    m_lx = float(std::cos(el) * std::cos(az)), m_ly = float(-std::cos(el) * std::sin(az));
    m_lz = float(std::sin(el));
    m_relief = static_cast<float>(sh.relief), m_ambient = static_cast<float>(sh.ambient);
    for (int k = 0; k < 3; ++k) m_top[k] = sh.top[k], m_bottom[k] = sh.bottom[k];
    m_background = sh.background;
    m_plain_grey = sh.ramp.empty() && sh.relief == 0.0 && sh.toe == 0.0 && sh.shoulder == 0.0;
    build_yuv_tables();
}

void Shader::background_row(int y, int h, float bg[3]) const {
    const float s = h > 1 ? float(y) / float(h - 1) : 0.0f;
    const size_t n = m_background.size() / 3;
    if (n < 2) {
        for (int k = 0; k < 3; ++k) bg[k] = m_top[k] + s * (m_bottom[k] - m_top[k]);
        return;
    }
    const float u = s * float(n - 1);
    const size_t i = std::min(n - 2, size_t(u));
    const float f = u - float(i);
    const float* a = m_background.data() + 3 * i;
    for (int k = 0; k < 3; ++k) bg[k] = a[k] + f * (a[3 + k] - a[k]);
}

void Shader::rows(const Frame& field, int y0, int y1, float* rgb) const {
    const int w = field.width, h = field.height;
    IMPULSE_DCHECK(field.data.size() == size_t(w) * size_t(h) && 0 <= y0 && y0 <= y1 && y1 <= h);
    const float lo = m_lo, scale = m_scale, relief = m_relief, ambient = m_ambient;
    const float lx = m_lx, ly = m_ly, lz = m_lz;
    for (int y = y0; y < y1; ++y) {
        float bg[3];
        background_row(y, h, bg);
        const float* row = field.data.data() + size_t(y) * w;
        float* o = rgb + size_t(y - y0) * w * 3;
        for (int x = 0; x < w; ++x) {
            const float fi = std::clamp((row[x] - lo) * scale, 0.0f, m_last);
            if (m_plain_grey) {  // the exact display value, as the grey image path writes it
                const float t = fi / m_last;
                o[3 * x] = o[3 * x + 1] = o[3 * x + 2] = t;
                continue;
            }
            const float* c0 = m_lut.data() + size_t(fi + 0.5f) * 4;
            float c[4] = {c0[0], c0[1], c0[2], c0[3]};
            if (relief != 0.0f) {
                // Central differences (one-sided at the borders) of the height field.
                const int x0 = std::max(0, x - 1), x1 = std::min(w - 1, x + 1);
                const int ya = std::max(0, y - 1), yb = std::min(h - 1, y + 1);
                const float dzdx = relief * (field.at(x1, y) - field.at(x0, y)) / float(std::max(1, x1 - x0));
                const float dzdy = relief * (field.at(x, yb) - field.at(x, ya)) / float(std::max(1, yb - ya));
                const float n = std::sqrt(dzdx * dzdx + dzdy * dzdy + 1.0f);
                const float lambert = std::max(0.0f, (-dzdx * lx - dzdy * ly + lz) / n);
                // Normalised so a flat field keeps its ramp colour.
                const float light = ambient + (1.0f - ambient) * lambert / std::max(1e-6f, lz);
                // Lit colours past white go through the same shoulder (a hard clip without one).
                for (int k = 0; k < 3; ++k)
                    c[k] = m_shoulder > 0.0f ? float(tone_curve(c[k] * light, 0.0, m_shoulder))
                                             : std::min(1.0f, c[k] * light);
            }
            for (int k = 0; k < 3; ++k) o[3 * x + k] = std::clamp(c[3] * c[k] + (1.0f - c[3]) * bg[k], 0.0f, 1.0f);
        }
    }
}

void shade(const Frame& field, const ValueMapping& mapping, const Shading& sh,
           std::vector<float>& rgb) {
    const int w = field.width, h = field.height;
    rgb.resize(size_t(w) * h * 3);
    const Shader shader(mapping, sh);
    tbb::parallel_for(0, h, [&](int y) { shader.rows(field, y, y + 1, rgb.data() + size_t(y) * w * 3); });
}

void shading_alpha(const Frame& field, const ValueMapping& mapping, const Shading& sh,
                   std::vector<float>& alpha) {
    alpha.assign(field.data.size(), 1.0f);
    if (sh.ramp.empty()) return;
    const double inv = 1.0 / (mapping.hi - mapping.lo);
    for (size_t i = 0; i < alpha.size(); ++i) {
        float c[4];
        ramp_at(sh.ramp, tone_curve((field.data[i] - mapping.lo) * inv, sh.toe, sh.shoulder), c);
        alpha[i] = std::clamp(c[3], 0.0f, 1.0f);
    }
}

}  // namespace impulse::output
