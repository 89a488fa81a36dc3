// SPDX-License-Identifier: Apache-2.0
// impulse_bench_blur: the cost of motion blur (docs/motion_blur.md) on the default scene
// (`drift`, 1920x1080, 30 fps), side by side in one run: sequential frames rendered by one
// scenes::Renderer without a shutter and with `camera.shutter = 0.5` (a 180-degree shutter,
// centred), the median frame time of each (with min and max) and their ratio (target <= 1.5x).
// Both renderers step the same frames forward, alternating frame by frame so machine load
// falls on both alike. See bench/README.md ("impulse_bench_blur").

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/common.h"
#include "render/render.h"
#include "scenes/scenes.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

constexpr double kTargetRatio = 1.5;  ///< blurred frame <= 1.5x the unblurred one

}  // namespace

int main(int argc, char** argv) {
    const int frames = argc > 1 ? std::atoi(argv[1]) : 20;
    const std::string error = argc > 2 ? argv[2] : "0.001";  // camera.shutter_error
    if (frames < 1) {
        std::fprintf(stderr, "usage: impulse_bench_blur [FRAMES >= 1 [SHUTTER_ERROR]]\n");
        return 2;
    }
    const std::string path = scenes::resolve_scene("drift");
    scenes::Renderer sharp(scenes::load_scene(path));
    scenes::Renderer blurred(
        scenes::load_scene(path, {"camera.shutter=0.5", "camera.shutter_error=" + error}));
    render::Frame f;
    sharp.render(0, f);  // the first frame integrates from birth: not timed
    blurred.render(0, f);
    std::vector<double> a, b;
    for (int i = 1; i <= frames; ++i) {
        auto t0 = Clock::now();
        sharp.render(i, f);
        a.push_back(ms_since(t0));
        t0 = Clock::now();
        blurred.render(i, f);
        b.push_back(ms_since(t0));
    }
    const Stats sa = summarise(a), sb = summarise(b);
    std::printf("impulse_bench_blur: drift 1920x1080, frames 1-%d sequential (load %s)\n", frames,
                loadavg().c_str());
    std::printf("%-28s %s ms\n", "shutter 0 (unblurred)", cell(sa).c_str());
    std::printf("%-28s %s ms\n", ("shutter 0.5, error " + error).c_str(), cell(sb).c_str());
    const double ratio = sb.med / sa.med;
    std::printf("ratio                        %.2fx (target <= %.1fx): %s\n", ratio, kTargetRatio,
                ratio <= kTargetRatio ? "met" : "missed");
    return 0;
}
