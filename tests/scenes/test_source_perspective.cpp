// SPDX-License-Identifier: Apache-2.0
// Source layers under a perspective camera (issue 13): an fbm layer seen straight down is its
// orthographic render; in a grazing view the near pixels are the tile sampled at their plane
// points, the far ones fade to the tile's mean, and nothing is NaN (scenes/sources/source_grid.cpp); the
// tile and its pyramid count in the memory budget. A gaussian solid layer likewise, through the
// impulse layers' pipeline (scenes/sources/source_solid.cpp).
#include <catch2/catch.hpp>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "numeric/errors.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "synth/synth.h"
#include "tests/scene_render.h"

#if defined(__SANITIZE_ADDRESS__)
#define IMPULSE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IMPULSE_TEST_ASAN 1
#endif
#endif
#ifndef IMPULSE_TEST_ASAN
#define IMPULSE_TEST_ASAN 0
#endif

namespace {

using namespace impulse;

const std::string kLayer = R"(
[[layer]]
source = "fbm"
seed = 9
[layer.fbm]
method = "fourier"
hurst = 0.6
samples = 64
)";

std::string num(double v) {
    std::ostringstream s;
    s << std::setprecision(17) << v;
    return s.str();
}

std::string perspective(double height, double pitch, int w, int h, const std::string& size) {
    return "[output]\nsize = [" + std::to_string(w) + ", " + std::to_string(h) +
           "]\n[camera]\ntype = \"perspective\"\nposition = [32.0, 32.0]\nheight = " + num(height) +
           "\npitch = " + num(pitch) + "\nfov = 60.0\n" + kLayer + "size = " + size + "\n";
}

double rms(const render::Frame& f) {
    double q = 0;
    for (float v : f.data) q += double(v) * v;
    return std::sqrt(q / double(f.data.size()));
}

/// NaN pixels, and pixels above the horizon that are not exactly the mean (0).
struct PixelFaults {
    int nan = 0, sky = 0;
};
/// Calls visit(i, j, value, x, y) for every pixel of `f` that sees the plane at (x, y).
template <class Visit>
PixelFaults for_plane_pixels(const render::PerspectiveView& view, const render::Frame& f,
                             const Visit& visit) {
    PixelFaults faults;
    for (int j = 0; j < f.height; ++j)
        for (int i = 0; i < f.width; ++i) {
            const double v = f.data[size_t(j) * f.width + i];
            if (!std::isfinite(v)) ++faults.nan;
            double x = 0, y = 0;
            if (!view.texture_point(i + 0.5, j + 0.5, x, y)) {
                faults.sky += v != 0.0;
                continue;
            }
            visit(i, j, v, x, y);
        }
    return faults;
}

}  // namespace

TEST_CASE("an fbm layer seen straight down through a perspective camera is its orthographic render",
          "[scenes][source][fbm][perspective]") {
    // 64 pixels, fov 60: focal 32 / tan 30 pixels; 4 pixels a texture unit, 2 a sample (size 32):
    // the footprint (sd 0.125 units, a quarter sample) is below the bilinear read's own blur.
    const double focal = 32.0 / std::tan(M_PI / 6.0), zoom = 4.0;
    const render::Frame p =
        test::render_scene_text(perspective(focal / zoom, 90.0, 64, 64, "32.0"));
    const render::Frame o = test::render_scene_text(
        "[output]\nsize = [64, 64]\n[camera]\ncenter = [32.0, 32.0]\nzoom = " + num(zoom) + "\n" +
        kLayer + "size = 32.0\n");
    const double sd = rms(o);
    REQUIRE(sd > 0.1);
    double worst = 0;
    for (size_t k = 0; k < p.data.size(); ++k)
        worst = std::max(worst, double(std::abs(p.data[k] - o.data[k])));
    CAPTURE(sd, worst);
    CHECK(worst < 1e-4 * sd);  // the same bilinear reads; the plane points differ by rounding
}

TEST_CASE("an fbm layer in a grazing perspective view is sampled near and fades to the mean far",
          "[scenes][source][fbm][perspective]") {
    const int w = 160, h = 120;
    const std::string text = perspective(6.0, 12.0, w, h, "64.0");  // one texture unit a sample
    scenes::Scene scene = scenes::load_scene_string(text, "p.toml");
    const render::PerspectiveView view(scene.camera.perspective(w, h, 0.0));
    const render::Frame f = test::render_scene_text(text);
    // The tile itself: an orthographic frame whose pixel (i, j) is sample (i + 1, j + 1) mod 64.
    const render::Frame tile = test::render_scene_text(
        "[output]\nsize = [64, 64]\n[camera]\ncenter = [32.5, 32.5]\n" + kLayer + "size = 64.0\n");
    const double sd = rms(tile);
    auto sample = [&](int i, int j) {
        return double(tile.data[size_t(((j - 1) % 64 + 64) % 64) * 64 + ((i - 1) % 64 + 64) % 64]);
    };
    int near = 0, far = 0, near_bad = 0, far_bad = 0;
    const PixelFaults faults =
        for_plane_pixels(view, f, [&](int, int, double v, double x, double y) {
            const auto fp = view.footprint(x, y);
            const double major = 0.5 * fp.s_major;  // the pixel filter's sd along, texture units
            if (major * major < 1.0 / 6.0 - 1e-3) {
                // Below the bilinear read's own blur: the tile read at the plane point.
                const double fx = std::floor(x), fy = std::floor(y), a = x - fx, b = y - fy;
                const int ix = int(fx), iy = int(fy);
                const double ref = (1 - b) * ((1 - a) * sample(ix, iy) + a * sample(ix + 1, iy)) +
                                   b * ((1 - a) * sample(ix, iy + 1) + a * sample(ix + 1, iy + 1));
                ++near;
                near_bad += std::abs(v - ref) > 1e-3 * sd;
            } else if (major > 128.0) {  // two tiles: nothing of the field is left
                ++far;
                far_bad += std::abs(v) > 0.02 * sd;
            }
        });
    CAPTURE(near, far, sd);
    CHECK(faults.nan == 0);
    CHECK(faults.sky == 0);  // above the horizon: the mean
    CHECK(near > 500);
    CHECK(far > 100);
    CHECK(near_bad == 0);
    CHECK(far_bad == 0);
}

// ---------------------------------------------------------------------------------------------
// Solid layers (docs/perspective.md §10): a gaussian slice drawn as the 2-D impulses of the
// cells that reach the plane.

namespace {

std::string solid_layer(double radius, int seed = 5) {
    return "[[layer]]\nsource = \"solid\"\nseed = " + std::to_string(seed) +
           "\n[layer.solid]\nkernel = \"gaussian\"\nradius = " + num(radius) + "\nz0 = 3.7\n";
}

std::string solid_camera(double height, double pitch, int w, int h, const std::string& extra = "") {
    return "[output]\nsize = [" + std::to_string(w) + ", " + std::to_string(h) +
           "]\n[camera]\ntype = \"perspective\"\nposition = [32.0, 32.0]\nheight = " + num(height) +
           "\npitch = " + num(pitch) + "\nfov = 60.0\n" + extra;
}

/// The layer's noise itself (the seed the scene gives it), for point references.
synth::SolidNoise solid_noise(const scenes::Scene& scene, double radius) {
    synth::SolidParams p;
    p.kernel.type = kernels::KernelType::Gaussian;
    p.kernel.radius = radius;
    p.kernel.sigma = radius / 3.0;
    p.seed = scene.layers[0].process.seed;
    return synth::SolidNoise(p);
}

}  // namespace

TEST_CASE(
    "a gaussian solid layer seen straight down through a perspective camera is its orthographic "
    "render",
    "[scenes][source][solid][perspective]") {
    // 128 pixels, fov 60, one pixel a texture unit; R = 24 (sigma 8 px): the pixel filter (sd
    // 0.5 px) is below the pyramid's sigma_0, so level 0, the kernel itself, is drawn.
    const double focal = 64.0 / std::tan(M_PI / 6.0), R = 24.0;
    const render::Frame p =
        test::render_scene_text(solid_camera(focal, 90.0, 128, 128) + solid_layer(R));
    const render::Frame o = test::render_scene_text(
        "[output]\nsize = [128, 128]\n[camera]\ncenter = [32.0, 32.0]\n" + solid_layer(R));
    const double sd = rms(o);
    REQUIRE(sd > 0.05);
    double worst = 0, d2 = 0;
    for (size_t k = 0; k < p.data.size(); ++k) {
        const double d = p.data[k] - o.data[k];
        worst = std::max(worst, std::abs(d)), d2 += d * d;
    }
    const double rms_diff = std::sqrt(d2 / double(p.data.size()));
    CAPTURE(sd, worst, rms_diff);
    // The 2-D kernel is cut at r = R, the slice of the 3-D one at r = sqrt(R^2 - dz^2): they differ
    // on that ring, where the kernel is below exp(-4.5) = 1.1 % of its peak; 1.7 % of the sd in rms
    // by quadrature (docs/perspective.md §10). Measured here: 1.73 % in rms, 9.5 % at worst.
    CHECK(rms_diff < 0.03 * sd);
    CHECK(worst < 0.1 * sd);
}

TEST_CASE(
    "a gaussian solid layer in a grazing perspective view is footprint-filtered near and fades far",
    "[scenes][source][solid][perspective][slow]") {
    const int w = 160, h = 120;
    const double R = 3.0, sigma = R / 3.0;
    // Camera 40 units up: the kernel (R = 3) is small against the depth (over 40), so the map is
    // affine over it (docs/perspective.md §1); 6 units up, where the footprint at the impulse
    // differs from the pixel's within one kernel, the near pixels err twice as much.
    const std::string text = solid_camera(40.0, 12.0, w, h) + solid_layer(R);
    const scenes::Scene scene = scenes::load_scene_string(text, "p.toml");
    const render::PerspectiveView view(scene.camera.perspective(w, h, 0.0));
    const render::Frame f = test::render_scene_text(text);
    const double sd = std::sqrt(scenes::layer_theory(scene.layers[0]).variance);
    const synth::SolidNoise noise = solid_noise(scene, R);
    // Reference: the slice filtered by the pixel's footprint (docs/perspective.md eq. 1.1), by
    // Gauss-Hermite quadrature of the noise's own point evaluation (9 nodes along, 5 across).
    static const double u9[] = {-4.5127, -3.2054, -2.0768, -1.0233, 0.0,
                                1.0233,  2.0768,  3.2054,  4.5127};
    static const double w9[] = {2.2345e-5, 2.7891e-3, 4.9916e-2, 2.4410e-1, 4.0635e-1,
                                2.4410e-1, 4.9916e-2, 2.7891e-3, 2.2345e-5};
    static const double u5[] = {-2.8570, -1.3556, 0.0, 1.3556, 2.8570};
    static const double w5[] = {1.1257e-2, 2.2208e-1, 5.3333e-1, 2.2208e-1, 1.1257e-2};
    std::vector<size_t> near_pixels;
    std::vector<synth::SolidPoint> pts;
    int far = 0, far_bad = 0;
    const PixelFaults faults =
        for_plane_pixels(view, f, [&](int i, int j, double v, double x, double y) {
            const auto fp = view.footprint(x, y);
            const double sM = 0.5 * fp.s_major, sm = 0.5 * fp.s_minor;  // the filter's sd, units
            if (sM < sigma && (i + j) % 3 == 0) {
                near_pixels.push_back(size_t(j) * w + i);
                for (int a = 0; a < 9; ++a)
                    for (int b = 0; b < 5; ++b)
                        pts.push_back({x + sM * u9[a] * fp.ex - sm * u5[b] * fp.ey,
                                       y + sM * u9[a] * fp.ey + sm * u5[b] * fp.ex, 3.7, 0.0});
            } else if (sigma / std::hypot(sigma, sM) < 0.005) {  // under half the cut-off's sd
                ++far;
                far_bad += std::abs(v) > 0.02 * sd;
            }
        });
    std::vector<float> values;
    noise.evaluate(pts, values);
    // The rms and largest difference of a frame's near pixels from the reference, in sd.
    auto near_error = [&](const render::Frame& g, double& worst) {
        double d2 = 0;
        worst = 0;
        for (size_t k = 0; k < near_pixels.size(); ++k) {
            double ref = 0;
            for (int a = 0; a < 9; ++a)
                for (int b = 0; b < 5; ++b) ref += w9[a] * w5[b] * values[k * 45 + a * 5 + b];
            const double d = (g.data[near_pixels[k]] - ref) / sd;
            d2 += d * d, worst = std::max(worst, std::abs(d));
        }
        return std::sqrt(d2 / double(near_pixels.size()));
    };
    double worst = 0, worst_off = 0;
    const double near_rms = near_error(f, worst);
    // The off-switch: unfiltered, the near pixels are the slice at their plane points.
    const double off_rms = near_error(
        test::render_scene_text(solid_camera(40.0, 12.0, w, h, "antialias = \"off\"\n") +
                                solid_layer(R)),
        worst_off);
    CAPTURE(near_pixels.size(), far, sd, near_rms, worst, off_rms, worst_off);
    CHECK(faults.nan == 0);
    CHECK(faults.sky == 0);  // above the horizon: exactly the mean
    CHECK(near_pixels.size() > 500);
    CHECK(far > 100);
    // The impulse layers' filter forms are within 1-3 % of the filtered kernel (line form,
    // docs/perspective.md §4), and the cut of §10 adds 1.7 % in rms: measured 4.0 % and 20 % at
    // worst (unfiltered: 15.6 % and 96 %).
    CHECK(near_rms < 0.05);
    CHECK(worst < 0.25);
    CHECK(off_rms > 2.0 * near_rms);
    CHECK(far_bad == 0);
}

TEST_CASE(
    "a gaussian solid layer seen straight down has the variance of the footprint-filtered slice",
    "[scenes][source][solid][perspective][stats][slow]") {
    // R = 1.5 px (sigma 0.5 px): the pixel filter (sd s = 0.5 px) is as wide as the kernel. The
    // slice filtered by g_s is sum_i a_i e^{-dz_i^2 / 2 sigma^2} 2 pi sigma^2 N(x - x_i; sigma'^2),
    // sigma'^2 = sigma^2 + s^2, whose variance is lambda E[a^2] pi^{3/2} sigma^4 / sigma'^2:
    // Campbell's sigma^3 pi^{3/2} times sigma^2 / sigma'^2 = 1/2 (docs/perspective.md eq. 10.3).
    const int n = 256;
    const double focal = 0.5 * n / std::tan(M_PI / 6.0), R = 1.5, ratio = 0.5;
    auto measure = [&](const std::string& extra, int seeds) {
        double s2 = 0, theory = 0;
        for (int seed = 1; seed <= seeds; ++seed) {
            const std::string text = solid_camera(focal, 90.0, n, n, extra) + solid_layer(R, seed);
            theory = scenes::layer_theory(scenes::load_scene_string(text, "p.toml").layers[0]).variance;
            for (float v : test::render_scene_text(text).data) s2 += double(v) * v;
        }
        return s2 / (double(seeds) * n * n) / theory;
    };
    // Effective samples: the filtered field's correlation area int rho^2 = 2 pi sigma'^2 = pi px^2,
    // so 4 x 256^2 / pi = 83 000 and the sd of the variance ratio is ratio sqrt(2 / 83 000) =
    // 0.5 %; the pyramid's blend of two levels (linear in log sigma, docs/perspective.md §2)
    // approximates h2 * g_s with its own error (empirical: measured -1.9 % here, 0.4905): the
    // band is 2 % + 4 sd.
    const double filtered = measure("", 4);
    CAPTURE(filtered);
    CHECK(std::abs(filtered - ratio) < 0.02 * ratio + 4.0 * 0.005 * ratio);
    // The off-switch: without the footprint filter the point samples keep the whole variance
    // (measured 0.995).
    const double unfiltered = measure("antialias = \"off\"\n", 1);
    CAPTURE(unfiltered);
    CHECK(std::abs(unfiltered - ratio) > 0.5 * ratio);
}

TEST_CASE("a 4-D gaussian solid layer in perspective has the same bits on one thread as on all",
          "[scenes][source][solid][perspective][determinism][slow]") {
    // dims = 4: the plane also moves along t (rate), d2 = dz^2 + dt^2 (docs/perspective.md §10);
    // a drift moves it in the plane. Frame 1 at 2 fps: t = 0.5 s.
    const std::string text = "[output]\nfps = 2.0\nframes = 4\n" +
                             solid_camera(20.0, 15.0, 160, 90).substr(9) + solid_layer(4.0) +
                             "dims = 4\nrate = 3.0\nvelocity = 1.5\n[[layer.flow]]\ntype = "
                             "\"uniform\"\nvelocity = [2.0, -1.0]\n";
    const render::Frame all = test::render_scene_text(text, 1);
    render::Frame one;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = test::render_scene_text(text, 1);
    }
    CHECK(test::same_bits(all, one));
    const scenes::Scene scene = scenes::load_scene_string(text, "p.toml");
    const render::PerspectiveView view(scene.camera.perspective(160, 90, 0.5));
    const PixelFaults faults = for_plane_pixels(view, all, [](int, int, double, double, double) {});
    CHECK(faults.nan == 0);
    CHECK(faults.sky == 0);
    CHECK(rms(all) > 0.1);
}

TEST_CASE("a perspective frame of a solid slice over the impulse budget is refused with the estimate",
          "[scenes][source][solid][errors]") {
    // R = 0.05 texture units, a twentieth of a pixel near the camera: 6.6e8 impulses.
    REQUIRE_THROWS_WITH(
        test::render_scene_text(solid_camera(40.0, 15.0, 320, 180) + solid_layer(0.05), 0, "p.toml"),
        Catch::Contains("p.toml: layer[0]: a perspective frame of the solid slice needs about") &&
            Catch::Contains("raise camera.cutoff or layer.solid.radius"));
}

TEST_CASE("solid layers other than gaussian are refused under a perspective camera",
          "[scenes][source][errors]") {
    for (const char* kernel : {"cosine", "spectrum"}) {
        std::string solid = std::string("[layer.solid]\nkernel = \"") + kernel + "\"\n";
        if (std::string(kernel) == "spectrum") solid += "model = \"gaussian\"\nlength = 4.0\n";
        REQUIRE_THROWS_WITH(
            scenes::Renderer(scenes::load_scene_string(
                "[camera]\ntype = \"perspective\"\n[[layer]]\nsource = \"solid\"\n" + solid,
                "p.toml")),
            Catch::Contains("kernel = \"" + std::string(kernel) +
                            "\" is seen through an orthographic camera only"));
    }
}

namespace {

/// MiB allocated by malloc now (glibc's mallinfo2: small blocks and mmapped ones); 0 where it is
/// not known (another C library, or the sanitizers' allocator).
double allocated_mib() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || __GLIBC_MINOR__ >= 33) && !IMPULSE_TEST_ASAN
    const struct mallinfo2 m = mallinfo2();
    return double(m.uordblks + m.hblkhd) / (1024.0 * 1024.0);
#else
    return 0.0;
#endif
}

/// A subdivision layer of 16 x 16 samples over 8 texture units, markov of length `length`: at 4
/// (eight samples) a tile so correlated that its own mean is a large draw (-0.68 for seed 5,
/// against an sd of 0.60 about it); at 1, 0.055 against 0.98.
std::string subdivision_layer(double length) {
    return "[[layer]]\nsource = \"subdivision\"\nseed = 5\n[layer.subdivision]\nacf = \"markov\"\n"
           "length = " + num(length) + "\nsamples = 16\nsize = 8.0\n";
}

}  // namespace

TEST_CASE("a subdivision layer in a grazing view fades to its own tile's mean",
          "[scenes][source][subdivision][perspective][stats][slow]") {
    // Length 4 at the default cut-off: the top level keeps the tile's mean, so a fade measured
    // by the rms (the mean included) never completes and the sky showed 0; length 1 at cut-off
    // 0.5: the far field fades out and used to fade to 0.
    const double length = GENERATE(4.0, 1.0);
    const std::string cutoff = length == 1.0 ? "cutoff = 0.5\n" : "";
    const std::string layer = subdivision_layer(length);
    const int w = 320, h = 240, n = 16;
    const double cell = 0.5;
    const std::string text = "[output]\nsize = [" + std::to_string(w) + ", " + std::to_string(h) +
                             "]\n[camera]\ntype = \"perspective\"\nposition = [4.0, 4.0]\n"
                             "height = 1.5\npitch = 12.0\nfov = 60.0\n" + cutoff + layer;
    const scenes::Scene scene = scenes::load_scene_string(text, "p.toml");
    const render::PerspectiveView view(scene.camera.perspective(w, h, 0.0));
    const render::Frame f = test::render_scene_text(text);
    // The samples: an orthographic frame with a pixel per cell reads sample (i, j) at pixel (i, j).
    const render::Frame tile = test::render_scene_text(
        "[output]\nsize = [16, 16]\n[camera]\ncenter = [4.0, 4.0]\nzoom = 2.0\n" + layer);
    double tile_mean = 0, tile_sq = 0;
    for (float v : tile.data) tile_mean += v, tile_sq += double(v) * v;
    tile_mean /= tile.data.size();
    const double sd = std::sqrt(tile_sq / tile.data.size() - tile_mean * tile_mean);
    // The tile read bilinearly at texture point (x, y) (samples at cell centres, wrapped).
    auto at = [&](double x, double y) {
        const double gx = x / cell - 0.5, gy = y / cell - 0.5, fx = std::floor(gx), fy = std::floor(gy);
        const double a = gx - fx, b = gy - fy;
        auto s = [&](int i, int j) { return double(tile.data[size_t((j % n + n) % n) * n + (i % n + n) % n]); };
        const int i = int(fx), j = int(fy);
        return (1 - b) * ((1 - a) * s(i, j) + a * s(i + 1, j)) + b * ((1 - a) * s(i, j + 1) + a * s(i + 1, j + 1));
    };
    std::vector<std::pair<double, double>> near_points;
    double near_sum = 0, far_sum = 0, far_worst = 0, sky_worst = 0;
    int far = 0;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double v = f.data[size_t(j) * w + i];
            double x = 0, y = 0;
            if (!view.texture_point(i + 0.5, j + 0.5, x, y)) {  // above the horizon
                sky_worst = std::max(sky_worst, std::abs(v - tile_mean));
                continue;
            }
            const double major = 0.5 * view.footprint(x, y).s_major;  // texture units
            if (major * major < cell * cell / 6.0 - 1e-6) {  // under the bilinear read's blur
                near_points.push_back({x, y});
                near_sum += v;
            } else if (major > 2.0 * n * cell) {  // two tiles: faded out
                ++far;
                far_sum += v;
                far_worst = std::max(far_worst, std::abs(v - tile_mean));
            }
        }
    REQUIRE(near_points.size() > 2000);
    REQUIRE(far > 500);
    const double near_mean = near_sum / near_points.size(), far_mean = far_sum / far;
    // The near band's mean samples the tile at its plane points: its sampling error is the
    // scatter of that mean over the band moved across the tile (an 8 x 8 lattice of shifts
    // spanning one tile; the tile's bilinear reads, which the near pixels are).
    double m1 = 0, m2 = 0;
    for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
            double sum = 0;
            for (const auto& [x, y] : near_points) sum += at(x + sx * n * cell / 8, y + sy * n * cell / 8);
            const double m = sum / near_points.size();
            m1 += m / 64, m2 += m * m / 64;
        }
    const double sampling_sd = std::sqrt(std::max(0.0, m2 - m1 * m1));
    CAPTURE(length, tile_mean, sd, near_mean, far_mean, sampling_sd, near_points.size(), far);
    CHECK(far_worst < 1e-5 * sd);  // faded out: the tile's mean itself
    CHECK(sky_worst < 1e-5 * sd);  // and so is the sky, with no step at the horizon
    CHECK(std::abs(far_mean - near_mean) < 4.0 * sampling_sd);
    // The mechanism: at length 4 the layer's stated mean (0), which the sky showed, is far
    // outside the near band's sampling error.
    if (length == 4.0) CHECK(std::abs(0.0 - near_mean) > 4.0 * sampling_sd);
}

TEST_CASE("a source layer's tile and pyramid count in limits.max_memory_mib",
          "[scenes][source][perspective][limits]") {
    // A 1024^2 fbm tile (4 MiB) whose pyramid (7 MiB at its peak) a perspective camera builds.
    const std::string text = "[output]\nsize = [64, 64]\n[camera]\ntype = \"perspective\"\n"
                             "position = [32.0, 32.0]\nheight = 6.0\npitch = 12.0\n"
                             "[[layer]]\nsource = \"fbm\"\n[layer.fbm]\nmethod = \"fourier\"\n"
                             "samples = 1024\n";
    const double before = allocated_mib();
    double mib = 0, held = 0;
    {
        scenes::Renderer r(scenes::load_scene_string(text, "m.toml"));
        render::Frame out;
        r.render(0, out);
        mib = r.estimated_memory_mib();
        held = allocated_mib() - before;  // what the renderer holds after a frame
    }
    const double tile_mib = 4.0, pyramid_mib = 7.0;
    CAPTURE(mib, held);
    CHECK(mib > tile_mib + pyramid_mib);
    // The estimate against what is allocated (glibc's count; 0 where it is not known): the tile
    // and 4/3 of it in levels are held after the frame, the estimate counts the pyramid's peak
    // of 7/4 and the CLI's output buffers; within a factor 1.25 either way (measured: 0.9).
    if (held > 0) {
        CHECK(held < 1.25 * mib);
        CHECK(held > mib / 1.25);
    }
    auto with_limit = [&](double limit) {
        std::ostringstream s;
        s << std::setprecision(17) << "limits.max_memory_mib=" << limit;
        return scenes::load_scene_string(text, "m.toml", {s.str()});
    };
    // Just under the estimate: refused in one line naming the sources' share; just over: drawn.
    try {
        scenes::Renderer r(with_limit(mib * 0.999));
        FAIL("not refused");
    } catch (const BudgetError& e) {
        CHECK_THAT(e.what(), Catch::Contains("MiB of it the source layers' tiles, pyramids and buffers"));
        CHECK(std::string(e.what()).find('\n') == std::string::npos);
    }
    scenes::Renderer r(with_limit(mib * 1.001));
    render::Frame out;
    CHECK_NOTHROW(r.render(0, out));
    // An orthographic camera builds no pyramid.
    const std::string flat = "[output]\nsize = [64, 64]\n[[layer]]\nsource = \"fbm\"\n"
                             "[layer.fbm]\nmethod = \"fourier\"\nsamples = 1024\n";
    const double flat_mib = scenes::Renderer(scenes::load_scene_string(flat, "f.toml")).estimated_memory_mib();
    CHECK(mib - flat_mib > pyramid_mib);
}
