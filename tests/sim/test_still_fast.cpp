// SPDX-License-Identifier: Apache-2.0
// The still-layer fast path of LayerSimulator::impulses_at against a plain reference built from
// the public per-cell API: the cells meeting the birth region in canonical order (rows, then
// cells), each cell's impulses from sim::cell_impulses in order, kept when the position lies in
// a box of the view expanded by the support radius; weight = amplitude, theta = theta0 for a
// random orientation (0 otherwise), a field's angle plus jitter (theta0 / pi - 1) for a field.
// Every value must match bit for bit. Also the batched (AVX2) Philox against Random123's.

#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <utility>
#include <vector>

#include "numeric/rng.h"
#include "sim/sim.h"

namespace {

using namespace impulse;

sim::Impulses reference(const sim::ProcessConfig& c, const numeric::Region& view, double radius,
                        double t_s) {
    // Periods below are whole multiples of the cell size, so the cells are cell_size wide.
    const double cell = c.cell_size;
    const numeric::Region keep = view.expanded(radius);
    const numeric::Box all = keep.bounds();
    sim::Impulses out;
    std::vector<float> th0;
    sim::CellImpulses ci;
    auto in_keep = [&](double x, double y) {
        return std::any_of(keep.boxes.begin(), keep.boxes.end(), [&](const numeric::Box& b) {
            return x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1;
        });
    };
    auto meets = [&](int64_t cx, int64_t cy) {
        return std::any_of(keep.boxes.begin(), keep.boxes.end(), [&](const numeric::Box& b) {
            return cx >= std::floor(b.x0 / cell) && cx <= std::floor(b.x1 / cell) &&
                   cy >= std::floor(b.y0 / cell) && cy <= std::floor(b.y1 / cell);
        });
    };
    for (auto cy = int64_t(std::floor(all.y0 / cell)); cy <= int64_t(std::floor(all.y1 / cell)); ++cy)
        for (auto cx = int64_t(std::floor(all.x0 / cell)); cx <= int64_t(std::floor(all.x1 / cell));
             ++cx) {
            if (!meets(cx, cy)) continue;
            sim::cell_impulses(c, cx, cy, 0, ci);
            for (size_t k = 0; k < ci.x.size(); ++k) {
                if (!in_keep(ci.x[k], ci.y[k])) continue;
                out.x.push_back(ci.x[k]);
                out.y.push_back(ci.y[k]);
                out.weight.push_back(ci.amplitude[k]);
                out.theta.push_back(c.orientation == sim::OrientationMode::Random ? ci.theta0[k]
                                                                                  : 0.0f);
                th0.push_back(ci.theta0[k]);
            }
        }
    if (c.orientation == sim::OrientationMode::Field) {
        c.orientation_field->angles(t_s, out.size(), out.x.data(), out.y.data(), out.theta.data());
        const double jitter = c.orientation_jitter.value(t_s);
        for (size_t j = 0; j < out.size(); ++j)
            out.theta[j] = static_cast<float>(out.theta[j] +
                                              jitter * (th0[j] * (1.0 / std::numbers::pi) - 1.0));
    }
    return out;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

void check_still(const sim::ProcessConfig& c, const numeric::Region& view, double radius) {
    const sim::Timing timing{24.0, 5};
    sim::LayerSimulator s(c, nullptr, timing, radius);
    sim::Impulses got;
    // A still layer's frames all hold the same impulses (frame 3 reuses the output's arrays);
    // the pieces go to any thread.
    for (const auto& [f, threads] : {std::pair<int64_t, int>{0, 1}, {3, 2}}) {
        const int64_t frame = f;  // clang 14 cannot capture a structured binding in a lambda
        tbb::task_arena(threads).execute([&] { s.impulses_at(frame, view, got); });
        const sim::Impulses want =
            reference(c, view, radius, static_cast<double>(timing.start_frame + frame) / timing.fps);
        INFO("frame " << frame << ", " << threads << " threads: " << got.size()
                      << " impulses, reference " << want.size());
        REQUIRE(want.size() > 0);
        CHECK(same_bits(got.x, want.x));
        CHECK(same_bits(got.y, want.y));
        CHECK(same_bits(got.weight, want.weight));
        CHECK(same_bits(got.theta, want.theta));
    }
}

numeric::Region wedge() {
    // Overlapping boxes, one of them across the origin (negative cells), and a disjoint one.
    numeric::Region r;
    r.boxes = {{-150.5, -40.0, 220.0, 30.0}, {-60.0, 10.0, 90.25, 160.0}, {400.0, -300.0, 470.0, -250.0}};
    return r;
}

}  // namespace

TEST_CASE("still fast path: plain layer, every amplitude and orientation", "[sim][still]") {
    for (const auto amp : {sim::Amplitude::Normal, sim::Amplitude::Uniform, sim::Amplitude::Sign,
                           sim::Amplitude::Exponential})
        for (const auto orient : {sim::OrientationMode::Fixed, sim::OrientationMode::Random,
                                  sim::OrientationMode::Flow, sim::OrientationMode::Vorticity}) {
            sim::ProcessConfig c;
            c.seed = 0x1234567890ull;
            c.layer = 3;
            c.intensity = 0.03;
            c.amplitude = amp;
            c.orientation = orient;
            INFO("amplitude " << int(amp) << ", orientation " << int(orient));
            check_still(c, wedge(), 12.0);
        }
}

TEST_CASE("still fast path: orientation field with and without jitter", "[sim][still]") {
    for (const double jitter : {0.0, 0.7}) {
        sim::ProcessConfig c;
        c.orientation = sim::OrientationMode::Field;
        c.orientation_field = sim::make_radial_orientation(10.0, -5.0);
        c.orientation_jitter = jitter;
        INFO("jitter " << jitter);
        check_still(c, wedge(), 8.0);
    }
}

TEST_CASE("still fast path: birth regions (thinning, culling, inverted)", "[sim][still]") {
    const auto circle = sim::make_circle_shape(30.0, 20.0, 90.0);
    for (const bool invert : {false, true}) {
        sim::ProcessConfig c;
        c.seed = 11;
        c.intensity = 0.05;
        c.orientation = sim::OrientationMode::Random;
        c.region = sim::make_shape_region(circle, 30.0, invert);
        INFO("invert " << invert);
        check_still(c, wedge(), 12.0);
    }
}

TEST_CASE("still fast path: periodic domain", "[sim][still]") {
    sim::ProcessConfig c;
    c.seed = 5;
    c.amplitude = sim::Amplitude::Sign;
    c.period = std::array<double, 2>{128.0, 64.0};  // 8 x 4 cells of 16
    check_still(c, wedge(), 12.0);
}

TEST_CASE("still fast path: dense cells (over 64 candidates, split Poisson draws)", "[sim][still]") {
    for (const double intensity : {0.4, 1.2}) {  // ~100 and ~300 candidates per cell
        sim::ProcessConfig c;
        c.intensity = intensity;
        numeric::Region view;
        view.boxes = {{-20.0, -20.0, 21.0, 13.0}, {5.0, 0.0, 40.0, 30.0}};
        for (const bool region : {false, true}) {
            c.region = region ? sim::make_shape_region(sim::make_circle_shape(0, 0, 25), 10, false)
                              : nullptr;
            INFO("intensity " << intensity << ", region " << region);
            check_still(c, view, 4.0);
        }
    }
}

TEST_CASE("batched Philox draws match CounterRng's", "[sim][still]") {
    const numeric::CounterRng rng(0xFEDCBA9876543210ull, 0x5245474Eu);
    numeric::DrawBatch batch;
    const int64_t big = int64_t(1) << 40;
    for (const size_t n : {1, 16, 37, 300}) {  // partial and whole lane groups, regrown arrays
        batch.clear();
        std::vector<std::array<double, 4>> want;
        for (size_t j = 0; j < n; ++j) {
            const int64_t a = int64_t(j) * 977 - big, b = int64_t(j % 7) - 3, c = int64_t(j) << 33;
            const uint32_t d = 0xFFFFFFF0u + uint32_t(j);
            CHECK(batch.add(a, b, c, d) == j);
            want.push_back(rng.uniforms(a, b, c, d));
        }
        batch.run(rng);
        for (size_t j = 0; j < n; ++j)
            for (int i = 0; i < 4; ++i) CHECK(batch.u01(j, i) == want[j][size_t(i)]);
    }
}
