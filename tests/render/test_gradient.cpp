// SPDX-License-Identifier: Apache-2.0
// render::accumulate_gradient: a single impulse against its kernel's exact gradient, a field
// of impulses against central differences of render::accumulate's field on a fine lattice
// (tolerance from the kernel's third derivative, h^2 / 6), bit identity across threads and
// tiles (docs/channels.md "Derivatives").

#include <tbb/task_arena.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>

#include "kernels/kernels.h"
#include "render/render.h"
#include "sim/sim.h"

namespace {

using impulse::kernels::Kernel;
using impulse::kernels::KernelParams;
using impulse::kernels::KernelType;
using impulse::render::EvalOptions;
using impulse::render::Frame;
using impulse::render::View;

constexpr double kPi = std::numbers::pi;

impulse::sim::Impulses one_impulse(double x, double y, float w, float theta) {
    impulse::sim::Impulses imp;
    imp.x = {x}, imp.y = {y}, imp.weight = {w}, imp.theta = {theta};
    return imp;
}

}  // namespace

TEST_CASE("the derivative channels of a single impulse are its kernel's gradient",
          "[render][gradient]") {
    KernelParams p;
    SECTION("an elliptical Gabor kernel (the general path)") {
        p.type = KernelType::Gabor, p.radius = 20.0, p.frequency = 0.08, p.aspect = 1.7;
    }
    SECTION("an isotropic Gaussian (the separable path)") {
        p.type = KernelType::Gaussian, p.radius = 20.0, p.sigma = 6.0;
    }
    const Kernel k(p);
    const View view{90, 70, -13.3, 4.1, 0.5};  // half a texture unit per pixel
    const auto imp = one_impulse(9.7, 21.2, 1.3f, 0.6f);
    Frame dx, dy;
    impulse::render::accumulate_gradient(k, imp, view, dx, dy);
    double largest = 0.0;
    for (int y = 0; y < view.height; ++y)
        for (int x = 0; x < view.width; ++x) {
            const double tx = view.x0 + (x + 0.5) * view.scale, ty = view.y0 + (y + 0.5) * view.scale;
            const auto g = k.value_gradient(tx - imp.x[0], ty - imp.y[0], imp.theta[0]);
            // Per pixel: d/dpixel = scale d/dtexture. The sum of one term rounds to float once
            // (relative 2^-24 = 6e-8); the double arithmetic before it adds ~1e-15.
            const double w = imp.weight[0];
            const double ex = w * g[1] * view.scale, ey = w * g[2] * view.scale;
            CHECK(std::abs(dx.at(x, y) - ex) <= 6e-8 * std::abs(ex) + 1e-30);
            CHECK(std::abs(dy.at(x, y) - ey) <= 6e-8 * std::abs(ey) + 1e-30);
            largest = std::max(largest, std::abs(ex));
        }
    REQUIRE(largest > 0.01);  // the impulse is in the view
}

TEST_CASE("derivative channels match central differences of the value on a fine lattice",
          "[render][gradient]") {
    // A still cosine field (radius R = 8 texture units) on a lattice of h = 0.05 units per
    // pixel: (f(x + h) - f(x - h)) / 2h - f'(x) = h^2 / 6 f'''(xi) where f is smooth. Along any
    // line through one cosine bump |f'''| stays below 0.52 (pi / R)^3 (a dense scan of the
    // lines; 4 (pi / R)^3 taken). At the support's edge f'' jumps by J = pi^2 / (2 R^2) (h'' of
    // (1 + cos(pi r / R)) / 2 at r = R), where the central difference errs by up to J h / 4
    // instead. Each impulse adds its |w| times the larger; per pixel, times h. The value's float
    // rounding and envelope polynomial (1e-6 of e(0)) add 2e-6 sum |w| to the difference.
    KernelParams p;
    p.type = KernelType::Cosine, p.radius = 8.0;
    const Kernel k(p);
    impulse::sim::ProcessConfig c;
    c.seed = 77, c.cell_size = 8.0, c.intensity = 6.0 / (kPi * 64.0);
    c.amplitude = impulse::sim::Amplitude::Uniform;
    const View view{160, 120, 3.0, -2.0, 0.05};
    impulse::sim::LayerSimulator sim(c, nullptr, impulse::sim::Timing{}, p.radius);
    impulse::sim::Impulses imp;
    sim.impulses_at(0, view.box().expanded(p.radius), imp);
    REQUIRE(imp.size() > 3);
    Frame f, dx, dy;
    f.resize(view.width, view.height);
    impulse::render::accumulate(k, imp, view, f);
    impulse::render::accumulate_gradient(k, imp, view, dx, dy);
    const double h = view.scale;
    const double m3 = 4.0 * std::pow(kPi / p.radius, 3);  // per texture unit^3
    const double jump = kPi * kPi / (2.0 * p.radius * p.radius);
    const double per_weight = std::max(h * h / 6.0 * m3, jump * h / 4.0) * h + 2e-6;
    double worst = 0.0, largest_bound = 0.0, scale = 0.0;
    for (int y = 1; y + 1 < view.height; ++y)
        for (int x = 1; x + 1 < view.width; ++x) {
            // The impulses whose support reaches the pixel or its two neighbours.
            const double tx = view.x0 + (x + 0.5) * h, ty = view.y0 + (y + 0.5) * h;
            double sum_w = 0.0;
            for (size_t k2 = 0; k2 < imp.size(); ++k2)
                if (std::hypot(imp.x[k2] - tx, imp.y[k2] - ty) < p.radius + 2 * h)
                    sum_w += std::abs(imp.weight[k2]);
            const double bound = per_weight * sum_w;
            const double cx = (f.at(x + 1, y) - f.at(x - 1, y)) / 2.0;
            const double cy = (f.at(x, y + 1) - f.at(x, y - 1)) / 2.0;
            const double err = std::max(std::abs(cx - dx.at(x, y)), std::abs(cy - dy.at(x, y)));
            CHECK(err <= bound);
            worst = std::max(worst, err / bound);
            largest_bound = std::max(largest_bound, bound);
            scale = std::max(scale, std::abs(double(dx.at(x, y))));
        }
    INFO("worst error / bound " << worst << ", largest bound " << largest_bound
                                << ", largest derivative " << scale);
    CHECK(largest_bound < 0.1 * scale);  // tight enough to see a wrong derivative
}

TEST_CASE("derivative channels have the same bits for any threads and tiles",
          "[render][gradient][determinism]") {
    KernelParams p;
    p.type = KernelType::Gaussian, p.radius = 12.0, p.sigma = 4.0;
    const Kernel k(p);
    impulse::sim::ProcessConfig c;
    c.seed = 5, c.cell_size = 12.0, c.intensity = 10.0 / (kPi * 144.0);
    c.orientation = impulse::sim::OrientationMode::Random;
    const View view{200, 150, 0.0, 0.0, 1.0};
    impulse::sim::LayerSimulator sim(c, nullptr, impulse::sim::Timing{}, p.radius);
    impulse::sim::Impulses imp;
    sim.impulses_at(0, view.box().expanded(p.radius), imp);
    Frame ax, ay, bx, by;
    EvalOptions serial;
    serial.parallel = false, serial.tile_size = 16;
    impulse::render::accumulate_gradient(k, imp, view, ax, ay, serial);
    tbb::task_arena arena(2);
    arena.execute([&] { impulse::render::accumulate_gradient(k, imp, view, bx, by); });
    CHECK(std::memcmp(ax.data.data(), bx.data.data(), ax.data.size() * 4) == 0);
    CHECK(std::memcmp(ay.data.data(), by.data.data(), ay.data.size() * 4) == 0);
}
