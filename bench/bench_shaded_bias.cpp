// SPDX-License-Identifier: Apache-2.0
// impulse_bench_shaded_bias: the bias of a scene's shaded frame against its supersampled shaded
// reference, per band of rows, with filtering after shading and without (issue 35 item 4;
// docs/shading.md "Measuring the bias"). The reference is the frame rendered unfiltered at
// `samples` x `samples` pixels per pixel, every sample shaded, filtered with the camera's
// Gaussian pixel filter (tests/shaded_bias.h). `--cost R`: instead, the cost of the remedy on a
// frame of the scene's own size: R times the render and the shading into the video encoder's
// YUV 4:2:0 planes with and without, medians. See bench/README.md.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/common.h"
#include "scenes/scenes.h"
#include "tests/shaded_bias.h"

namespace {

using namespace impulse;

struct Options {
    std::string scene;
    int width = 64, height = 36, samples = 16, bands = 8, cost = 0;
    int64_t frame = 0;
    std::vector<std::string> sets;
};

/// The arguments; a flag of the table below takes an integer in its range.
Options parse_args(int argc, char** argv) {
    Options o;
    struct Flag {
        const char* name;
        int* value;
        int lo, hi;
    } flags[] = {{"--samples", &o.samples, 1, 32}, {"--bands", &o.bands, 1, 64},
                 {"--cost", &o.cost, 1, 99}, {"--frame", nullptr, 0, 1 << 30}};
    const std::string usage = " (usage: impulse_bench_shaded_bias SCENE [--size WxH] [--samples N] "
                              "[--bands N] [--frame F] [--cost R] [--set KEY=VALUE]...)";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const std::string v = i + 1 < argc ? argv[i + 1] : "";
        const Flag* flag = nullptr;
        for (const Flag& f : flags)
            if (a == f.name) flag = &f;
        if (flag) {
            const long n = std::strtol(v.c_str(), nullptr, 10);
            if (v.empty() || v.find_first_not_of("0123456789") != std::string::npos || n < flag->lo || n > flag->hi)
                throw std::invalid_argument(a + " " + v + ": expected an integer in [" + std::to_string(flag->lo) +
                                            ", " + std::to_string(flag->hi) + "]" + usage);
            flag->value ? void(*flag->value = int(n)) : void(o.frame = n);
            ++i;
        } else if (a == "--size" && std::sscanf(v.c_str(), "%dx%d", &o.width, &o.height) == 2 &&
                   std::min(o.width, o.height) >= 8 && std::max(o.width, o.height) <= 2048) {
            ++i;
        } else if (a == "--set" && !v.empty()) {
            o.sets.push_back(v), ++i;
        } else if (!a.empty() && a[0] != '-' && o.scene.empty()) {
            o.scene = a;
        } else {
            throw std::invalid_argument(a + (a == "--size" ? " " + v + ": expected WxH in [8, 2048]^2" : ": unknown argument") + usage);
        }
    }
    if (o.scene.empty()) throw std::invalid_argument("missing scene" + usage);
    return o;
}

double seconds_since(bench::Clock::time_point t0) { return bench::ms_since(t0) / 1000.0; }

/// The remedy's cost on a frame of the scene's own size: the render, and the shading at the
/// frame time (Scene::shading_at, the Shader's tables, Shader::rows_yuv420 over the frame: what
/// `impulse render` does per video frame) with filter "after" and "before", interleaved.
void cost(const Options& o, const std::string& path) {
    scenes::Renderer r(scenes::load_scene(path, o.sets));
    const scenes::Scene& sc = r.scene();
    const int W = sc.output.width & ~1, H = sc.output.height & ~1;
    std::vector<uint8_t> y(size_t(W) * H), cb(size_t(W / 2) * (H / 2)), cr(cb.size());
    const output::Yuv420Planes planes{y.data(), cb.data(), cr.data(), W, W / 2, W / 2};
    std::vector<double> render_s, after_s, before_s, sd_s, tables_s;
    render::Frame f;
    for (int k = 0; k < o.cost; ++k) {
        auto t0 = bench::Clock::now();
        r.render(o.frame, f);
        render_s.push_back(seconds_since(t0));
        for (const bool after : {true, false}) {
            t0 = bench::Clock::now();
            scenes::Scene switched = sc;
            switched.shading.filter_after = after;
            const output::Shading s = switched.shading_at(sc.frame_time(o.frame));
            if (after) sd_s.push_back(seconds_since(t0));
            const output::Shader shader(r.mapping(), s);
            if (after) tables_s.push_back(seconds_since(t0) - sd_s.back());
            shader.rows_yuv420(f, 0, H, planes);
            (after ? after_s : before_s).push_back(seconds_since(t0));
        }
    }
    const double rm = bench::summarise(render_s).med, am = bench::summarise(after_s).med,
                 bm = bench::summarise(before_s).med;
    std::printf("%s frame %lld at %dx%d, %d runs, medians: render %.3f s, shading with filter "
                "\"after\" %.4f s, \"before\" %.4f s; frame cost ratio (render + after) / "
                "(render + before) = %.3f\n",
                o.scene.c_str(), static_cast<long long>(o.frame), sc.output.width,
                sc.output.height, o.cost, rm, am, bm, (rm + am) / (rm + bm));
    std::printf("  of \"after\": Scene::shading_at (the sub-pixel sd) %.4f s, the Shader's tables "
                "%.4f s, the rows %.4f s (medians)\n",
                bench::summarise(sd_s).med, bench::summarise(tables_s).med,
                am - bench::summarise(sd_s).med - bench::summarise(tables_s).med);
}

void run(const Options& o) {
    const std::string path = scenes::resolve_scene(o.scene);
    if (o.cost > 0) return cost(o, path);
    const scenes::Renderer coarse(scenes::load_scene(path, o.sets, {o.width, o.height}));
    const std::vector<double> ref = test::shaded_reference(path, o.sets, o.width, o.height,
                                                           o.samples, o.frame, coarse.mapping());
    const test::ShadedBias after =
        test::shaded_bias(path, o.sets, o.width, o.height, o.frame, ref, true, o.bands);
    const test::ShadedBias before =
        test::shaded_bias(path, o.sets, o.width, o.height, o.frame, ref, false, o.bands);
    std::printf("%s frame %lld at %dx%d against %dx%d samples per pixel shaded and filtered "
                "(Gaussian, camera.filter %.2f px); luma, in units of the band's reference sd; "
                "averaged ramp: %d tables by row (0: one for the frame, or none), their interpolation "
                "error <= %.2g\n",
                o.scene.c_str(), static_cast<long long>(o.frame), o.width, o.height, o.samples,
                o.samples, coarse.scene().camera.filter, after.levels, after.level_error);
    for (const std::string& s : o.sets) std::printf("  --set %s\n", s.c_str());
    std::printf("%5s %9s %9s %13s %11s %13s %11s %9s\n", "band", "rows", "ref sd", "bias before",
                "rms before", "bias after", "rms after", "bias se");
    for (size_t b = 0; b < after.bands.size(); ++b) {
        const test::ShadedBand &a = after.bands[b], &z = before.bands[b];
        std::printf("%5zu %4d-%-4d %9.4f %13.3f %11.3f %13.3f %11.3f %9.3f\n", b, a.row0, a.row1,
                    a.ref_sd, z.bias, z.rms, a.bias, a.rms, a.bias_se);
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        run(parse_args(argc, argv));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "impulse_bench_shaded_bias: %s\n", e.what());
        return 1;
    }
    return 0;
}
