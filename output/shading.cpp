// SPDX-License-Identifier: Apache-2.0
// Colour ramps, height-field lighting and alpha compositing.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "output/output.h"
#include "numeric/check.h"

namespace impulse::output {
namespace {

/// The averaged ramp's tables reach this many sd each side (the Gaussian's weight beyond is
/// 7e-6, under a 10-bit step).
constexpr double kAverageReach = 4.5;
/// Tables for sub-pixel sds below this many entries are not built: a quarter of an entry
/// (1/16384 of the display range) changes no 16-bit code.
constexpr float kMinLevelSd = 0.25f;

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

/// `table` (RGBA per entry) averaged over N(0, sd^2), sd in entries: the mean of the
/// premultiplied colour a c and of a over the distribution (compositing over the background is
/// linear in them), stored back as c = E[a c] / E[a] and E[a] so the per-pixel compositing is
/// unchanged. Trapezoid rule at steps of sd / 8 over +-kAverageReach sd, the table linearly
/// interpolated and held at its ends (the tone curve's limits): for a table with slope jumps J
/// (display units per unit) its error is about 5e-4 J sd (docs/shading.md "The averaged ramp").
std::vector<float> averaged_table(const std::vector<float>& table, double sd) {
    const int n = int(table.size() / 4);
    std::vector<float> pre(table.size());
    for (size_t i = 0; i < table.size(); i += 4)
        for (int k = 0; k < 4; ++k) pre[i + k] = k < 3 ? table[i + 3] * table[i + k] : table[i + 3];
    const double step = sd / 8.0;
    const int taps = int(std::ceil(kAverageReach * 8.0));
    std::vector<double> w(size_t(2 * taps + 1));
    double sum = 0.0;
    for (int k = -taps; k <= taps; ++k) sum += w[size_t(k + taps)] = std::exp(-0.5 * (k / 8.0) * (k / 8.0));
    for (double& v : w) v /= sum;
    std::vector<float> out(table.size());
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& r) {
        for (int i = r.begin(); i < r.end(); ++i) {
            double acc[4] = {0, 0, 0, 0};
            for (int k = -taps; k <= taps; ++k) {
                const double x = std::clamp(i + k * step, 0.0, double(n - 1));
                const int i0 = std::min(n - 2, int(x));
                const double f = x - i0;
                const float* a = pre.data() + 4 * size_t(i0);
                for (int c = 0; c < 4; ++c) acc[c] += w[size_t(k + taps)] * (a[c] + f * (a[4 + c] - a[c]));
            }
            float* o = out.data() + 4 * size_t(i);
            o[3] = float(acc[3]);
            for (int c = 0; c < 3; ++c) o[c] = acc[3] > 1e-12 ? float(acc[c] / acc[3]) : table[4 * size_t(i) + c];
        }
    });
    return out;
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
    const double span = mapping.hi - mapping.lo;
    // With sub-pixel sd the averaged tables reach 4.5 sd further each side: a pixel past the
    // clip still sees the part of its distribution inside (docs/shading.md "The averaged ramp").
    float sd_max = 0.0f;
    for (float v : sh.subpixel_sd) sd_max = std::max(sd_max, v);
    const double reach = sd_max > 0.0f ? kAverageReach * sd_max / std::abs(span) : 0.0;
    const double x0 = -roll_off_span(sh.toe) - reach, x1 = 1.0 + roll_off_span(sh.shoulder) + reach;
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
    if (sd_max > 0.0f) build_levels(sh.subpixel_sd);
    build_yuv_tables();
}

void Shader::build_levels(const std::vector<float>& subpixel_sd) {
    // docs/shading.md "The averaged ramp": the sub-pixel sd of each height in table entries.
    m_row_sd.resize(subpixel_sd.size());
    for (size_t i = 0; i < subpixel_sd.size(); ++i)
        m_row_sd[i] = std::max(0.0f, subpixel_sd[i] * std::abs(m_scale));
    const auto [lo_it, hi_it] = std::minmax_element(m_row_sd.begin(), m_row_sd.end());
    if (*lo_it == *hi_it) {  // one sd for every row: its table replaces m_lut, exactly
        m_plain_grey = false;
        m_lut = averaged_table(m_lut, *hi_it);
        m_row_sd.clear();
        return;
    }
    // Tables at sds rising by 2^(1/8) from the least that changes the table (kMinLevelSd) or
    // the least row's, to the largest row's; a row interpolates the two bracketing it, linearly
    // in log sd.
    if (*hi_it < kMinLevelSd) {
        m_row_sd.clear();
        return;
    }
    m_plain_grey = false;
    float first = *hi_it;
    for (float v : m_row_sd)
        if (v >= kMinLevelSd) first = std::min(first, v);
    const int count = 1 + std::max(0, int(std::ceil(8.0 * std::log2(*hi_it / first) - 1e-9)));
    for (int j = 0; j < count; ++j) m_level_sd.push_back(float(first * std::exp2(j / 8.0)));
    // The frames of a video share the ramp, the mapping and (a camera without keys) the rows'
    // sds, and each builds a Shader: the last tables built are kept and reused when both match.
    static std::mutex cache_mutex;
    static std::vector<float> cached_base, cached_sd;
    static std::shared_ptr<const Levels> cached;
    {
        const std::lock_guard lock(cache_mutex);
        if (cached && cached_base == m_lut && cached_sd == m_level_sd) {
            m_levels = cached;
            return;
        }
    }
    auto levels = std::make_shared<Levels>();
    auto& tables = levels->tables;
    tables.resize(size_t(count));
    tbb::parallel_for(0, count, [&](int j) { tables[size_t(j)] = averaged_table(m_lut, m_level_sd[size_t(j)]); });
    // A row below kMinLevelSd, shaded with m_lut, errs by at most that sd's table's difference
    // from it.
    const auto premultiplied = [](const float* c, int k) { return k < 3 ? c[3] * c[k] : c[3]; };
    const auto largest_difference = [&](const std::vector<float>& a, const std::vector<float>& b) {
        double d = 0.0;
        for (size_t i = 0; i < a.size(); i += 4)
            for (int k = 0; k < 4; ++k)
                d = std::max(d, double(std::abs(premultiplied(&a[i], k) - premultiplied(&b[i], k))));
        return d;
    };
    double& error = levels->error;
    error = largest_difference(m_lut, averaged_table(m_lut, kMinLevelSd));
    // Linear interpolation between neighbours errs by about an eighth of the second difference
    // of three neighbours (f'' h^2 / 8 against the second difference f'' h^2); a pair alone, by
    // at most half its difference.
    if (tables.size() == 2) error = std::max(error, 0.5 * largest_difference(tables[0], tables[1]));
    for (size_t j = 1; j + 1 < tables.size(); ++j) {
        double d2 = 0.0;
        for (size_t i = 0; i < m_lut.size(); i += 4)
            for (int k = 0; k < 4; ++k)
                d2 = std::max(d2, double(std::abs(premultiplied(&tables[j + 1][i], k) -
                                                  2.0f * premultiplied(&tables[j][i], k) +
                                                  premultiplied(&tables[j - 1][i], k))));
        error = std::max(error, d2 / 8.0);
    }
    m_levels = levels;
    const std::lock_guard lock(cache_mutex);
    cached_base = m_lut, cached_sd = m_level_sd, cached = std::move(levels);
}

Shader::RowTables Shader::row_tables(int y, int h) const {
    if (!m_levels) return {m_lut.data(), nullptr, 0.0f};
    const size_t n = m_row_sd.size();
    float sd = m_row_sd.front();
    if (n > 1) {
        const float u = (h > 1 ? float(y) / float(h - 1) : 0.0f) * float(n - 1);
        const size_t i = std::min(n - 2, size_t(u));
        sd = m_row_sd[i] + (u - float(i)) * (m_row_sd[i + 1] - m_row_sd[i]);
    }
    if (sd < kMinLevelSd) return {m_lut.data(), nullptr, 0.0f};
    // The two tables bracketing sd, weighted linearly in log sd.
    const auto& tables = m_levels->tables;
    const int last = int(tables.size()) - 1;
    const double u = std::clamp(8.0 * std::log2(sd / m_level_sd.front()), 0.0, double(last));
    const int j = std::min(last - 1, int(u));
    if (j < 0) return {tables.front().data(), nullptr, 0.0f};
    return {tables[size_t(j)].data(), tables[size_t(j) + 1].data(), float(u - j)};
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
        const RowTables lut = row_tables(y, h);
        const float* row = field.data.data() + size_t(y) * w;
        float* o = rgb + size_t(y - y0) * w * 3;
        for (int x = 0; x < w; ++x) {
            const float fi = std::clamp((row[x] - lo) * scale, 0.0f, m_last);
            if (m_plain_grey) {  // the exact display value, as the grey image path writes it
                const float t = fi / m_last;
                o[3 * x] = o[3 * x + 1] = o[3 * x + 2] = t;
                continue;
            }
            const float* c0 = lut.lo + size_t(fi + 0.5f) * 4;
            float c[4] = {c0[0], c0[1], c0[2], c0[3]};
            if (lut.hi) {  // between two averaged tables: premultiplied colours interpolated
                const float* c1 = lut.hi + size_t(fi + 0.5f) * 4;
                const float w = lut.weight, a = c0[3] + w * (c1[3] - c0[3]);
                for (int k = 0; k < 3; ++k) {
                    const float p = c0[3] * c0[k] + w * (c1[3] * c1[k] - c0[3] * c0[k]);
                    c[k] = a > 1e-12f ? p / a : c0[k];
                }
                c[3] = a;
            }
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

void Shader::alpha_rows(const Frame& field, int y0, int y1, float* alpha) const {
    const int w = field.width;
    for (int y = y0; y < y1; ++y) {
        const RowTables lut = row_tables(y, field.height);
        const float* row = field.data.data() + size_t(y) * w;
        float* o = alpha + size_t(y - y0) * w;
        for (int x = 0; x < w; ++x) {
            const size_t i = size_t(std::clamp((row[x] - m_lo) * m_scale, 0.0f, m_last) + 0.5f) * 4 + 3;
            const float a = lut.hi ? lut.lo[i] + lut.weight * (lut.hi[i] - lut.lo[i]) : lut.lo[i];
            o[x] = std::clamp(a, 0.0f, 1.0f);
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
    if (!sh.subpixel_sd.empty()) {  // the averaged ramp's coverage (docs/shading.md)
        Shader(mapping, sh).alpha_rows(field, 0, field.height, alpha.data());
        return;
    }
    const double inv = 1.0 / (mapping.hi - mapping.lo);
    for (size_t i = 0; i < alpha.size(); ++i) {
        float c[4];
        ramp_at(sh.ramp, tone_curve((field.data[i] - mapping.lo) * inv, sh.toe, sh.shoulder), c);
        alpha[i] = std::clamp(c[3], 0.0f, 1.0f);
    }
}

}  // namespace impulse::output
