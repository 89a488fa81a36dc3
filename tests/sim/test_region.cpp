// SPDX-License-Identifier: Apache-2.0
// Birth regions (Lewis 1986 §3.1, points "restricted to an area of the plane"): the shapes'
// signed distances, polygon fill rules, sampled masks, and the thinning of births — the density
// of kept births against lambda p(r), the survivors being the unthinned impulses themselves,
// and the culling of cells outside the region changing nothing.

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include "sim/sim.h"
#include "numeric/errors.h"

namespace {

namespace numeric = impulse::numeric;
namespace sim = impulse::sim;
constexpr double kPi = std::numbers::pi;

/// (x, y) of the local point (u, v) of a frame centred on (cx, cy) turned by `angle`.
std::array<double, 2> local_to_world(double cx, double cy, double angle, double u, double v) {
    return {cx + u * std::cos(angle) - v * std::sin(angle), cy + u * std::sin(angle) + v * std::cos(angle)};
}

double d_at(const sim::Shape& s, std::array<double, 2> p) { return s.distance(p[0], p[1]); }

double smoothstep_region(double d, double feather) {
    const double t = std::clamp((d + 0.5 * feather) / feather, 0.0, 1.0);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

sim::ProcessConfig dense_still(double intensity) {
    sim::ProcessConfig c;
    c.seed = 77;
    c.cell_size = 16.0;
    c.intensity = intensity;
    return c;
}

}  // namespace

TEST_CASE("region shapes: exact signed distances", "[sim][region]") {
    SECTION("circle") {
        const auto c = sim::make_circle_shape(10, -5, 20);
        CHECK(c->distance(10, -5) == Approx(-20));
        CHECK(c->distance(35, -5) == Approx(5));
        CHECK(c->distance(10, 5) == Approx(-10));
    }
    SECTION("box, turned, sharp and rounded corners") {
        const double a = 0.5;  // radians
        const auto b = sim::make_box_shape(100, 50, 50, 30, a, 0.0);
        auto at = [&](const sim::Shape& s, double u, double v) {
            return d_at(s, local_to_world(100, 50, a, u, v));
        };
        CHECK(at(*b, 0, 0) == Approx(-30));
        CHECK(at(*b, 70, 0) == Approx(20));
        CHECK(at(*b, 40, 20) == Approx(-10));
        CHECK(at(*b, 60, 40) == Approx(std::sqrt(200.0)));
        CHECK(at(*b, -60, -40) == Approx(std::sqrt(200.0)));
        const auto r = sim::make_box_shape(100, 50, 50, 30, a, 10.0);
        // The corner arc is centred on (40, 20) in the box's frame, radius 10.
        CHECK(at(*r, 60, 40) == Approx(std::sqrt(800.0) - 10.0));
        CHECK(at(*r, 40 + 10 / std::sqrt(2.0), 20 + 10 / std::sqrt(2.0)) == Approx(0).margin(1e-9));
        CHECK(at(*r, 70, 0) == Approx(20));
        CHECK_THROWS_AS(sim::make_box_shape(0, 0, 10, 5, 0, 6), impulse::ValueError);
        const auto bb = b->bounds();  // turned rectangle: half-extents 50 cos a + 30 sin a, ...
        CHECK(bb.x1 - bb.x0 == Approx(2 * (50 * std::cos(a) + 30 * std::sin(a))));
        CHECK(bb.y1 - bb.y0 == Approx(2 * (50 * std::sin(a) + 30 * std::cos(a))));
    }
    SECTION("ellipse against a dense sampling of its boundary") {
        const double a = 100, b = 40, ang = 0.3, cx = 5, cy = -7;
        const auto e = sim::make_ellipse_shape(cx, cy, a, b, ang);
        std::vector<std::array<double, 2>> boundary;
        const int n = 200000;  // spacing <= 2 pi a / n = 3e-3: distance error ~ spacing^2 / R
        for (int i = 0; i < n; ++i) {
            const double t = 2 * kPi * i / n;
            boundary.push_back(local_to_world(cx, cy, ang, a * std::cos(t), b * std::sin(t)));
        }
        const double pts[][2] = {{0, 0}, {150, 30}, {-60, 10}, {20, 38}, {0, 41}, {-200, -90}, {90, 0}};
        for (const auto& q : pts) {
            const auto p = local_to_world(cx, cy, ang, q[0], q[1]);
            double best = 1e300;
            for (const auto& s : boundary) best = std::min(best, std::hypot(p[0] - s[0], p[1] - s[1]));
            const bool inside = std::pow(q[0] / a, 2) + std::pow(q[1] / b, 2) < 1;
            CAPTURE(q[0], q[1]);
            CHECK(d_at(*e, p) == Approx(inside ? -best : best).margin(2e-3));
        }
    }
    SECTION("capsule") {
        const auto c = sim::make_capsule_shape(0, 0, 100, 0, 10);
        CHECK(c->distance(50, 0) == Approx(-10));
        CHECK(c->distance(50, 25) == Approx(15));
        CHECK(c->distance(-20, 0) == Approx(10));
        CHECK(c->distance(103, 4) == Approx(-5));
        CHECK_THROWS_AS(sim::make_capsule_shape(0, 0, 1, 1, -1), impulse::ValueError);
    }
    SECTION("combinations: union, intersection, subtraction") {
        auto a = sim::make_circle_shape(0, 0, 10), b = sim::make_circle_shape(15, 0, 10);
        const auto u = sim::make_combined_shape(sim::ShapeOp::Union, {a, b});
        const auto i = sim::make_combined_shape(sim::ShapeOp::Intersection, {a, b});
        const auto s = sim::make_combined_shape(sim::ShapeOp::Subtract, {a, b});
        CHECK(u->distance(-5, 0) < 0);
        CHECK(u->distance(20, 0) < 0);
        CHECK(u->distance(40, 0) == Approx(15));
        CHECK(i->distance(7.5, 0) < 0);
        CHECK(i->distance(-5, 0) > 0);
        CHECK(s->distance(-5, 0) < 0);
        CHECK(s->distance(7.5, 0) > 0);
        CHECK(i->bounds().x0 == Approx(5));
        CHECK(i->bounds().x1 == Approx(10));
    }
}

TEST_CASE("region polygons: a non-convex shape and the two fill rules", "[sim][region]") {
    // An L: the notch [50, 100] x [50, 100] is outside.
    const std::vector<std::array<double, 2>> ell = {{0, 0}, {100, 0}, {100, 50}, {50, 50}, {50, 100}, {0, 100}};
    for (auto rule : {sim::FillRule::EvenOdd, sim::FillRule::NonZero}) {
        const auto p = sim::make_polygon_shape(ell, rule);
        CHECK(p->distance(25, 25) == Approx(-25));
        CHECK(p->distance(75, 25) == Approx(-25));
        CHECK(p->distance(25, 75) == Approx(-25));
        CHECK(p->distance(75, 75) == Approx(25));  // in the notch: to the inner edges
        CHECK(p->distance(60, 90) == Approx(10));
        CHECK(p->distance(120, 25) == Approx(20));
        CHECK(p->distance(50, 50) == Approx(0).margin(1e-12));
        // Vertices on the ray's line are counted once: points level with them.
        CHECK(p->distance(-10, 50) == Approx(10));
        CHECK(p->distance(25, 50) < 0);
        CHECK(p->distance(75, 50) == Approx(0).margin(1e-12));
    }
    // A pentagram drawn through every second vertex of a pentagon: the centre pentagon is wound
    // twice, so it is inside under nonzero and outside under even-odd; the points are inside
    // under both.
    std::vector<std::array<double, 2>> star;
    for (int k = 0; k < 5; ++k) {
        const double t = kPi / 2 + 2 * kPi * (2 * k % 5) / 5.0;
        star.push_back({100 * std::cos(t), 100 * std::sin(t)});
    }
    const auto nz = sim::make_polygon_shape(star, sim::FillRule::NonZero);
    const auto eo = sim::make_polygon_shape(star, sim::FillRule::EvenOdd);
    CHECK(nz->distance(0, 0) < 0);
    CHECK(eo->distance(0, 0) > 0);
    CHECK(nz->distance(0, 80) < 0);
    CHECK(eo->distance(0, 80) < 0);
    CHECK(nz->distance(0, -95) > 0);  // between the two lower points
    // Degenerate polygons are refused.
    CHECK_THROWS_AS(sim::make_polygon_shape({{0, 0}, {1, 1}}, sim::FillRule::EvenOdd), impulse::ValueError);
    CHECK_THROWS_AS(sim::make_polygon_shape({{0, 0}, {1, 1}, {3, 3}, {2, 2}}, sim::FillRule::EvenOdd),
                    impulse::ValueError);
    CHECK_THROWS_AS(sim::make_polygon_shape({{5, 5}, {5, 5}, {5, 5}}, sim::FillRule::EvenOdd),
                    impulse::ValueError);
}

TEST_CASE("region edges: smoothstep feather, hard edge, invert, support", "[sim][region]") {
    const auto circle = sim::make_circle_shape(0, 0, 100);
    const auto soft = sim::make_shape_region(circle, 40, false);
    CHECK(soft->acceptance(0, 0) == 1.0);
    CHECK(soft->acceptance(80, 0) == 1.0);       // d = -20 = -feather/2
    CHECK(soft->acceptance(100, 0) == Approx(0.5));
    CHECK(soft->acceptance(110, 0) == Approx(smoothstep_region(10, 40)));
    CHECK(soft->acceptance(120, 0) == 0.0);
    const auto s = soft->support();
    REQUIRE(s);
    CHECK(s->x0 == Approx(-120));
    CHECK(s->x1 == Approx(120));
    const auto hard = sim::make_shape_region(circle, 0, false);
    CHECK(hard->acceptance(99.9, 0) == 1.0);
    CHECK(hard->acceptance(100.1, 0) == 0.0);
    const auto inv = sim::make_shape_region(circle, 40, true);
    CHECK(inv->acceptance(110, 0) == Approx(1.0 - smoothstep_region(10, 40)));
    CHECK_FALSE(inv->support());
    CHECK_THROWS_AS(sim::make_shape_region(circle, -1, false), impulse::ValueError);
}

TEST_CASE("region masks: bilinear, clamped, pixel centres at origin + (i + 0.5) spacing",
          "[sim][region]") {
    sim::MaskGrid g;
    g.width = 4, g.height = 3;
    g.values = {0, 0, 0, 0,  //
                0, 1, 0.5f, 0,  //
                0, 0, 0, 0};
    g.origin_x = 100, g.origin_y = 200, g.spacing = 10;
    const auto m = sim::make_mask_region(g, false);
    CHECK(m->acceptance(115, 215) == 1.0);            // pixel (1, 1)'s centre
    CHECK(m->acceptance(125, 215) == Approx(0.5));    // pixel (2, 1)
    CHECK(m->acceptance(120, 215) == Approx(0.75));   // half-way between them
    CHECK(m->acceptance(115, 210) == Approx(0.5));    // half-way to row 0
    CHECK(m->acceptance(0, 0) == 0.0);                // clamped to pixel (0, 0)
    // Support: the non-zero pixels (1..2, 1) plus the bilinear reach of one pixel.
    const auto s = m->support();
    REQUIRE(s);
    CHECK(s->x0 == Approx(105));
    CHECK(s->x1 == Approx(135));
    CHECK(s->y0 == Approx(205));
    CHECK(s->y1 == Approx(225));
    for (double x = 80; x < 160; x += 0.7)
        for (double y = 180; y < 250; y += 0.7)
            if (x < s->x0 || x > s->x1 || y < s->y0 || y > s->y1) REQUIRE(m->acceptance(x, y) == 0.0);
    const auto inv = sim::make_mask_region(g, true);
    CHECK(inv->acceptance(125, 215) == Approx(0.5));
    CHECK(inv->acceptance(0, 0) == 1.0);
    CHECK_FALSE(inv->support());
    // A non-zero border is held out to infinity: no support.
    g.values[0] = 0.2f;
    CHECK_FALSE(sim::make_mask_region(g, false)->support());
    g.values[0] = 1.5f;
    CHECK_THROWS_AS(sim::make_mask_region(g, false), impulse::ValueError);
}

TEST_CASE("region thinning: kept births have density lambda p(r)", "[sim][region][stats]") {
    // A still process of intensity lambda = 0.25 per unit^2 in a circle of radius 200 with a
    // feather of 120: p(r) = 1 - smoothstep((r - 140) / 120). Births in annuli of width 10 out
    // to r = 360 (cells cover [-400, 400]^2, so every annulus is whole).
    //
    // Band: the kept births are a thinned Poisson process, Poisson with intensity lambda p, so
    // the count in an annulus is Poisson with mean mu = lambda int p(r) 2 pi r dr (Simpson,
    // 64 steps per annulus: exact to ~1e-9 relative); sd sqrt(mu); band 5 sd (+1 for the
    // integration). Annuli are disjoint, so the counts are independent: 36 bins at 5 sd give a
    // false alarm chance below 1e-4 for any seed; the seed is fixed.
    const double lambda = 0.25, radius = 200, feather = 120;
    sim::ProcessConfig c = dense_still(lambda);
    c.region = sim::make_shape_region(sim::make_circle_shape(0, 0, radius), feather, false);
    sim::ProcessConfig bare = c;
    bare.region = nullptr;
    const int nb = 36;
    const double width = 10;
    std::vector<double> kept(nb, 0), all(nb, 0);
    sim::CellImpulses cell;
    for (int cy = -25; cy < 25; ++cy)
        for (int cx = -25; cx < 25; ++cx) {
            for (int pass = 0; pass < 2; ++pass) {
                sim::cell_impulses(pass ? bare : c, cx, cy, 0, cell);
                for (size_t k = 0; k < cell.x.size(); ++k) {
                    const double r = std::hypot(cell.x[k], cell.y[k]);
                    const int b = static_cast<int>(r / width);
                    if (b < nb) (pass ? all : kept)[b] += 1;
                }
            }
        }
    auto p = [&](double r) { return smoothstep_region(r - radius, feather); };
    int out_of_band = 0, unthinned_out = 0, hard_out = 0;
    double worst = 0;
    for (int b = 0; b < nb; ++b) {
        const double r0 = b * width, h = width / 64;
        double integral = 0, area = 0, hard = 0;
        for (int i = 0; i <= 64; ++i) {
            const double r = r0 + i * h, wgt = (i == 0 || i == 64) ? 1 : (i % 2 ? 4 : 2);
            integral += wgt * p(r) * 2 * kPi * r;
            area += wgt * 2 * kPi * r;
            hard += wgt * (r <= radius ? 1.0 : 0.0) * 2 * kPi * r;
        }
        const double mu = lambda * integral * h / 3, mu_all = lambda * area * h / 3,
                     mu_hard = lambda * hard * h / 3;
        const double band = 5 * std::sqrt(std::max(mu, 1.0)) + 1;
        worst = std::max(worst, std::abs(kept[b] - mu) / std::sqrt(std::max(mu, 1.0)));
        if (std::abs(kept[b] - mu) > band) {
            ++out_of_band;
            UNSCOPED_INFO("annulus " << b << " kept " << kept[b] << " expected " << mu);
        }
        // Teeth: the unthinned births, and a hard edge at the radius, fail where p is soft.
        if (std::abs(kept[b] - mu_all) > band) ++unthinned_out;
        if (std::abs(kept[b] - mu_hard) > band) ++hard_out;
        // The unthinned process itself has density lambda (the same Poisson band).
        CHECK(std::abs(all[b] - mu_all) < 5 * std::sqrt(mu_all) + 1);
    }
    CAPTURE(worst, unthinned_out, hard_out);
    CHECK(out_of_band == 0);
    CHECK(unthinned_out >= 10);  // the 12 annuli of the feather and beyond
    CHECK(hard_out >= 6);
}

TEST_CASE("region thinning keeps the unthinned impulses themselves, by identity",
          "[sim][region][determinism]") {
    // Survivors are a subset of the region-free impulses with the same bits (position,
    // amplitude, angle, birth), in the same order; where p = 1 every birth survives, where
    // p = 0 none does.
    sim::ProcessConfig c = dense_still(0.05);
    c.lifetime_s = 2.0;
    c.region = sim::make_shape_region(sim::make_circle_shape(40, 0, 60), 30, false);
    sim::ProcessConfig bare = c;
    bare.region = nullptr;
    sim::CellImpulses a, b;
    size_t kept = 0, total = 0;
    for (int ct = 0; ct < 3; ++ct)
        for (int cy = -6; cy < 6; ++cy)
            for (int cx = -5; cx < 9; ++cx) {
                sim::cell_impulses(c, cx, cy, ct, a);
                sim::cell_impulses(bare, cx, cy, ct, b);
                size_t j = 0;
                for (size_t k = 0; k < b.x.size(); ++k) {
                    const double pk = c.region->acceptance(b.x[k], b.y[k]);
                    const bool match = j < a.x.size() && a.x[j] == b.x[k] && a.y[j] == b.y[k] &&
                                       a.amplitude[j] == b.amplitude[k] &&
                                       a.theta0[j] == b.theta0[k] && a.birth_s[j] == b.birth_s[k];
                    if (pk == 1.0) REQUIRE(match);
                    if (pk == 0.0) REQUIRE_FALSE(match);
                    if (match) ++j;
                }
                REQUIRE(j == a.x.size());  // nothing kept that the bare process lacks
                kept += a.x.size(), total += b.x.size();
            }
    CHECK(kept > 100);
    CHECK(kept < total);
}

TEST_CASE("region culling: skipping cells outside the support changes no bit",
          "[sim][region][determinism]") {
    // A moving layer whose particles cross the region's edge: the culled simulator and one that
    // generates every cell (a region with the same p but no support) give the same impulses,
    // stepping frame by frame and jumping.
    sim::ProcessConfig c = dense_still(16.0 / (kPi * 256.0));
    c.lifetime_s = 1.5;
    auto shape = sim::make_combined_shape(
        sim::ShapeOp::Union, {sim::make_ellipse_shape(0, 0, 120, 50, 0.4),
                              sim::make_capsule_shape(-100, 80, 90, 120, 20)});
    c.region = sim::make_shape_region(shape, 24, false);
    sim::ProcessConfig all = c;
    all.region = sim::without_support(c.region);
    auto flow = std::shared_ptr<sim::Flow>(sim::make_uniform_flow(numeric::Keyframed{40.0}, numeric::Keyframed{-10.0}));
    const numeric::Box view{-300, -200, 300, 200};
    sim::LayerSimulator culled(c, flow, {}, 16.0), full(all, flow, {}, 16.0);
    sim::Impulses a, b;
    size_t seen = 0;
    for (int f : {0, 1, 2, 3, 30, 31, 7}) {
        culled.impulses_at(f, view, a);
        full.impulses_at(f, view, b);
        REQUIRE(a.size() == b.size());
        CHECK(std::memcmp(a.x.data(), b.x.data(), a.size() * sizeof(double)) == 0);
        CHECK(std::memcmp(a.y.data(), b.y.data(), a.size() * sizeof(double)) == 0);
        CHECK(std::memcmp(a.weight.data(), b.weight.data(), a.size() * sizeof(float)) == 0);
        seen += a.size();
    }
    CHECK(seen > 1000);
    // The budget estimate counts only the support's area.
    const numeric::Box big{-1000, -1000, 1000, 1000};
    CHECK(sim::expected_impulses(c, big) < 0.1 * sim::expected_impulses(all, big));
}
