// SPDX-License-Identifier: Apache-2.0
// Flows: optional divergence and vorticity outputs never change the velocity; the curl-noise
// inner loop gives the same bits in its baseline and AVX2 builds; the curl-noise velocity is
// divergence-free and its vorticity output is the curl of the velocity (finite differences).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "sim/detail/curl.h"
#include "sim/sim.h"
#include "numeric/errors.h"

namespace {

namespace numeric = impulse::numeric;
namespace sim = impulse::sim;

struct Named {
    std::string name;
    std::shared_ptr<sim::Flow> flow;
    bool divergence_free;
};

std::vector<Named> every_flow() {
    sim::VectorGrid g;
    g.width = 9, g.height = 7, g.spacing = 16.0, g.origin_x = -20.0, g.origin_y = 10.0;
    std::mt19937 rng(5);
    std::normal_distribution<float> n(0.0f, 3.0f);
    for (int i = 0; i < g.width * g.height; ++i) g.vx.push_back(n(rng)), g.vy.push_back(n(rng));
    std::vector<Named> out;
    out.push_back({"uniform", sim::make_uniform_flow(3.0, -2.0), true});
    out.push_back({"shear", sim::make_shear_flow(0.3, 10.0, 20.0, 0.4), true});
    out.push_back({"vortex", sim::make_vortex_flow(sim::VortexModel::LambOseen, 5.0, 8.0, 2000.0, 25.0), true});
    out.push_back({"rankine", sim::make_vortex_flow(sim::VortexModel::Rankine, 5.0, 8.0, 2000.0, 25.0), true});
    out.push_back({"source", sim::make_source_flow(0.0, 0.0, 0.2, 40.0), false});
    out.push_back({"curl", sim::make_curl_noise_flow(9, 64.0, 12.0, std::nullopt), true});
    out.push_back({"grid", sim::make_grid_flow(g, 1.5), false});
    auto sum = std::make_shared<sim::FlowSum>();
    sum->push(sim::make_uniform_flow(3.0, -2.0));
    sum->push(sim::make_curl_noise_flow(9, 64.0, 12.0, std::nullopt));
    out.push_back({"uniform + curl", sum, true});
    auto mixed = std::make_shared<sim::FlowSum>();
    mixed->push(sim::make_curl_noise_flow(9, 64.0, 12.0, std::nullopt));
    mixed->push(sim::make_source_flow(0.0, 0.0, 0.2, 40.0));
    out.push_back({"curl + source", mixed, false});
    return out;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

TEST_CASE("flows: div and curl are optional and never change v", "[sim][flows]") {
    constexpr size_t n = 500;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-150.0, 150.0);
    std::vector<double> x(n), y(n);
    for (size_t i = 0; i < n; ++i) x[i] = u(rng), y[i] = u(rng);
    for (const auto& f : every_flow()) {
        DYNAMIC_SECTION(f.name) {
            f.flow->prepare({-100.0, -100.0, 100.0, 100.0});  // some points outside the cache
            std::vector<double> vx(n, 0.0), vy(n, 0.0), div(n, 0.0), curl(n, 0.0);
            f.flow->add(0.5, n, x.data(), y.data(), vx.data(), vy.data(), div.data(), curl.data());
            std::vector<double> vx2(n, 0.0), vy2(n, 0.0);
            f.flow->add(0.5, n, x.data(), y.data(), vx2.data(), vy2.data(), nullptr, nullptr);
            CHECK(same_bits(vx, vx2));
            CHECK(same_bits(vy, vy2));
            // One output alone is the same as with the other.
            std::vector<double> div3(n, 0.0), curl4(n, 0.0);
            std::vector<double> vx3(n, 0.0), vy3(n, 0.0);
            f.flow->add(0.5, n, x.data(), y.data(), vx3.data(), vy3.data(), div3.data(), nullptr);
            CHECK(same_bits(div, div3));
            std::fill(vx3.begin(), vx3.end(), 0.0), std::fill(vy3.begin(), vy3.end(), 0.0);
            f.flow->add(0.5, n, x.data(), y.data(), vx3.data(), vy3.data(), nullptr, curl4.data());
            CHECK(same_bits(curl, curl4));
            // divergence_free() is what the simulator trusts to skip ln J: it must be exact.
            CHECK(f.flow->divergence_free() == f.divergence_free);
            const double max_div = std::abs(*std::max_element(
                div.begin(), div.end(), [](double a, double b) { return std::abs(a) < std::abs(b); }));
            if (f.divergence_free)
                CHECK(max_div == 0.0);
            else
                CHECK(max_div > 1e-3);
        }
    }
}

namespace {

/// Node values for points whose stencil leaves the test lattice: a smooth formula, so both
/// builds read the same numbers.
void formula_nodes(const void*, int64_t i0, int64_t j0, double out[16]) {
    for (int b = 0; b < 4; ++b)
        for (int a = 0; a < 4; ++a)
            out[4 * b + a] = std::sin(0.37 * double(i0 + a)) * std::cos(0.23 * double(j0 + b));
}

}  // namespace

TEST_CASE("curl noise: the baseline and AVX2 inner loops give the same bits", "[sim][flows][determinism]") {
    if (!numeric::cpu_has_avx2()) {
        WARN("no AVX2 on this CPU: only the baseline loop runs here");
        return;
    }
    sim::detail::CurlLattice L;
    L.i0 = -7, L.j0 = 3, L.width = 41, L.height = 29;
    L.inv_hx = 1.0 / 37.5, L.inv_hy = 1.0 / 29.0;
    std::vector<double> nodes(static_cast<size_t>(L.width * L.height));
    std::mt19937_64 rng(3);
    std::normal_distribution<double> normal(0.0, 1.0);
    for (double& v : nodes) v = normal(rng);
    L.nodes = nodes.data();
    L.fetch = &formula_nodes;
    // Points over the cached nodes and beyond them on every side (the fetch path).
    constexpr size_t n = 4000;
    std::uniform_real_distribution<double> ux((L.i0 - 6) / L.inv_hx, (L.i0 + L.width + 6) / L.inv_hx);
    std::uniform_real_distribution<double> uy((L.j0 - 6) / L.inv_hy, (L.j0 + L.height + 6) / L.inv_hy);
    std::vector<double> x(n), y(n);
    for (size_t i = 0; i < n; ++i) x[i] = ux(rng), y[i] = uy(rng);
    std::vector<double> vx[2], vy[2], curl[2];
    for (int k = 0; k < 2; ++k) {
        vx[k].assign(n, 1.0), vy[k].assign(n, -1.0), curl[k].assign(n, 0.5);
        (k ? sim::detail::curl_add_avx2 : sim::detail::curl_add_base)(
            L, 1.7, n, x.data(), y.data(), vx[k].data(), vy[k].data(), curl[k].data());
    }
    CHECK(same_bits(vx[0], vx[1]));
    CHECK(same_bits(vy[0], vy[1]));
    CHECK(same_bits(curl[0], curl[1]));
    // Something was computed (the outputs moved away from their start values).
    size_t moved = 0;
    for (size_t i = 0; i < n; ++i) moved += vx[0][i] != 1.0 && vy[0][i] != -1.0 && curl[0][i] != 0.5;
    CHECK(moved > n * 9 / 10);
}

TEST_CASE("curl noise: scales outside [1e-3, 1e9] and lattices over 1e8 nodes are refused",
          "[sim][flows][errors]") {
    // A scale of 1 over a perspective view's region of 1e4 units needs (1e4 / 0.125)^2 = 6.4e9
    // nodes: it failed with std::bad_alloc; 1e-300 overflowed the node indices.
    CHECK_THROWS_WITH(sim::make_curl_noise_flow(1, 1e-300, 16.0, std::nullopt),
                      Catch::Contains("scale = 1e-300: expected a length in [0.001, 1e+09]"));
    CHECK_THROWS_AS(sim::make_curl_noise_flow(1, 1e300, 16.0, std::nullopt), impulse::ValueError);
    auto flow = sim::make_curl_noise_flow(1, 1.0, 16.0, std::nullopt);
    CHECK_THROWS_WITH(flow->prepare({0.0, 0.0, 1e4, 1e4}),
                      Catch::Contains("needs a potential lattice of") &&
                          Catch::Contains("over the limit of 1e+08 (raise the scale)"));
    CHECK_NOTHROW(flow->prepare({0.0, 0.0, 100.0, 100.0}));  // 800 x 800 nodes
}

TEST_CASE("curl noise: v is divergence-free and the curl output is its vorticity", "[sim][flows]") {
    // Inside one lattice cell psi is a bicubic polynomial, so v = (d psi/dy, -d psi/dx) is a
    // polynomial of degree <= 3 in each coordinate and central differences with step d have
    // truncation error d^2/6 |d^3 v|. Here d = spacing/1000 = 0.0375 units; |d^3 v| is at most
    // about speed * 8^3 / scale^3 ~ 3e-4 per unit^3, so truncation ~ 1e-7; rounding of v (|v| <
    // 100, a few ulps) divided by 2d adds ~ 1e-12. A tolerance of 1e-5 is 100 times that, while
    // the vorticity itself is ~ 0.2 rms (checked below, so the comparison is not of zeros).
    const double scale = 300.0, spacing = scale / 8.0, d = spacing / 1000.0;
    auto flow = sim::make_curl_noise_flow(21, scale, 16.0, std::nullopt);
    flow->prepare({-600.0, -600.0, 600.0, 600.0});
    std::mt19937_64 rng(17);
    std::uniform_int_distribution<int> cell(-14, 13);
    std::uniform_real_distribution<double> frac(0.1, 0.9);  // stencils stay inside one cell
    double worst_div = 0.0, worst_curl = 0.0, curl_sq = 0.0;
    constexpr int kPoints = 400;
    for (int k = 0; k < kPoints; ++k) {
        const double px = (cell(rng) + frac(rng)) * spacing, py = (cell(rng) + frac(rng)) * spacing;
        const double xs[5] = {px, px + d, px - d, px, px};
        const double ys[5] = {py, py, py, py + d, py - d};
        double vx[5] = {}, vy[5] = {}, curl[5] = {};
        flow->add(0.0, 5, xs, ys, vx, vy, nullptr, curl);
        const double dvx_dx = (vx[1] - vx[2]) / (2 * d), dvy_dy = (vy[3] - vy[4]) / (2 * d);
        const double dvy_dx = (vy[1] - vy[2]) / (2 * d), dvx_dy = (vx[3] - vx[4]) / (2 * d);
        worst_div = std::max(worst_div, std::abs(dvx_dx + dvy_dy));
        worst_curl = std::max(worst_curl, std::abs((dvy_dx - dvx_dy) - curl[0]));
        curl_sq += curl[0] * curl[0];
    }
    INFO("max |div| " << worst_div << ", max |curl - fd curl| " << worst_curl << ", rms curl "
                      << std::sqrt(curl_sq / kPoints));
    CHECK(worst_div < 1e-5);
    CHECK(worst_curl < 1e-5);
    CHECK(std::sqrt(curl_sq / kPoints) > 0.05);
}
