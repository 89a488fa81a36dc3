// SPDX-License-Identifier: Apache-2.0
// `impulse scenes` (the built-in scenes) and `impulse info` (a scene's closed-form statistics and
// cost estimate).

#include "app/commands.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/scenes.h"

namespace impulse::app {

int run_scenes() {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(scenes::builtin_scene_dir(), ec))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& p : files) {
        // A scene file opens with a comment paragraph; its first sentence describes it.
        std::ifstream in(p);
        std::string line, text;
        while (std::getline(in, line) && line.rfind("#", 0) == 0)
            text += (text.empty() ? "" : " ") + line.substr(line.find_first_not_of("# ") == std::string::npos
                                                               ? line.size()
                                                               : line.find_first_not_of("# "));
        const size_t stop = text.find(". ");
        if (stop != std::string::npos) text.resize(stop + 1);
        // "clouds: wind-blown ..." and "Drift: flowing ..." name the scene again.
        const std::string stem = p.stem().string();
        if (text.size() > stem.size() + 1 && text[stem.size()] == ':' &&
            std::equal(stem.begin(), stem.end(), text.begin(),
                       [](char a, char b) { return std::tolower(a) == std::tolower(b); }))
            text = text.substr(text.find_first_not_of(' ', stem.size() + 1));
        // A volume scene ([volume]: impulses in 3-D, OpenVDB out) says so on its line.
        in.clear();
        in.seekg(0);
        bool is_volume = false;
        while (std::getline(in, line)) is_volume = is_volume || line.rfind("[volume]", 0) == 0;
        std::printf("%-10s %s%s\n", stem.c_str(), is_volume ? "(volume) " : "", text.c_str());
    }
    return 0;
}

namespace {

/// A layer's composition for `impulse info`: what differs from a plainly added layer.
std::string composition_text(const scenes::LayerConfig& l) {
    const scenes::Composition& c = l.compose;
    std::ostringstream s;
    if (!c.name.empty()) s << " name=\"" << c.name << "\"";
    if (!c.visible) s << " hidden";
    if (c.blend != scenes::Blend::Add) s << " blend=" << scenes::kBlendNames[size_t(c.blend)];
    if (!c.opacity.is_constant())
        s << " opacity=keyframed";
    else if (c.opacity.value(0.0) != 1.0)
        s << " opacity=" << c.opacity.value(0.0);
    if (c.warp)
        s << " warp=layer[" << c.warp->source[0] << "],layer[" << c.warp->source[1] << "]";
    if (c.orientation) s << " orientation=layer[" << c.orientation->source << "]";
    for (size_t j : c.flow_sources) s << " flow=layer[" << j << "]";
    return s.str();
}

}  // namespace

namespace {

/// `impulse info` of a volume scene: sizes, the Campbell variance of the unshaped field per
/// octave, the impulse estimate.
int print_volume_info(const scenes::Scene& scene) {
    const scenes::VolumeSceneConfig& v = *scene.volume;
    const volume::CloudVolume cloud(v.cloud);
    const volume::CloudTheory t = cloud.theory();
    const long long nframes = scene.output.frames;
    std::printf("scene      %s (hash %s)\n", scene.path.c_str(), scene.hash.c_str());
    std::printf("output     %dx%d, %lld frame%s at %g fps (preview; volume %dx%dx%d voxels)\n",
                scene.output.width, scene.output.height, nframes, nframes == 1 ? "" : "s",
                scene.output.fps, v.cloud.size[0], v.cloud.size[1], v.cloud.size[2]);
    std::printf("volume     %d octave%s from r=%g, density=%g per kernel volume, lifetime %g s, "
                "sqrt(J) %s\n", v.cloud.octaves, v.cloud.octaves == 1 ? "" : "s",
                v.cloud.kernel.radius, v.cloud.density, v.cloud.lifetime_s,
                v.cloud.jacobian ? "on" : "off");
    if (v.cloud.aspect != 1.0 || v.cloud.orientation != sim::OrientationMode::Fixed)
        std::printf("kernel     aspect %g (int h^2 and the variance x %g), orientation %s%s\n",
                    v.cloud.aspect, v.cloud.aspect,
                    std::string(sim::kOrientationModeNames[size_t(v.cloud.orientation)]).c_str(),
                    v.cloud.aspect == 1.0 ? " (a radial kernel: no effect)" : "");
    std::printf("variance   %.6g (Campbell's theorem, the field before shaping)\n", t.variance);
    for (size_t o = 0; o < t.octave_variance.size(); ++o)
        std::printf("octave[%zu]  variance=%.6g\n", o, t.octave_variance[o]);
    std::printf("impulses   ~%.3g per frame\n", cloud.expected_impulses());
    return 0;
}

}  // namespace

/// `impulse info`'s motion blur line for impulse layer i (docs/motion_blur.md): the travel over
/// the shutter, the variance factor, the copies and the sub-stepping's error bound.
static void print_motion_blur(const scenes::Scene& scene, size_t i) {
    const scenes::MotionBlur m = scenes::layer_motion_blur(scene, i);
    if (m.paths.empty()) return;
    const auto& l = scene.layers[i];
    const kernels::Kernel k(l.kernel);
    const sim::Shutter sh = scene.camera.shutter_at(scene.output.fps, kernels::kernel_curvature(k));
    double travel = 0.0;
    for (const auto& b : m.paths) travel = std::max(travel, std::hypot(b[0], b[1]));
    int copies = 1;
    while (copies < sh.max_samples && travel > sh.max_step * copies) copies *= 2;
    std::printf("           motion blur: travel up to %.3g units over the shutter, variance x %.4g; "
                "up to %d cop%s (%.3g units apart at most), each impulse within %.3g of its peak\n",
                travel, m.variance_factor(k), copies, copies == 1 ? "y" : "ies", sh.max_step,
                scene.camera.shutter_error);
}

int run_info(const InfoOptions& opt) {
    const std::string path = scenes::resolve_scene(opt.scene);
    scenes::Scene scene = scenes::load_scene(path, overrides_for(opt.sets, opt.crop, ""),
                                             parse_size("--size", opt.size));
    for (const auto& w : scene.warnings) std::cerr << w << "\n";
    if (scene.volume) return print_volume_info(scene);
    scenes::Renderer r(scene);
    const auto t = scenes::scene_theory(scene);
    std::printf("scene      %s (hash %s)\n", path.c_str(), scene.hash.c_str());
    const long long nframes = scene.output.frames;
    std::printf("output     %dx%d, %lld frame%s at %g fps\n", scene.output.width, scene.output.height,
                nframes, nframes == 1 ? "" : "s", scene.output.fps);
    bool keyframed = false;
    bool sources = false;  // layers drawn by another synthesizer state their own theory
    for (const auto& l : scene.layers) keyframed = keyframed || l.keyframed(), sources = sources || l.source;
    std::printf("mean       %.6g\nvariance   %.6g (%s%s)\n", t.mean, t.variance,
                scenes::is_sum_of_layers(scene) ? (sources ? "each layer's closed form, summed" : "Campbell's theorem")
                : sources ? "each layer's closed form, composed: docs/scenes.md \"Composition\""
                          : "Campbell's theorem, layers composed: docs/scenes.md \"Composition\"",
                keyframed ? ", at t = 0: layers are keyframed" : "");
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const auto& l = scene.layers[i];
        const auto lt = scenes::layer_theory(l);
        if (l.source) {  // another synthesizer's field (scenes/source.h)
            std::printf("layer[%zu]   %s source, mean=%.6g variance=%.6g%s%s\n", i,
                        std::string(l.source->kind()).c_str(), lt.mean, lt.variance,
                        l.keyframed() ? " (keyframed)" : "", composition_text(l).c_str());
            continue;
        }
        std::printf("layer[%zu]   %s r=%g density=%g lambda=%.4g/unit^2 variance=%.6g%s%s%s\n", i,
                    std::string(kernels::to_string(l.kernel.type)).c_str(), l.kernel.radius,
                    l.density.value(0.0), l.process.intensity, lt.variance,
                    l.process.lifetime_s > 0 ? " (animated)" : " (still)",
                    l.keyframed() ? " (keyframed)" : "", composition_text(l).c_str());
        if (const auto rule = r.lattice(i)) {
            if (rule->spacing > 1)
                std::printf("           lattice h=%d px, predicted rms error %.2g of the layer's sd "
                            "(render.tolerance %g), spectral error %.2g (<= %g)\n",
                            rule->spacing, rule->predicted_error, scene.render.tolerance,
                            rule->spectral_error, render::kSpectralFidelity);
            else if (scene.render.tolerance > 0 && rule->over_memory)
                std::printf("           lattice h=1 px (direct): the rule's quadrature needs more "
                            "than a quarter of limits.max_memory_mib\n");
            else if (scene.render.tolerance > 0 && rule->next_error == 0.0)
                std::printf("           lattice h=1 px (direct): the kernel's radius is under 6 px (a lattice is at most a third of it)\n");
            else if (scene.render.tolerance > 0 && rule->next_error > scene.render.tolerance)
                std::printf("           lattice h=1 px (direct): h=2 would give %.2g of the sd, over "
                            "render.tolerance %g\n",
                            rule->next_error, scene.render.tolerance);
            else if (scene.render.tolerance > 0)
                std::printf("           lattice h=1 px (direct): h=2 would give a frequency %.2g of "
                            "its power in error, over %g (docs/multirate.md §5)\n",
                            rule->next_spectral, render::kSpectralFidelity);
        }
        const auto lm = scenes::layer_moments(l);
        std::printf("           overlap %.3g effective impulses, excess kurtosis %.3g%s\n",
                    lm.effective_impulses, lm.excess_kurtosis,
                    l.marginal ? " before shaping" : "");
        if (l.marginal)
            std::printf("           shaped to %s, F_x %s\n",
                        std::string(kernels::to_string(l.marginal->target().params().type)).c_str(),
                        std::string(kernels::kSourceCdfNames[size_t(l.marginal_cdf)]).c_str());
        print_motion_blur(scene, i);
    }
    if (scene.camera.shutter > 0)
        std::printf("blurred    variance %.6g (each kernel's mean along its path over the shutter: "
                    "docs/motion_blur.md)\n",
                    scenes::blurred_scene_theory(scene).variance);
    std::printf("impulses   ~%.3g per frame, ~%.0f MiB", r.estimated_impulses(), r.estimated_memory_mib());
    if (const double steps = r.estimated_flow_steps(); steps > 0)
        std::printf(", ~%.3g flow steps for the first frame", steps);
    std::printf("\n");
    return 0;
}

}  // namespace impulse::app
