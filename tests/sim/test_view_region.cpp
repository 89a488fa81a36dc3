// SPDX-License-Identifier: Apache-2.0
// Regions (numeric::Region, a union of boxes): the impulses of a region are those of its bounding
// box whose support touches one of the boxes, in the same canonical order, for still and moving
// layers; a still layer's parallel generation gives the same bits on any number of threads.

#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "sim/sim.h"

namespace {

namespace numeric = impulse::numeric;
namespace sim = impulse::sim;

sim::ProcessConfig config(bool moving) {
    sim::ProcessConfig c;
    c.seed = 77;
    c.cell_size = 16.0;
    c.intensity = 16.0 / (std::numbers::pi * 16.0 * 16.0);
    if (moving) c.lifetime_s = 1.0, c.orientation = sim::OrientationMode::Random;
    return c;
}

std::shared_ptr<sim::Flow> wind() {
    auto f = std::make_shared<sim::FlowSum>();
    f->push(sim::make_uniform_flow(numeric::Keyframed(40.0), numeric::Keyframed(-15.0)));
    return f;
}

bool same(const sim::Impulses& a, const sim::Impulses& b) {
    auto eq = [](const auto& u, const auto& v) {
        return u.size() == v.size() &&
               (u.empty() || std::memcmp(u.data(), v.data(), u.size() * sizeof(u[0])) == 0);
    };
    return eq(a.x, b.x) && eq(a.y, b.y) && eq(a.weight, b.weight) && eq(a.theta, b.theta);
}

}  // namespace

TEST_CASE("a region gives its bounding box's impulses that touch one of its boxes, in order",
          "[sim][determinism]") {
    constexpr double R = 16.0;  // support radius given to the simulator
    // A wedge-like union: two rows of different widths, overlapping, and a detached box.
    numeric::Region region;
    region.boxes = {{0, 0, 300, 40}, {-100, 30, 500, 90}, {700, -50, 760, 10}, {5, 5, 4, 4}};
    CHECK(region.boxes[3].x1 < region.boxes[3].x0);  // an empty box is ignored
    const numeric::Box all = region.bounds();
    CHECK(all.x0 == -100);
    CHECK(all.x1 == 760);
    CHECK(all.y0 == -50);
    CHECK(all.y1 == 90);
    for (const bool moving : {false, true}) {
        CAPTURE(moving);
        auto flow = moving ? wind() : nullptr;
        for (int64_t frame : {0, 7}) {
            sim::LayerSimulator a(config(moving), flow, {}, R), b(config(moving), flow, {}, R);
            sim::Impulses from_region, from_box;
            a.impulses_at(frame, region, from_region);
            b.impulses_at(frame, all, from_box);
            sim::Impulses expected;
            for (size_t i = 0; i < from_box.size(); ++i) {
                bool in = false;
                for (const numeric::Box& box : region.boxes) {
                    if (box.x1 < box.x0) continue;
                    const numeric::Box k = box.expanded(R);
                    in = in || (from_box.x[i] >= k.x0 && from_box.x[i] <= k.x1 &&
                                from_box.y[i] >= k.y0 && from_box.y[i] <= k.y1);
                }
                if (!in) continue;
                expected.x.push_back(from_box.x[i]), expected.y.push_back(from_box.y[i]);
                expected.weight.push_back(from_box.weight[i]);
                expected.theta.push_back(from_box.theta[i]);
            }
            // The union leaves out a good part of the bounding box, so the test is not vacuous.
            CHECK(expected.size() < 0.8 * from_box.size());
            CHECK(expected.size() > 100);
            CHECK(same(from_region, expected));
        }
    }
}

TEST_CASE("a still layer's rows of cells give the same bits on one thread and on many",
          "[sim][determinism]") {
    numeric::Region region;
    region.boxes = {{-2000, -500, 2000, 0}, {-900, 0, 900, 700}};
    sim::Impulses many, one;
    {
        sim::LayerSimulator s(config(false), nullptr, {}, 16.0);
        s.impulses_at(0, region, many);
    }
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        sim::LayerSimulator s(config(false), nullptr, {}, 16.0);
        s.impulses_at(0, region, one);
    }
    CHECK(many.size() > 10000);
    CHECK(same(many, one));
    // canonical order: by row of cells, then cell
    bool ordered = true;
    for (size_t i = 1; i < many.size(); ++i) {
        const double ra = std::floor(many.y[i - 1] / 16.0), rb = std::floor(many.y[i] / 16.0);
        const double ca = std::floor(many.x[i - 1] / 16.0), cb = std::floor(many.x[i] / 16.0);
        ordered = ordered && (ra < rb || (ra == rb && ca <= cb));
    }
    CHECK(ordered);
}
