// SPDX-License-Identifier: Apache-2.0
// Tiled sparse convolution: impulses are binned into square tiles in their canonical order,
// tiles are evaluated in parallel, each pixel written by one task (design.md §3 "Evaluation").

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "numeric/cpu.h"
#include "render/eval_detail.h"
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

LoopKernel loop_kernel(const kernels::Kernel& k, const View& view) {
    const auto& p = k.params();
    LoopKernel lk;
    lk.radius_px = static_cast<float>(p.radius / view.scale);
    lk.inv_r2 = 1.0f / (lk.radius_px * lk.radius_px);
    lk.aspect2 = static_cast<float>(p.aspect * p.aspect);
    lk.carrier = k.has_carrier();
    lk.freq_cpp = static_cast<float>(p.frequency * view.scale);
    lk.phase_cycles = static_cast<float>(p.phase / (2.0 * std::numbers::pi));
    lk.general = lk.carrier || p.aspect != 1.0;
    // Isotropic Gaussian envelopes (gaussian; gabor with aspect 1) take the separable path.
    if (p.aspect == 1.0 && (p.type == kernels::KernelType::Gaussian ||
                            p.type == kernels::KernelType::Gabor)) {
        lk.separable = true;
        const double s = view.scale;  // texture units per pixel
        lk.gauss_g = static_cast<float>(
            p.type == kernels::KernelType::Gaussian
                ? s * s / (2.0 * p.sigma * p.sigma)
                : std::numbers::pi * k.gabor_a() * k.gabor_a() * s * s);
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

}  // namespace

void accumulate(const kernels::Kernel& kernel, const sim::Impulses& impulses, const View& view,
                Frame& out, const EvalOptions& options) {
    if (out.width != view.width || out.height != view.height) out.resize(view.width, view.height);
    const LoopKernel lk = loop_kernel(kernel, view);
    const Prepared prep = prepare(kernel, impulses, view, "render::accumulate");
    const int T = std::max(8, options.tile_size);
    const int ntx = (view.width + T - 1) / T, nty = (view.height + T - 1) / T;
    const float r = lk.radius_px;

    // Bin into tiles (counting sort keeps each tile's list in canonical order).
    std::vector<uint32_t> count(size_t(ntx) * nty + 1, 0);
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
            for (int a = a0; a <= a1; ++a) ++count[size_t(b) * ntx + a + 1];
    }
    for (size_t t = 1; t < count.size(); ++t) count[t] += count[t - 1];
    std::vector<uint32_t> bins(count.back());
    std::vector<uint32_t> fill(count.begin(), count.end() - 1);
    for (size_t i = 0; i < prep.px.size(); ++i) {
        int a0, a1, b0, b1;
        if (!tile_range(i, a0, a1, b0, b1)) continue;
        for (int b = b0; b <= b1; ++b)
            for (int a = a0; a <= a1; ++a) bins[fill[size_t(b) * ntx + a]++] = uint32_t(i);
    }

    const LoopImpulses li = prep.view();
    auto do_tile = [&](int t) {
        const int a = t % ntx, b = t / ntx;
        const int x0 = a * T, y0 = b * T;
        const int tw = std::min(T, view.width - x0), th = std::min(T, view.height - y0);
        const int stride = tw + 2 * detail::kPad;
        std::vector<float> acc(size_t(stride) * th, 0.0f);
        eval_tile(lk, li, bins.data() + count[t], count[t + 1] - count[t], x0, y0, tw, th,
                  acc.data(), options);
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
    const LoopKernel lk = loop_kernel(kernel, view);
    const Prepared prep = prepare(kernel, impulses, view, "render::accumulate_region");
    std::vector<uint32_t> idx;
    select(prep, lk.radius_px, x0, y0, x0 + w, y0 + h, idx);
    const int stride = w + 2 * detail::kPad;
    std::vector<float> acc(size_t(stride) * h, 0.0f);
    eval_tile(lk, prep.view(), idx.data(), idx.size(), x0, y0, w, h, acc.data(), options);
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
