// SPDX-License-Identifier: Apache-2.0
// A sample grid seen through a perspective camera (scenes/detail/source_grid.h): a mip pyramid of the
// grid and each pixel's footprint filtered from it (docs/scenes.md "Source layers under a
// perspective camera"; the probes form of docs/perspective.md §3.3 on a pyramid of the field
// instead of the kernel, and the same fade to the mean, §6).

#include "scenes/detail/source_grid.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "render/render.h"

namespace impulse::scenes::detail {
namespace {

constexpr int kMaxTapHalf = 8;  // at most 2 * 8 + 1 taps along the major axis, as the probes

// The grid halved: every level-(l+1) sample is a weighted sum of the level-l samples around its
// position, along x then along y, with the grid's own fold at the edges.
SampleGrid halve(const SampleGrid& g) {
    SampleGrid h;  // not a copy of g: its values would keep g's capacity
    h.n = std::max(1, g.n / 2);
    h.cell = 2.0 * g.cell;
    h.offset = g.offset;
    h.periodic = g.periodic;
    h.mean = g.mean;
    const bool centres = g.offset != 0.0;
    // Offset 0: level-(l+1) sample i sits on level-l sample 2i ([1 2 1] / 4); offset 0.5: between
    // samples 2i and 2i + 1 ([1 3 3 1] / 8).
    auto filter = [&](const float* in, int64_t stride, int64_t i) {
        auto at = [&](int64_t k) { return double(in[g.fold(k) * stride]); };
        const int64_t c = 2 * i;
        if (centres) return (at(c - 1) + 3.0 * at(c) + 3.0 * at(c + 1) + at(c + 2)) / 8.0;
        return (at(c - 1) + 2.0 * at(c) + at(c + 1)) / 4.0;
    };
    std::vector<float> rows(size_t(g.n) * h.n);  // x halved: g.n rows of h.n
    for (int j = 0; j < g.n; ++j)
        for (int i = 0; i < h.n; ++i)
            rows[size_t(j) * h.n + i] = float(filter(g.values.data() + size_t(j) * g.n, 1, i));
    h.values.assign(size_t(h.n) * h.n, 0.0f);
    for (int j = 0; j < h.n; ++j)
        for (int i = 0; i < h.n; ++i) h.values[size_t(j) * h.n + i] = float(filter(rows.data() + i, h.n, j));
    return h;
}

double mean_square(const std::vector<float>& v) {
    double s = 0.0;
    for (float x : v) s += double(x) * x;
    return s / double(v.size());
}

}  // namespace

std::optional<int> lattice_denominator(double p) {
    for (int b = 1; b <= kMaxCoherentDenominator; ++b) {
        const double a = p * b;
        if (std::abs(a - std::round(a)) <= 1e-9 * a) return b;
    }
    return std::nullopt;
}

std::array<std::complex<double>, kMaxCoherentDenominator> coherent_images(double nu, double p, int b,
                                                                          double phi) {
    std::array<std::complex<double>, kMaxCoherentDenominator> A{};
    // tri((k / b - phi) / p) > 0 for b (phi - p) < k < b (phi + p).
    const int64_t k0 = int64_t(std::ceil(b * (phi - p))), k1 = int64_t(std::floor(b * (phi + p)));
    for (int c = 0; c < b; ++c) {
        const double w = 2.0 * std::numbers::pi * (nu + c) / b;
        const std::complex<double> step = std::polar(1.0, w);
        std::complex<double> z = std::polar(1.0, w * double(k0)), sum = 0.0;
        for (int64_t k = k0; k <= k1; ++k, z *= step)
            sum += std::max(0.0, 1.0 - std::abs(double(k) / b - phi) / p) * z;
        A[size_t(c)] = sum / (b * p);
    }
    return A;
}

double GridPyramid::bytes(int n) {
    // Levels 1, 2, ... hold 1/4, 1/16, ... of the grid (1/3 in all) besides the copy of level 0;
    // the first halving's rows (n x n/2) and its result (n/2 x n/2) beside level 0: 7/4.
    return 4.0 * double(n) * double(n) * 7.0 / 4.0;
}

GridPyramid::GridPyramid(const SampleGrid& grid) {
    levels.push_back(grid);
    while (levels.back().n > 1) levels.push_back(halve(levels.back()));
    // Level l's field is level 0 filtered by the halvings (variance step 4^k per halving k, in
    // level-0 cells^2: 1/2 for [1 2 1] / 4, 3/4 for [1 3 3 1] / 8) and read bilinearly (a tent
    // of half-width 2^l: variance 4^l / 6).
    const double step = grid.offset != 0.0 ? 0.75 : 0.5;
    // The sd each level keeps is about the grid's mean (which every level keeps: the filters sum
    // to 1 and wrap or mirror), so the top level, the mean itself, keeps none.
    const double m2 = grid.mean * grid.mean;
    const double var0 = mean_square(grid.values) - m2;
    for (size_t l = 0; l < levels.size(); ++l) {
        const double q = std::pow(4.0, double(l));
        variance.push_back(step * (q - 1.0) / 3.0 + q / 6.0);
        const double var_l = std::max(0.0, mean_square(levels[l].values) - m2);
        sd_fraction.push_back(var0 > 0.0 ? std::sqrt(var_l / var0) : 0.0);
    }
}

double GridPyramid::level_value(int l, double X, double Y, double ex, double ey, double extra) const {
    const SampleGrid& g = levels[size_t(l)];
    const double scale = std::ldexp(1.0, -l), off = g.offset;
    if (!(extra > 0.0)) return g.sample(X * scale - off, Y * scale - off);
    // Copies of the level along the major axis with Gaussian weights whose variance is `extra`
    // (docs/perspective.md eq. 3.2), at most one level spacing apart.
    const double sd = std::sqrt(extra), spacing = std::ldexp(1.0, l);
    const int m = std::clamp(int(std::ceil(3.0 * sd / spacing)), 1, kMaxTapHalf);
    const double step = 3.0 * sd / m;
    double w[2 * kMaxTapHalf + 1], sw = 0.0, st2 = 0.0;
    for (int j = 0; j <= 2 * m; ++j) {
        const double t = (j - m) * step;
        w[j] = std::exp(-0.5 * t * t / extra);
        sw += w[j], st2 += w[j] * t * t;
    }
    const double stretch = std::sqrt(extra / (st2 / sw));  // the taps' variance is `extra` exactly
    double v = 0.0;
    for (int j = 0; j <= 2 * m; ++j) {
        const double t = (j - m) * step * stretch;
        v += w[j] * g.sample((X + t * ex) * scale - off, (Y + t * ey) * scale - off);
    }
    return v / sw;
}

double GridPyramid::level_for(double var_minor, double var_major) const {
    const int top = int(levels.size()) - 1;
    // Across: the level whose own blur is the footprint's (linear in the variance between levels).
    double lambda = 0.0;
    for (int l = 0; l < top && var_minor > variance[size_t(l)]; ++l)
        lambda = l + std::min(1.0, (var_minor - variance[size_t(l)]) /
                                       (variance[size_t(l) + 1] - variance[size_t(l)]));
    // Along: no coarser than the taps can cover (3 sd within kMaxTapHalf spacings), as the probes'
    // budget widens the isotropic part (docs/perspective.md eq. 3.3).
    int need = 0;
    while (need < top &&
           9.0 * std::max(0.0, var_major - variance[size_t(need)]) >
               std::pow(kMaxTapHalf * std::ldexp(1.0, need), 2))
        ++need;
    return std::min(double(top), std::max(lambda, double(need)));
}

double GridPyramid::filtered(double X, double Y, double var_major, double var_minor, double ex,
                             double ey, double cutoff) const {
    const double lambda = level_for(var_minor, var_major);
    const int lo = int(std::floor(lambda)), hi = std::min(lo + 1, int(levels.size()) - 1);
    const double a = lambda - lo;
    // The remaining sd, log-linear between levels, fades the field to the grid's own mean (what
    // the top level, one sample, holds: the mean the near pixels average to) as the impulse
    // layers' kernels fade to theirs (docs/perspective.md §6).
    const double sd = std::exp((1.0 - a) * std::log(std::max(sd_fraction[size_t(lo)], 1e-300)) +
                               a * std::log(std::max(sd_fraction[size_t(hi)], 1e-300)));
    const double fade = cutoff > 0.0 ? render::fade_weight(sd, cutoff) : 1.0;
    const double mean = levels.front().mean;
    if (fade == 0.0) return mean;
    double v = level_value(lo, X, Y, ex, ey, var_major - variance[size_t(lo)]);
    if (a > 0.0 && hi != lo)
        v = (1.0 - a) * v + a * level_value(hi, X, Y, ex, ey, var_major - variance[size_t(hi)]);
    return mean + fade * (v - mean);
}

void GridPyramid::add(const PixelFootprints& px, double dx, double dy, numeric::Frame& out) const {
    const double cell = levels.front().cell, c = px.filter_sd_px / cell, mean = levels.front().mean;
    tbb::parallel_for(0, px.height, [&](int j) {
        for (int i = 0; i < px.width; ++i) {
            const size_t p = size_t(j) * px.width + i;
            if (!(px.s_major[p] > 0.0f)) {  // the ray misses the plane: the mean faded to
                if (mean != 0.0) out.data[p] = static_cast<float>(out.data[p] + mean);
                continue;
            }
            const double sM = c * px.s_major[p], sm = c * px.s_minor[p];
            const double v = filtered((px.x[p] - dx) / cell, (px.y[p] - dy) / cell, sM * sM,
                                      sm * sm, px.ex[p], px.ey[p], px.cutoff);
            out.data[p] = static_cast<float>(out.data[p] + v);
        }
    });
}

}  // namespace impulse::scenes::detail
