// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the scene loader and the renderer: any bytes must load or fail with
// impulse::Error, and what loads must render or fail with impulse::Error — never crash, hang,
// leak or trip a sanitizer.
//
// Tight budget: a scene asks for its own size and limits, so the target overrides them as
// `--size` and `--set` do (kBudget): every scene renders frames 0 and 1 at 64x48, and one whose
// estimated impulses, memory or perspective pixel evaluations exceed the small limits below is
// refused with BudgetError by the Renderer before any work (scenes/frame/renderer.cpp), so an input
// cannot buy a long run with a large size or density. The memory limit also bounds what is made
// at load, before the Renderer's estimate: the source layers' tiles together (an fbm or
// subdivision field, made as its layer is read: 2 MiB holds one 256^2 incremental fbm surface
// or many 128^2 ones; at 8 MiB the grown corpus's scenes of 7-14 fbm layers synthesized up to
// 512^2 each and ran at 30-50 inputs a second), the caches a flow builds before the first frame
// (a curl-noise or stream-function potential lattice, a node every scale / 8 over the region
// the impulses move in: 2 MiB is ~75 thousand nodes; a mutated curl scale used to build
// lattices of up to 1e8 nodes, seconds under the sanitizers) and a designed kernel's spectral
// grids (47 bytes a node: 2 MiB fits 128^2, not 256^2; a ridges-like design at 2048^2 took
// 10-14 s). The flow-step limit bounds the walk that places a flowing scene's first-frame
// impulses (each moved from its birth, ~3.5 us a step under the sanitizers: 50 000 steps is
// ~0.2 s; a clouds-like scene needs 3e7).
// Keep it at >= 100 executions a second.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "render/render.h"
#include "kernels/pyramid.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace {

const std::vector<std::string> kBudget = {
    "output.size=[64, 48]",
    "limits.max_impulses=20000",
    "limits.max_memory_mib=2",
    "limits.max_pixel_evaluations=2000000",
    "limits.max_flow_steps=50000",
};

/// Whether rendering fits the budget beyond what the limits bound: an anti-aliased camera
/// builds a kernel pyramid per layer, and for a kernel that is not radially symmetric its levels
/// are grids of up to 257 x 257 samples, each filtered separably (~3e7 products per level, up to
/// ~20 levels): seconds under the sanitizers. Such scenes are loaded and their theory computed,
/// but not rendered (the perspective and pyramid tests render them).
bool render_within_budget(const impulse::scenes::Scene& s) {
    if (s.camera.type != impulse::scenes::CameraConfig::Type::Perspective &&
        !s.camera.antialiased())
        return true;
    for (const auto& layer : s.layers)
        if (!impulse::kernels::is_radial(impulse::kernels::Kernel(layer.kernel))) return false;
    return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    try {
        impulse::scenes::Scene s = impulse::scenes::load_scene_string(text, "fuzz.toml", kBudget);
        (void)impulse::scenes::scene_theory(s);
        if (!render_within_budget(s)) return 0;
        impulse::scenes::Renderer renderer(std::move(s));
        impulse::render::Frame frame;
        renderer.render(0, frame);
        renderer.render(1, frame);
    } catch (const impulse::Error&) {
    }
    return 0;
}
