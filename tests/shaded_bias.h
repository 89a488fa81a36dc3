// SPDX-License-Identifier: Apache-2.0
#pragma once
// The bias of shaded frames against a supersampled shaded reference (docs/shading.md
// "Measuring the bias"), for tests and impulse_bench_shaded_bias. The frame is the scene at
// W x H shaded as the product shades it; the reference is the same frame rendered unfiltered
// (camera.antialias = "off") at N W x N H, every fine pixel shaded, and filtered with the
// camera's Gaussian pixel filter (camera.filter pixels, N camera.filter fine pixels) sampled at
// the W x H pixel centres. Compared on the luma of the display RGB (BT.709 weights), per band of
// rows: perspective frames in `bands` equal bands from the top, orthographic ones whole.

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"

namespace impulse::test {

/// One band's comparison, in units of the reference's luma sd over the band.
struct ShadedBand {
    int row0 = 0, row1 = 0;   ///< rows [row0, row1)
    double ref_sd = 0.0;      ///< the reference's luma sd over the band
    double bias = 0.0;        ///< mean(frame - reference) / ref_sd
    double rms = 0.0;         ///< rms(frame - reference) / ref_sd
    /// The standard error of `bias`: the scatter of the means of 4 x 4-pixel blocks over the
    /// square root of their number (blocks four filter sds wide are nearly independent).
    double bias_se = 0.0;
};

struct ShadedBias {
    std::vector<ShadedBand> bands;
    double level_error = 0.0;  ///< the frame's Shader::level_error (display units)
    int levels = 0;            ///< its averaged tables
};

/// Luma of display RGB.
inline std::vector<double> shaded_luma(const render::Frame& field, const output::ValueMapping& m,
                                       const output::Shading& s) {
    std::vector<float> rgb;
    output::shade(field, m, s, rgb);
    std::vector<double> y(field.data.size());
    for (size_t i = 0; i < y.size(); ++i)
        y[i] = 0.2126 * rgb[3 * i] + 0.7152 * rgb[3 * i + 1] + 0.0722 * rgb[3 * i + 2];
    return y;
}

/// `fine` (n W x n H) filtered by a Gaussian of `sd` fine pixels and sampled at the W x H
/// pixel centres (separable, truncated at 5 sd, edges clamped).
inline std::vector<double> gaussian_downsample(const std::vector<double>& fine, int W, int H, int n,
                                               double sd) {
    const int SW = W * n, SH = H * n;
    const int reach = int(std::ceil(5.0 * sd));
    std::vector<double> w;
    double sum = 0.0;
    for (int k = -reach; k < n + reach; ++k) {
        const double d = k + 0.5 - 0.5 * n;
        w.push_back(std::exp(-0.5 * d * d / (sd * sd)));
        sum += w.back();
    }
    for (double& v : w) v /= sum;
    std::vector<double> rows(size_t(SH) * W, 0.0), out(size_t(W) * H, 0.0);
    for (int y = 0; y < SH; ++y)
        for (int i = 0; i < W; ++i) {
            double s = 0.0;
            for (size_t k = 0; k < w.size(); ++k)
                s += w[k] * fine[size_t(y) * SW + std::clamp(n * i - reach + int(k), 0, SW - 1)];
            rows[size_t(y) * W + i] = s;
        }
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double s = 0.0;
            for (size_t k = 0; k < w.size(); ++k)
                s += w[k] * rows[size_t(std::clamp(n * j - reach + int(k), 0, SH - 1)) * W + i];
            out[size_t(j) * W + i] = s;
        }
    return out;
}

/// The reference's luma for scene `path` (a file or a built-in name) with `sets` at W x H
/// (n x n samples per pixel) at frame `frame`.
inline std::vector<double> shaded_reference(const std::string& path, std::vector<std::string> sets,
                                            int W, int H, int n, int64_t frame,
                                            const output::ValueMapping& mapping) {
    sets.push_back("camera.antialias=\"off\"");
    scenes::Renderer fine(scenes::load_scene(path, sets, {W * n, H * n}));
    render::Frame f;
    fine.render(frame, f);
    output::Shading s = fine.scene().shading_at(fine.scene().frame_time(frame));
    s.subpixel_sd.clear();  // unfiltered: every sample shaded at its value
    return gaussian_downsample(shaded_luma(f, mapping, s), W, H, n, fine.scene().camera.filter * n);
}

/// The frame's luma against `reference` per band; `filter_after` false shades it as
/// `[shading] filter = "before"` does.
inline ShadedBias shaded_bias(const std::string& path, const std::vector<std::string>& sets, int W,
                              int H, int64_t frame, const std::vector<double>& reference,
                              bool filter_after, int bands = 8) {
    scenes::Renderer coarse(scenes::load_scene(path, sets, {W, H}));
    render::Frame f;
    coarse.render(frame, f);
    output::Shading s = coarse.scene().shading_at(coarse.scene().frame_time(frame));
    if (!filter_after) s.subpixel_sd.clear();
    const output::Shader shader(coarse.mapping(), s);
    ShadedBias out;
    out.level_error = shader.level_error(), out.levels = shader.levels();
    const std::vector<double> y = shaded_luma(f, coarse.mapping(), s);
    const bool perspective = coarse.scene().camera.type == scenes::CameraConfig::Type::Perspective;
    const int count = perspective ? bands : 1;
    for (int b = 0; b < count; ++b) {
        ShadedBand r;
        r.row0 = H * b / count, r.row1 = H * (b + 1) / count;
        double s1 = 0, s2 = 0, d1 = 0, d2 = 0;
        size_t n = 0;
        std::vector<double> blocks;
        for (int j0 = r.row0; j0 < r.row1; j0 += 4)
            for (int i0 = 0; i0 < W; i0 += 4) {
                double bd = 0;
                int bn = 0;
                for (int j = j0; j < std::min(j0 + 4, r.row1); ++j)
                    for (int i = i0; i < std::min(i0 + 4, W); ++i) {
                        const size_t p = size_t(j) * W + i;
                        const double d = y[p] - reference[p];
                        s1 += reference[p], s2 += reference[p] * reference[p];
                        d1 += d, d2 += d * d, bd += d, ++bn, ++n;
                    }
                blocks.push_back(bd / bn);
            }
        const double mean = s1 / n;
        r.ref_sd = std::sqrt(std::max(1e-30, s2 / n - mean * mean));
        r.bias = d1 / n / r.ref_sd;
        r.rms = std::sqrt(d2 / n) / r.ref_sd;
        double bm = 0, bv = 0;
        for (double v : blocks) bm += v;
        bm /= blocks.size();
        for (double v : blocks) bv += (v - bm) * (v - bm);
        r.bias_se = blocks.size() > 1
                        ? std::sqrt(bv / (blocks.size() - 1) / blocks.size()) / r.ref_sd
                        : 0.0;
        out.bands.push_back(r);
    }
    return out;
}

}  // namespace impulse::test
