// SPDX-License-Identifier: Apache-2.0
// impulse_bench_compose: the cost of composing layers (issue "scene language", composition):
// 1920x1080 frames of scenes that blend, warp, orient and flow layers by other layers, each
// against the scene without that feature, rendered side by side (every variant once per
// repetition, in turn) through scenes::Renderer with 2 threads. Figures are the median
// [min-max] over the repetitions after an untimed warm-up. See bench/README.md.

#include <tbb/task_arena.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "bench/common.h"
#include "render/render.h"
#include "scenes/scenes.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

/// Two hidden broad layers (sources), then A (cosine, r 16) and B (gabor, r 16); `b_keys` are
/// B's extra keys, `b_kernel` its extra kernel keys; `animated`: A and B live 2 s.
std::string scene(const std::string& b_keys, const std::string& flow = "",
                  const std::string& b_kernel = "", bool animated = false) {
    const std::string life = animated ? "lifetime = 2.0\n" : "";
    return R"([output]
size = [1920, 1080]
frames = 1000
[[layer]]
name = "wx"
visible = false
seed = 11
[layer.kernel]
radius = 96.0
[[layer]]
name = "wy"
visible = false
seed = 12
[layer.kernel]
radius = 96.0
[[layer]]
seed = 3
)" + life + R"([layer.kernel]
radius = 16.0
[[layer]]
seed = 4
)" + life + b_keys + "\n[layer.kernel]\ntype = \"gaussian\"\nradius = 16.0\nsigma = 5.0\n" +
           b_kernel + flow;
}

struct Row {
    std::string name, reference;  ///< the row it is compared with ("" for a reference)
    std::string text;
    bool animated = false;
    std::unique_ptr<scenes::Renderer> renderer;
    std::vector<double> ms;
};

}  // namespace

int main(int argc, char** argv) try {
    int reps = 7;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        if (a == "--quick")
            reps = 3;
        else if (a == "--reps" && i + 1 < argc)
            reps = std::max(1, std::atoi(argv[++i]));
        else
            throw std::invalid_argument(std::string(a) + ": usage: impulse_bench_compose [--quick] [--reps N]");
    }
    const std::string curl = "[[layer.flow]]\ntype = \"curl\"\nscale = 96.0\nspeed = 30.0\n";
    const std::string stream = "[[layer.flow]]\ntype = \"layer\"\nsource = \"wx\"\nspeed = 30.0\n";
    std::vector<Row> rows;
    rows.push_back({"sum", "", scene("")});
    rows.push_back({"multiply", "sum", scene("blend = \"multiply\"")});
    rows.push_back({"over, alpha", "sum", scene("blend = \"over\"\nalpha = [-1.0, 1.0]")});
    rows.push_back({"max, opacity 0.5", "sum", scene("blend = \"max\"\nopacity = 0.5")});
    rows.push_back({"warp 16", "sum", scene("warp = { source = [\"wx\", \"wy\"], amount = 16.0 }")});
    rows.push_back({"aspect 3 fixed", "", scene("", "", "aspect = 3.0\n")});
    rows.push_back({"aspect 3 circular", "aspect 3 fixed",
                    scene("orientation = { type = \"circular\", center = [960.0, 540.0] }", "",
                          "aspect = 3.0\n")});
    rows.push_back({"aspect 3 by layer", "aspect 3 circular",
                    scene("orientation = { type = \"layer\", source = \"wx\" }", "", "aspect = 3.0\n")});
    rows.push_back({"curl flow", "", scene("", curl, "", true), true});
    rows.push_back({"layer flow", "curl flow", scene("", stream, "", true), true});
    tbb::task_arena arena(2);
    render::Frame out;
    arena.execute([&] {
        for (auto& r : rows) {
            r.renderer = std::make_unique<scenes::Renderer>(scenes::load_scene_string(r.text, r.name));
            r.renderer->render(0, out);  // warm-up (and the sequential state of animated rows)
        }
        for (int rep = 1; rep <= reps; ++rep)
            for (auto& r : rows) {
                const auto t0 = Clock::now();
                r.renderer->render(r.animated ? rep : 0, out);
                r.ms.push_back(ms_since(t0));
            }
    });
    std::printf("1920x1080, 2 threads, %d repetitions; load average before: %s\n", reps,
                loadavg().c_str());
    std::printf("%-20s %-22s %-8s %s\n", "row", "ms per frame", "ratio", "against");
    for (const auto& r : rows) {
        const Stats s = summarise(r.ms);
        double ratio = 1.0;
        for (const auto& ref : rows)
            if (ref.name == r.reference) ratio = s.med / summarise(ref.ms).med;
        std::printf("%-20s %-22s %-8.2f %s\n", r.name.c_str(), cell(s).c_str(), ratio,
                    r.reference.empty() ? "-" : r.reference.c_str());
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
}
