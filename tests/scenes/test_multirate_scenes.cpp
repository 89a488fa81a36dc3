// SPDX-License-Identifier: Apache-2.0
// Multi-rate evaluation in the built-in scenes (docs/multirate.md §5): every built-in scene
// whose field is a plain sum of impulse layers, rendered at the default tolerance, stays within
// the largest predicted per-layer error of its direct evaluation (render.tolerance = 0); its
// lattices are coarser than the pixels where the kernels are wide; the scenes that shape,
// blend or transform their field still agree within a few times that (a smooth map of a field
// off by e sd is off by about |g'| e).

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "render/render.h"
#include "scenes/scenes.h"

namespace fs = std::filesystem;
using namespace impulse;

namespace {

double rms(const render::Frame& a, const render::Frame& b) {
    double s = 0.0;
    for (size_t i = 0; i < a.data.size(); ++i) {
        const double d = double(a.data[i]) - b.data[i];
        s += d * d;
    }
    return std::sqrt(s / double(a.data.size()));
}

bool plain_impulse_sum(const scenes::Scene& s) {
    if (!scenes::is_sum_of_layers(s) || s.transform.type != output::FieldTransform::Type::None)
        return false;
    for (const auto& l : s.layers)
        if (l.source || l.marginal) return false;
    return true;
}

}  // namespace

TEST_CASE("built-in scenes at the default tolerance stay within the predicted error",
          "[scenes][lattice][slow]") {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(fs::path(IMPULSE_SOURCE_DIR) / "scenes"))
        if (e.path().extension() == ".toml") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    int coarse_scenes = 0;
    for (const auto& f : files) {
        const auto probe = scenes::load_scene(f.string());
        if (probe.volume) continue;
        // Half the scene's own size (the same view): fewer pixels, the kernels half as wide in
        // pixels, so the lattices are coarser than at full size only where the kernels allow.
        const scenes::OutputSize half{probe.output.width / 2, probe.output.height / 2};
        const std::vector<std::string> frames = {"output.frames=4"};
        std::vector<std::string> lattice_sets = frames, direct_sets = frames;
        lattice_sets.push_back("render.tolerance=0.005");  // the default, whatever the file says
        direct_sets.push_back("render.tolerance=0");
        scenes::Renderer lattice(scenes::load_scene(f.string(), lattice_sets, half));
        scenes::Renderer direct(scenes::load_scene(f.string(), direct_sets, half));
        double predicted = 0.0;
        int coarse = 0;
        for (size_t i = 0; i < lattice.scene().layers.size(); ++i)
            if (const auto rule = lattice.lattice(i)) {
                predicted = std::max(predicted, rule->predicted_error);
                coarse += rule->spacing > 1;
                CHECK(rule->predicted_error <= lattice.scene().render.tolerance);
            }
        if (coarse == 0) continue;  // perspective, the pyramid, or kernels a few pixels wide
        ++coarse_scenes;
        render::Frame a, b;
        // Frame 3 after 0..2: sequential stepping, as a video renders.
        for (int64_t fr = 0; fr <= 3; ++fr) direct.render(fr, a), lattice.render(fr, b);
        const double sd = std::sqrt(scenes::scene_theory(lattice.scene(), lattice.scene().frame_time(3)).variance);
        const double e = rms(a, b) / sd;
        // The frame's squared error scatters about its expectation with about one independent
        // value per kernel area of the finest octave; the frames hold thousands: 50 % in the rms
        // is far outside that scatter (a wrong reconstruction is off by 10x or more).
        const bool plain = plain_impulse_sum(lattice.scene());
        INFO(f.filename().string() << ": " << coarse << " coarse layers, predicted <= " << predicted
                                   << ", measured " << e << (plain ? " (plain sum)" : " (shaped)"));
        CHECK(e <= (plain ? 1.5 : 4.0) * predicted);
    }
    CHECK(coarse_scenes >= 4);
}
