// SPDX-License-Identifier: Apache-2.0
// Colour ramps, height-field lighting and alpha compositing.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "render/render.h"

namespace impulse::render {
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

}  // namespace

void shade(const Frame& field, const ValueMapping& mapping, const Shading& sh,
           std::vector<float>& rgb) {
    const int w = field.width, h = field.height;
    rgb.resize(size_t(w) * h * 3);
    const double inv = 1.0 / (mapping.hi - mapping.lo);
    const double az = sh.light_azimuth_deg * std::numbers::pi / 180.0;
    const double el = sh.light_elevation_deg * std::numbers::pi / 180.0;
    // Light direction in image coordinates (x right, y down, z out of the screen).
    const double lx = std::cos(el) * std::cos(az), ly = -std::cos(el) * std::sin(az), lz = std::sin(el);
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const double v = field.at(x, y);
            const double t = std::clamp((v - mapping.lo) * inv, 0.0, 1.0);
            float c[4] = {float(t), float(t), float(t), 1.0f};
            if (!sh.ramp.empty()) ramp_at(sh.ramp, t, c);
            if (sh.relief != 0.0) {
                // Central differences (one-sided at the borders) of the height field.
                const int x0 = std::max(0, x - 1), x1 = std::min(w - 1, x + 1);
                const int y0 = std::max(0, y - 1), y1 = std::min(h - 1, y + 1);
                const double dzdx = sh.relief * (field.at(x1, y) - field.at(x0, y)) / std::max(1, x1 - x0);
                const double dzdy = sh.relief * (field.at(x, y1) - field.at(x, y0)) / std::max(1, y1 - y0);
                const double n = std::sqrt(dzdx * dzdx + dzdy * dzdy + 1.0);
                const double lambert = std::max(0.0, (-dzdx * lx - dzdy * ly + lz) / n);
                const float light = static_cast<float>(sh.ambient + (1.0 - sh.ambient) * lambert / std::max(1e-9, lz));
                for (int k = 0; k < 3; ++k) c[k] = std::min(1.0f, c[k] * light);
            }
            const float s = h > 1 ? float(y) / float(h - 1) : 0.0f;
            float* o = rgb.data() + (size_t(y) * w + x) * 3;
            for (int k = 0; k < 3; ++k) {
                const float bg = sh.top[k] + s * (sh.bottom[k] - sh.top[k]);
                o[k] = std::clamp(c[3] * c[k] + (1.0f - c[3]) * bg, 0.0f, 1.0f);
            }
        }
    });
}

}  // namespace impulse::render
