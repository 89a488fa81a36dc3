// SPDX-License-Identifier: Apache-2.0
// impulse_bench_persp_accuracy: a perspective scene's frame against its supersampled reference,
// per band of rows from near to the horizon (issue 19 item 6). The reference is the same scene
// rendered unfiltered (camera.antialias = "off") at `samples` x `samples` pixels per pixel and
// filtered with the product's own pixel filter, a Gaussian of camera.filter pixels, sampled at
// the pixel centres. Per band: the RMSE of the frame against the reference over the band's
// standard deviation (bound 0.1) and over the texture's (closed form, scenes::scene_theory; the
// fade's promise where a band is nearly flat: 2 x cut-off). See bench/README.md.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"

namespace {

using namespace impulse;

struct Options {
    std::string scene;
    int width = 240, height = 135, samples = 16, bands = 8;
    int64_t frame = 0;
    std::vector<std::string> sets;
};

[[noreturn]] void usage_error(const std::string& m) {
    throw std::invalid_argument(m + " (usage: impulse_bench_persp_accuracy SCENE [--size WxH] "
                                    "[--samples N] [--bands N] [--frame F] [--set KEY=VALUE]...)");
}

int positive(const std::string& flag, const std::string& v, int hi) {
    const int n = std::atoi(v.c_str());
    if (n < 1 || n > hi)
        usage_error(flag + " " + v + ": expected an integer in [1, " + std::to_string(hi) + "]");
    return n;
}

Options parse_args(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) usage_error(std::string(a) + ": missing value");
            return argv[++i];
        };
        if (a == "--size") {
            const std::string v = value();
            if (std::sscanf(v.c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 8 ||
                o.height < 8 || o.width > 2048 || o.height > 2048)
                usage_error("--size " + v + ": expected WxH in [8, 2048]^2");
        } else if (a == "--samples")
            o.samples = positive("--samples", value(), 32);
        else if (a == "--bands")
            o.bands = positive("--bands", value(), 64);
        else if (a == "--frame")
        {
            const std::string v = value();
            const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), o.frame);
            if (ec != std::errc() || end != v.data() + v.size() || o.frame < 0)
                usage_error("--frame " + v + ": expected an integer >= 0");
        }
        else if (a == "--set")
            o.sets.push_back(value());
        else if (!a.empty() && a[0] != '-' && o.scene.empty())
            o.scene = std::string(a);
        else
            usage_error(std::string(a) + ": unknown argument");
    }
    if (o.scene.empty()) usage_error("missing scene");
    return o;
}

/// Normalised Gaussian weights of standard deviation `sd` (samples) at the `n` samples that
/// cover one pixel's filter: sample k of pixel i sits at n i + k + 0.5 in sample units, the
/// pixel centre at n (i + 0.5). Truncated at 5 sd.
struct Taps {
    int reach = 0;  ///< samples each side of the pixel's n samples
    std::vector<double> w;
};

Taps gaussian_taps(double sd, int n) {
    Taps t;
    t.reach = static_cast<int>(std::ceil(5.0 * sd));
    double sum = 0.0;
    for (int k = -t.reach; k < n + t.reach; ++k) {
        const double d = k + 0.5 - 0.5 * n;
        t.w.push_back(std::exp(-0.5 * d * d / (sd * sd)));
        sum += t.w.back();
    }
    for (double& w : t.w) w /= sum;
    return t;
}

/// The supersampled frame filtered and sampled at the W x H pixel centres (separable; edge
/// samples clamped).
std::vector<double> filtered(const render::Frame& ss, int W, int H, int n, const Taps& t) {
    const int SW = ss.width, SH = ss.height;
    std::vector<double> rows(size_t(SH) * W, 0.0), out(size_t(W) * H, 0.0);
    for (int y = 0; y < SH; ++y)
        for (int i = 0; i < W; ++i) {
            double s = 0.0;
            for (size_t k = 0; k < t.w.size(); ++k) {
                const int x = std::clamp(n * i - t.reach + static_cast<int>(k), 0, SW - 1);
                s += t.w[k] * ss.data[size_t(y) * SW + x];
            }
            rows[size_t(y) * W + i] = s;
        }
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double s = 0.0;
            for (size_t k = 0; k < t.w.size(); ++k) {
                const int y = std::clamp(n * j - t.reach + static_cast<int>(k), 0, SH - 1);
                s += t.w[k] * rows[size_t(y) * W + i];
            }
            out[size_t(j) * W + i] = s;
        }
    return out;
}

/// Bands of equal rows over the rows whose centre column sees the plane, nearest first
/// ([first, second) rows).
std::vector<std::pair<int, int>> depth_bands(const render::PerspectiveView& view, int count) {
    const int W = view.camera().width, H = view.camera().height;
    const double cx = view.camera().x, cy = view.camera().y;
    std::vector<std::pair<double, int>> seen;  // distance from the foot, row
    for (int j = 0; j < H; ++j) {
        double x, y;
        if (view.texture_point(0.5 * W, j + 0.5, x, y)) seen.emplace_back(std::hypot(x - cx, y - cy), j);
    }
    if (seen.empty()) throw std::runtime_error("the centre column does not see the plane");
    const bool near_at_top = seen.front().first < seen.back().first;
    const int a = seen.front().second, b = seen.back().second + 1;  // rows [a, b)
    std::vector<std::pair<int, int>> bands;
    for (int k = 0; k < count; ++k) {
        const int r0 = a + (b - a) * k / count, r1 = a + (b - a) * (k + 1) / count;
        bands.emplace_back(r0, r1);
    }
    if (!near_at_top) std::reverse(bands.begin(), bands.end());
    return bands;
}

void run(const Options& o) {
    const std::string path = scenes::resolve_scene(o.scene);
    const scenes::Scene ours = scenes::load_scene(path, o.sets, {o.width, o.height});
    std::vector<std::string> ref_sets = o.sets;
    ref_sets.push_back("camera.antialias=\"off\"");
    const scenes::Scene ref =
        scenes::load_scene(path, ref_sets, {o.width * o.samples, o.height * o.samples});
    if (ours.camera.type != scenes::CameraConfig::Type::Perspective)
        throw std::runtime_error(o.scene + ": not a perspective camera");
    const double t = ours.frame_time(o.frame);
    render::Frame a, r;
    scenes::Renderer(ours).render(o.frame, a);
    scenes::Renderer(ref).render(o.frame, r);
    const double filter = ours.camera.filter, cutoff = ours.camera.cutoff;
    const std::vector<double> rf =
        filtered(r, o.width, o.height, o.samples, gaussian_taps(filter * o.samples, o.samples));
    const double sd0 = std::sqrt(scenes::scene_theory(ours, t).variance);
    const render::PerspectiveView view(ours.camera.perspective(o.width, o.height, t));
    std::printf("%s frame %lld at %dx%d against %dx%d supersampled, unfiltered, Gaussian filter "
                "%.2f px; cut-off %.3g, texture sd %.4g (closed form)\n",
                o.scene.c_str(), static_cast<long long>(o.frame), o.width, o.height, o.samples,
                o.samples, filter, cutoff, sd0);
    for (const std::string& s : o.sets) std::printf("  --set %s\n", s.c_str());
    std::printf("%5s %9s %10s %10s %12s %12s %s\n", "band", "rows", "ref sd", "rmse", "rmse/band sd",
                "rmse/tex sd", "bound (0.1 band sd or 2 x cut-off tex sd)");
    const auto bands = depth_bands(view, o.bands);
    for (size_t b = 0; b < bands.size(); ++b) {
        double se = 0, s1 = 0, s2 = 0;
        size_t n = 0;
        for (int j = bands[b].first; j < bands[b].second; ++j)
            for (int i = 0; i < o.width; ++i) {
                const size_t p = size_t(j) * o.width + i;
                const double d = a.data[p] - rf[p];
                se += d * d, s1 += rf[p], s2 += rf[p] * rf[p], ++n;
            }
        if (n == 0) continue;
        const double rmse = std::sqrt(se / n);
        const double sd = std::sqrt(std::max(0.0, s2 / n - (s1 / n) * (s1 / n)));
        const bool ok = rmse <= 0.1 * sd || rmse <= 2.0 * cutoff * sd0;
        std::printf("%5zu %4d-%-4d %10.4g %10.4g %12.3f %12.4f %s\n", b, bands[b].first,
                    bands[b].second, sd, rmse, rmse / sd, rmse / sd0, ok ? "PASS" : "MISS");
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        run(parse_args(argc, argv));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "impulse_bench_persp_accuracy: %s\n", e.what());
        return 1;
    }
    return 0;
}
