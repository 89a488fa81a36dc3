// SPDX-License-Identifier: Apache-2.0
// Exact df/dx, df/dy of an orthographic frame (render/gradient.h): impulses binned into square
// tiles in canonical order, each tile's pixels summing their impulses' kernel gradients in
// double (docs/channels.md "Derivatives").

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "render/render.h"

namespace impulse::render {
namespace {

/// One impulse as the tiles see it: texture position, weight and its rotation.
struct Placed {
    double x, y, w, c, s;
};

std::vector<Placed> place(const kernels::Kernel& k, const sim::Impulses& imp) {
    std::vector<Placed> p(imp.size());
    for (size_t i = 0; i < imp.size(); ++i) {
        const double t = k.params().orientation + double(imp.theta[i]);
        p[i] = {imp.x[i], imp.y[i], double(imp.weight[i]), std::cos(t), std::sin(t)};
        if (!std::isfinite(p[i].x + p[i].y + p[i].w + p[i].c)) {
            std::ostringstream s;
            s << "render::accumulate_gradient: impulse " << i << ": x = " << imp.x[i]
              << ", y = " << imp.y[i] << ", theta = " << imp.theta[i] << ", weight = "
              << imp.weight[i] << ": expected finite impulse coordinates, orientations and weights";
            throw ValueError(s.str());
        }
    }
    return p;
}

/// The indices of the impulses reaching each tile, in canonical order.
std::vector<std::vector<uint32_t>> bin(const std::vector<Placed>& p, double radius,
                                       const View& view, int tile, int tx, int ty) {
    std::vector<std::vector<uint32_t>> bins(size_t(tx) * ty);
    const double inv = 1.0 / view.scale, r = radius * inv;
    for (size_t i = 0; i < p.size(); ++i) {
        const double px = (p[i].x - view.x0) * inv - 0.5, py = (p[i].y - view.y0) * inv - 0.5;
        const double lo_x = std::max(0.0, std::floor(px - r)), hi_x = std::min(view.width - 1.0, std::ceil(px + r));
        const double lo_y = std::max(0.0, std::floor(py - r)), hi_y = std::min(view.height - 1.0, std::ceil(py + r));
        if (lo_x > hi_x || lo_y > hi_y) continue;
        for (int j = int(lo_y) / tile; j <= int(hi_y) / tile; ++j)
            for (int i2 = int(lo_x) / tile; i2 <= int(hi_x) / tile; ++i2)
                bins[size_t(j) * tx + i2].push_back(uint32_t(i));
    }
    return bins;
}

/// The pixels of tile [x0, x1) x [y0, y1) within the disk of radius R of impulse q: rows
/// [j0, j1), columns [i0, i1) (empty when j0 >= j1).
struct Reach {
    int i0, i1, j0, j1;
};
Reach reach(const Placed& q, double R, const View& v, int x0, int y0, int x1, int y1) {
    const double px = (q.x - v.x0) / v.scale - 0.5, py = (q.y - v.y0) / v.scale - 0.5, r = R / v.scale;
    return {std::max(x0, int(std::floor(px - r))), std::min(x1, int(std::ceil(px + r)) + 1),
            std::max(y0, int(std::floor(py - r))), std::min(y1, int(std::ceil(py + r)) + 1)};
}

/// An isotropic Gaussian's gradient is separable, -(x, y) / sigma^2 e^{-x^2 / 2 sigma^2}
/// e^{-y^2 / 2 sigma^2}: one exponential per column and row of the impulse's reach instead of one
/// per pixel (the value's evaluator splits it the same way; render/evaluate.cpp).
void add_gaussian(const kernels::Kernel& k, const Placed& q, const Reach& a, const View& v,
                  int x0, int y0, int tile, double* gx, double* gy) {
    const double R = k.radius(), g = 0.5 / (k.params().sigma * k.params().sigma);
    thread_local std::vector<double> ox, ex;
    ox.resize(size_t(a.i1 - a.i0)), ex.resize(ox.size());
    for (int i = a.i0; i < a.i1; ++i) {
        ox[size_t(i - a.i0)] = v.x0 + (i + 0.5) * v.scale - q.x;
        ex[size_t(i - a.i0)] = std::exp(-g * ox[size_t(i - a.i0)] * ox[size_t(i - a.i0)]);
    }
    for (int j = a.j0; j < a.j1; ++j) {
        const double oy = v.y0 + (j + 0.5) * v.scale - q.y, ey = q.w * std::exp(-g * oy * oy);
        double* rx = gx + size_t(j - y0) * tile;
        double* ry = gy + size_t(j - y0) * tile;
        for (int i = a.i0; i < a.i1; ++i) {
            const double o = ox[size_t(i - a.i0)];
            if (o * o + oy * oy >= R * R) continue;  // the support is the disk
            const double e = -2.0 * g * ex[size_t(i - a.i0)] * ey;
            rx[i - x0] += e * o, ry[i - x0] += e * oy;
        }
    }
}

/// Any kernel: its gradient in its own frame at each pixel of the reach, turned back.
void add_general(const kernels::Kernel& k, const Placed& q, const Reach& a, const View& v,
                 int x0, int y0, int tile, double* gx, double* gy) {
    const double R2 = k.radius() * k.radius();
    for (int j = a.j0; j < a.j1; ++j) {
        const double oy = v.y0 + (j + 0.5) * v.scale - q.y;
        double* rx = gx + size_t(j - y0) * tile;
        double* ry = gy + size_t(j - y0) * tile;
        for (int i = a.i0; i < a.i1; ++i) {
            const double ox = v.x0 + (i + 0.5) * v.scale - q.x;
            if (ox * ox + oy * oy >= R2) continue;
            const auto h = k.frame_value_gradient(q.c * ox + q.s * oy, -q.s * ox + q.c * oy);
            rx[i - x0] += q.w * (h[1] * q.c - h[2] * q.s);
            ry[i - x0] += q.w * (h[1] * q.s + h[2] * q.c);
        }
    }
}

/// Adds one kernel's impulses to dx, dy (per pixel: the texture gradient times view.scale).
/// Each tile sums its impulses in canonical order into double accumulators, so every pixel
/// adds its terms in the same order whatever the threads.
void add_kernel(const kernels::Kernel& k, const sim::Impulses& imp, const View& view, Frame& dx,
                Frame& dy, const EvalOptions& options) {
    const std::vector<Placed> p = place(k, imp);
    const int tile = std::max(8, options.tile_size);
    const int tx = (view.width + tile - 1) / tile, ty = (view.height + tile - 1) / tile;
    // An elliptical kernel reaches R along its orientation; the disk of radius R bounds it.
    const double R = k.radius();
    const auto bins = bin(p, R, view, tile, tx, ty);
    const auto& kp = k.params();
    const bool separable = kp.type == kernels::KernelType::Gaussian && kp.aspect == 1.0;
    auto run = [&](size_t b) {
        const int x0 = int(b % size_t(tx)) * tile, y0 = int(b / size_t(tx)) * tile;
        const int x1 = std::min(view.width, x0 + tile), y1 = std::min(view.height, y0 + tile);
        // Reused by each thread: a fresh pair of buffers per tile cost more in page faults
        // than the tile's arithmetic (bench/README.md "impulse_bench_channels").
        thread_local std::vector<double> gx, gy;
        gx.assign(size_t(tile) * tile, 0.0), gy.assign(gx.size(), 0.0);
        for (uint32_t id : bins[b]) {
            const Reach a = reach(p[id], R, view, x0, y0, x1, y1);
            if (a.i0 >= a.i1 || a.j0 >= a.j1) continue;
            if (separable)
                add_gaussian(k, p[id], a, view, x0, y0, tile, gx.data(), gy.data());
            else
                add_general(k, p[id], a, view, x0, y0, tile, gx.data(), gy.data());
        }
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const size_t o = size_t(y) * view.width + x, t = size_t(y - y0) * tile + (x - x0);
                dx.data[o] = static_cast<float>(dx.data[o] + gx[t] * view.scale);
                dy.data[o] = static_cast<float>(dy.data[o] + gy[t] * view.scale);
            }
    };
    if (options.parallel)
        tbb::parallel_for(size_t(0), bins.size(), run);
    else
        for (size_t b = 0; b < bins.size(); ++b) run(b);
}

}  // namespace

void accumulate_gradient(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                         const View& view, Frame& dx, Frame& dy, const EvalOptions& options) {
    for (Frame* f : {&dx, &dy})
        if (f->data.empty()) f->resize(view.width, view.height);
    if (dx.width != view.width || dx.height != view.height || dy.width != view.width ||
        dy.height != view.height)
        throw ValueError("render::accumulate_gradient: frames are not the view's size");
    if (impulses.scale.empty()) return add_kernel(kernel, impulses, view, dx, dy, options);
    // Scale classes as accumulate draws them: h(x / s_k) with the split weights (1/s_k in them).
    for (const ScaleClass& c : split_scale_classes(kernel, impulses, "render::accumulate_gradient"))
        add_kernel(kernels::Kernel(scaled_kernel(kernel.params(), c.scale)), c.impulses, view, dx,
                   dy, options);
}

}  // namespace impulse::render
