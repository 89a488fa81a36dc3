// SPDX-License-Identifier: Apache-2.0
// Tiled sparse convolution: impulses are binned into square tiles in their canonical order,
// tiles are evaluated in parallel, each pixel written by one task (design.md §3 "Evaluation").

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

#include "numeric/check.h"
#include "numeric/cpu.h"
#include "render/detail/eval.h"
#include "render/render.h"

namespace impulse::render {
namespace {

using detail::LoopImpulses;
using detail::LoopKernel;

/// Impulses in pixel coordinates with their orientation, for one frame.
struct Prepared {
    std::vector<float> px, py, w, c, s;
    LoopImpulses view() const { return {px.data(), py.data(), w.data(), c.data(), s.data()}; }
};

/// The kernel in pixel units, scaled by `s` (a scale class; 1: the kernel itself, the same
/// bits as before scale fields existed: every product and quotient with s = 1 is exact).
/// Scaling h(x) to h(x / s) multiplies lengths (radius, sigma) by s and divides frequencies by
/// s; the envelope's polynomial and tables are in q = r^2 / R^2 and serve every scale.
LoopKernel loop_kernel(const kernels::Kernel& k, const View& view, double s = 1.0) {
    const auto& p = k.params();
    LoopKernel lk;
    lk.radius_px = static_cast<float>(p.radius * s / view.scale);
    lk.inv_r2 = 1.0f / (lk.radius_px * lk.radius_px);
    lk.aspect2 = static_cast<float>(p.aspect * p.aspect);
    lk.carrier = k.has_carrier();
    lk.freq_cpp = static_cast<float>(p.frequency * view.scale / s);
    lk.phase_cycles = static_cast<float>(p.phase / (2.0 * std::numbers::pi));
    lk.general = lk.carrier || p.aspect != 1.0;
    // Isotropic Gaussian envelopes (gaussian; gabor with aspect 1) take the separable path.
    if (p.aspect == 1.0 && (p.type == kernels::KernelType::Gaussian ||
                            p.type == kernels::KernelType::Gabor)) {
        lk.separable = true;
        const double u = view.scale;  // texture units per pixel
        const double sigma = p.sigma * s, a = k.gabor_a() / s;
        lk.gauss_g = static_cast<float>(p.type == kernels::KernelType::Gaussian
                                            ? u * u / (2.0 * sigma * sigma)
                                            : std::numbers::pi * a * a * u * u);
    }
    lk.coeffs = k.polynomial().coefficients.data();
    lk.ncoeffs = static_cast<int>(k.polynomial().coefficients.size());
    if (!k.polynomial().monomial.empty()) {
        lk.mono = k.polynomial().monomial.data();
        lk.nmono = static_cast<int>(k.polynomial().monomial.size());
    }
    lk.aspect = static_cast<float>(p.aspect);
    if (!k.envelope_table().empty()) {
        lk.table = k.envelope_table().data();
        lk.table_n = static_cast<int>(k.envelope_table().size());
    }
    if (k.is_grid()) {
        lk.grid = k.grid_values().data();
        lk.grid_n = p.sampled->n;
    }
    return lk;
}

/// Throws ValueError naming the first impulse of `imp` that is not finite in `view`'s pixel
/// coordinates (a NaN breaks the tile binning: an out-of-range cast to int).
[[noreturn]] void refuse_nonfinite(const Prepared& p, const sim::Impulses& imp, const char* api) {
    for (size_t i = 0; i < p.px.size(); ++i) {
        std::ostringstream s;
        s << api << ": impulse " << i << ": ";
        if (!std::isfinite(p.px[i]))
            s << "x = " << imp.x[i];
        else if (!std::isfinite(p.py[i]))
            s << "y = " << imp.y[i];
        else if (!std::isfinite(p.c[i]) || !std::isfinite(imp.theta[i]))
            s << "theta = " << imp.theta[i];
        else if (!std::isfinite(p.w[i]))
            s << "weight = " << imp.weight[i];
        else
            continue;
        throw ValueError(s.str() + ": expected finite impulse coordinates, orientations and weights");
    }
    throw ValueError(std::string(api) + ": expected finite impulses");
}

Prepared prepare(const kernels::Kernel& k, const sim::Impulses& imp, const View& view,
                 const char* api) {
    Prepared p;
    const size_t n = imp.size();
    IMPULSE_DCHECK(imp.y.size() == n && imp.weight.size() == n && imp.theta.size() == n);
    IMPULSE_DCHECK(imp.scale.empty() || imp.scale.size() == n);
    p.px.resize(n), p.py.resize(n), p.w.resize(n), p.c.resize(n), p.s.resize(n);
    const double inv = 1.0 / view.scale;
    const double o = k.params().orientation;
    bool finite = true;
    for (size_t i = 0; i < n; ++i) {
        // Pixel coordinates with pixel i's centre at i; rounded to float once, here, so every
        // tile sees the same values.
        p.px[i] = static_cast<float>((imp.x[i] - view.x0) * inv - 0.5);
        p.py[i] = static_cast<float>((imp.y[i] - view.y0) * inv - 0.5);
        p.w[i] = imp.weight[i];
        const double t = o + static_cast<double>(imp.theta[i]);
        p.c[i] = static_cast<float>(std::cos(t));
        p.s[i] = static_cast<float>(std::sin(t));
        // A NaN or an infinity anywhere makes the sum NaN: one test per impulse at the API
        // boundary, a branch that is never taken on good input.
        finite &= std::isfinite(double(p.px[i]) + double(p.py[i]) + double(p.w[i]) + double(p.c[i]));
    }
    if (!finite) refuse_nonfinite(p, imp, api);
    return p;
}

// ---------------------------------------------------------------------------------------------
// Scale classes (docs/scenes.md "Kernel scale fields"; Lewis 1986 §3.1: "the kernel can be
// varied as a function of the position").
//
// An impulse of scale s draws g_s(x) = h(x / s) / s: the kernel s times larger with amplitude
// 1/s, so int g_s^2 = int h^2 (a change of variables x = s y) and the field's variance stays
// lambda E[a^2] int h^2 wherever s is, while its local spectrum lambda E[a^2] s^2 |H(s k)|^2
// moves to frequencies 1/s times the kernel's. The inner loops keep one kernel per call, so s is
// quantised into classes s_k = 2^(k/8), 1/8 octave apart, and the impulse is drawn as
//     c(f) [(1 - f) g_{s_k} + f g_{s_k+1}],   f = (s - s_k) / (s_k+1 - s_k) in [0, 1),
// both parts with the impulse's own amplitude. Its energy is
//     int (c ((1 - f) g_k + f g_k+1))^2 = c^2 [(1 - f)^2 + f^2 + 2 f (1 - f) rho] int h^2,
// with rho = int g_k g_k+1 / int h^2 = int h(y) h(y / r) dy / (r int h^2), r = s_k+1 / s_k =
// 2^(1/8) (substitute x = s_k y): the same for every k, one number per kernel
// (Kernel::scale_class_overlap). So c(f) = 1 / sqrt((1 - f)^2 + f^2 + 2 f (1 - f) rho) keeps
// int h^2 exactly, and the variance of the closed form holds at any s, not only at the classes.

/// 2^(j/8), j = 0 .. 8 (the mantissas of the class scales).
constexpr std::array<double, 9> kClassMantissa = {
    1.0, 1.0905077326652577, 1.189207115002721, 1.2968395546510096, 1.4142135623730951,
    1.5422108254079407, 1.681792830507429, 1.8340080864093424, 2.0};
constexpr int kClassesPerOctave = 8;
constexpr int kFirstClass = -4 * kClassesPerOctave;  // 2^-4 = kMinKernelScale
constexpr int kClassCount = 8 * kClassesPerOctave + 2;  // up to 2^4 and the class above it

/// The classes bracketing scale s > 0: s_k <= s < s_k+1. Exact arithmetic (frexp, ldexp, a
/// comparison table) and one division: the same bits on every machine.
struct ClassSplit {
    int k = 0;         ///< s_k = 2^(k/8)
    double f = 0.0;    ///< weight of class k + 1
    double s0 = 1.0, s1 = 1.0;
};
ClassSplit split_scale(double s) {
    int e = 0;
    const double m = 2.0 * std::frexp(s, &e);  // s = m 2^(e-1), m in [1, 2)
    e -= 1;
    int j = kClassesPerOctave - 1;
    while (kClassMantissa[j] > m) --j;
    ClassSplit c;
    c.k = kClassesPerOctave * e + j;
    c.s0 = std::ldexp(kClassMantissa[j], e);
    c.s1 = std::ldexp(kClassMantissa[j + 1], e);
    c.f = (s - c.s0) / (c.s1 - c.s0);
    return c;
}

/// s_k = 2^(k/8), exactly as split_scale computes it.
double class_scale(int k) {
    const int j = ((k % kClassesPerOctave) + kClassesPerOctave) % kClassesPerOctave;
    return std::ldexp(kClassMantissa[j], (k - j) / kClassesPerOctave);
}

/// Throws ValueError naming the first impulse whose scale is outside [kMinKernelScale,
/// kMaxKernelScale] (or not finite), or a scale array of another length than the impulses.
void check_scales(const sim::Impulses& imp, const char* api) {
    if (imp.scale.size() != imp.size())
        throw ValueError(std::string(api) + ": " + std::to_string(imp.scale.size()) +
                         " scales for " + std::to_string(imp.size()) +
                         " impulses: expected one per impulse or none");
    for (size_t i = 0; i < imp.size(); ++i) {
        const float v = imp.scale[i];
        if (v >= kMinKernelScale && v <= kMaxKernelScale) continue;  // false for NaN
        std::ostringstream m;
        m << api << ": impulse " << i << ": scale = " << v << ": expected a kernel scale in ["
          << kMinKernelScale << ", " << kMaxKernelScale << "]";
        throw ValueError(m.str());
    }
}

/// One kernel scale in the loops' form and the impulse parts drawn with it.
struct LoopClass {
    LoopKernel kernel;
    Prepared impulses;
};

/// The impulses grouped into scale classes, ascending; without scales, one class: the kernel
/// and the impulses as they are (the unscaled path, unchanged).
std::vector<LoopClass> loop_classes(const kernels::Kernel& k, const sim::Impulses& imp,
                                    const View& view, const char* api) {
    Prepared all = prepare(k, imp, view, api);  // names the first impulse that is not finite
    if (imp.scale.empty()) return {LoopClass{loop_kernel(k, view), std::move(all)}};
    std::vector<LoopClass> classes;
    for (const ScaleClass& c : split_scale_classes(k, imp, api))
        classes.push_back({loop_kernel(k, view, c.scale), prepare(k, c.impulses, view, api)});
    return classes;
}

void eval_tile(const LoopKernel& k, const LoopImpulses& p, const uint32_t* idx, size_t n, int tx0,
               int ty0, int tw, int th, float* acc, const EvalOptions& o) {
    if (o.use_avx2 && o.use_avx512 && numeric::cpu_has_avx512())
        detail::eval_tile_avx512(k, p, idx, n, tx0, ty0, tw, th, acc);
    else if (o.use_avx2 && numeric::cpu_has_avx2_fma())
        detail::eval_tile_avx2(k, p, idx, n, tx0, ty0, tw, th, acc);
    else
        detail::eval_tile_base(k, p, idx, n, tx0, ty0, tw, th, acc);
}

/// Indices of the impulses whose support box meets pixel rect [x0,x1) x [y0,y1), in order.
void select(const Prepared& p, float r, int x0, int y0, int x1, int y1, std::vector<uint32_t>& out) {
    out.clear();
    for (size_t i = 0; i < p.px.size(); ++i) {
        if (p.px[i] + r + 1.0f < x0 || p.px[i] - r - 1.0f > x1 - 1) continue;
        if (p.py[i] + r + 1.0f < y0 || p.py[i] - r - 1.0f > y1 - 1) continue;
        out.push_back(static_cast<uint32_t>(i));
    }
}

/// A class's impulses binned into square tiles of T pixels (counting sort: each tile's list
/// keeps the canonical order); tile t's impulses are bins[count[t] .. count[t + 1]).
struct TileBins {
    std::vector<uint32_t> count, bins;
};

TileBins bin_tiles(const Prepared& prep, float r, const View& view, int T, int ntx, int nty) {
    TileBins tb;
    tb.count.assign(size_t(ntx) * nty + 1, 0);
    auto tile_range = [&](size_t i, int& a0, int& a1, int& b0, int& b1) {
        a0 = std::clamp(static_cast<int>(std::floor((prep.px[i] - r - 1.0f) / T)), 0, ntx - 1);
        a1 = std::clamp(static_cast<int>(std::floor((prep.px[i] + r + 1.0f) / T)), 0, ntx - 1);
        b0 = std::clamp(static_cast<int>(std::floor((prep.py[i] - r - 1.0f) / T)), 0, nty - 1);
        b1 = std::clamp(static_cast<int>(std::floor((prep.py[i] + r + 1.0f) / T)), 0, nty - 1);
        const bool outside = prep.px[i] + r + 1.0f < 0 || prep.py[i] + r + 1.0f < 0 ||
                             prep.px[i] - r - 1.0f > view.width ||
                             prep.py[i] - r - 1.0f > view.height;
        return !outside;
    };
    for (size_t i = 0; i < prep.px.size(); ++i) {
        int a0, a1, b0, b1;
        if (!tile_range(i, a0, a1, b0, b1)) continue;
        for (int b = b0; b <= b1; ++b)
            for (int a = a0; a <= a1; ++a) ++tb.count[size_t(b) * ntx + a + 1];
    }
    for (size_t t = 1; t < tb.count.size(); ++t) tb.count[t] += tb.count[t - 1];
    tb.bins.resize(tb.count.back());
    std::vector<uint32_t> fill(tb.count.begin(), tb.count.end() - 1);
    for (size_t i = 0; i < prep.px.size(); ++i) {
        int a0, a1, b0, b1;
        if (!tile_range(i, a0, a1, b0, b1)) continue;
        for (int b = b0; b <= b1; ++b)
            for (int a = a0; a <= a1; ++a) tb.bins[fill[size_t(b) * ntx + a]++] = uint32_t(i);
    }
    return tb;
}

}  // namespace

std::vector<ScaleClass> split_scale_classes(const kernels::Kernel& kernel,
                                            const sim::Impulses& imp, const char* api) {
    check_scales(imp, api);
    const double rho = kernel.scale_class_overlap();
    std::array<sim::Impulses, kClassCount> parts;
    auto append = [&](sim::Impulses& to, size_t i, double w) {
        to.x.push_back(imp.x[i]), to.y.push_back(imp.y[i]), to.theta.push_back(imp.theta[i]);
        to.weight.push_back(static_cast<float>(w));
    };
    for (size_t i = 0; i < imp.size(); ++i) {
        const ClassSplit c = split_scale(imp.scale[i]);
        const double f = c.f;
        const double norm = 1.0 / std::sqrt((1 - f) * (1 - f) + f * f + 2 * f * (1 - f) * rho);
        const double w = imp.weight[i] * norm;
        const size_t slot = static_cast<size_t>(c.k - kFirstClass);
        append(parts[slot], i, w * (1 - f) / c.s0);
        if (f > 0.0) append(parts[slot + 1], i, w * f / c.s1);
    }
    std::vector<ScaleClass> classes;
    for (int slot = 0; slot < kClassCount; ++slot)
        if (!parts[slot].x.empty())
            classes.push_back({class_scale(slot + kFirstClass), std::move(parts[slot])});
    return classes;
}

double scale_class_at_least(double s) {
    const ClassSplit c = split_scale(s);
    return c.f > 0.0 ? c.s1 : c.s0;
}

kernels::KernelParams scaled_kernel(const kernels::KernelParams& p, double s) {
    kernels::KernelParams q = p;
    q.radius = p.radius * s, q.sigma = p.sigma * s;
    q.frequency = p.frequency / s, q.bandwidth = p.bandwidth / s;
    return q;
}

void accumulate(const kernels::Kernel& kernel, const sim::Impulses& impulses, const View& view,
                Frame& out, const EvalOptions& options) {
    if (out.width != view.width || out.height != view.height) out.resize(view.width, view.height);
    const std::vector<LoopClass> classes =
        loop_classes(kernel, impulses, view, "render::accumulate");
    const int T = std::max(8, options.tile_size);
    const int ntx = (view.width + T - 1) / T, nty = (view.height + T - 1) / T;
    std::vector<TileBins> bins;
    for (const LoopClass& c : classes)
        bins.push_back(bin_tiles(c.impulses, c.kernel.radius_px, view, T, ntx, nty));

    // Each pixel sums the classes in ascending scale, each class's parts in canonical order:
    // an order fixed by the impulses alone, whatever the threads or tiles.
    auto do_tile = [&](int t) {
        const int a = t % ntx, b = t / ntx;
        const int x0 = a * T, y0 = b * T;
        const int tw = std::min(T, view.width - x0), th = std::min(T, view.height - y0);
        const int stride = tw + 2 * detail::kPad;
        std::vector<float> acc(size_t(stride) * th, 0.0f);
        for (size_t c = 0; c < classes.size(); ++c) {
            const TileBins& tb = bins[c];
            eval_tile(classes[c].kernel, classes[c].impulses.view(), tb.bins.data() + tb.count[t],
                      tb.count[t + 1] - tb.count[t], x0, y0, tw, th, acc.data(), options);
        }
        for (int y = 0; y < th; ++y) {
            float* dst = out.data.data() + size_t(y0 + y) * view.width + x0;
            const float* src = acc.data() + size_t(y) * stride + detail::kPad;
            for (int x = 0; x < tw; ++x) dst[x] += src[x];
        }
    };
    const int ntiles = ntx * nty;
    if (options.parallel)
        tbb::parallel_for(0, ntiles, do_tile);
    else
        for (int t = 0; t < ntiles; ++t) do_tile(t);
}

void accumulate_region(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                       const View& view, int x0, int y0, int w, int h, float* tile,
                       const EvalOptions& options) {
    const std::vector<LoopClass> classes =
        loop_classes(kernel, impulses, view, "render::accumulate_region");
    const int stride = w + 2 * detail::kPad;
    std::vector<float> acc(size_t(stride) * h, 0.0f);
    std::vector<uint32_t> idx;
    for (const LoopClass& c : classes) {
        select(c.impulses, c.kernel.radius_px, x0, y0, x0 + w, y0 + h, idx);
        eval_tile(c.kernel, c.impulses.view(), idx.data(), idx.size(), x0, y0, w, h, acc.data(),
                  options);
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) tile[size_t(y) * w + x] += acc[size_t(y) * stride + detail::kPad + x];
}

void accumulate_naive(const kernels::Kernel& kernel, const sim::ProcessConfig& config,
                      const View& view, Frame& out) {
    if (out.width != view.width || out.height != view.height) out.resize(view.width, view.height);
    const double C = config.cell_size;
    tbb::parallel_for(0, view.height, [&](int j) {
        sim::CellImpulses cell;
        for (int i = 0; i < view.width; ++i) {
            const double x = view.x0 + (i + 0.5) * view.scale;
            const double y = view.y0 + (j + 0.5) * view.scale;
            const int64_t cx = static_cast<int64_t>(std::floor(x / C));
            const int64_t cy = static_cast<int64_t>(std::floor(y / C));
            double sum = 0.0;
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx) {
                    sim::cell_impulses(config, cx + dx, cy + dy, 0, cell);
                    for (size_t k = 0; k < cell.x.size(); ++k) {
                        const double th = config.orientation == sim::OrientationMode::Random
                                              ? cell.theta0[k] : 0.0;
                        sum += cell.amplitude[k] * kernel.evaluate(x - cell.x[k], y - cell.y[k], th);
                    }
                }
            out.data[size_t(j) * view.width + i] += static_cast<float>(sum);
        }
    });
}

}  // namespace impulse::render
