// SPDX-License-Identifier: Apache-2.0
// impulse_bench_channels: the cost of a frame's channels (docs/channels.md) against the field
// alone, on the default scene (`drift`, 1920x1080, five Gaussian octaves in wind + curl noise):
//   1. value alone: scenes::Renderer::render;
//   2. value + dx + dy + motion: scenes::Renderer::render_channels (the field as in 1, the
//      exact derivatives of every layer at every pixel, forward and backward motion vectors);
// interleaved frame by frame over the same frames, process CPU time per frame (both use every
// core: CPU time is what a loaded machine does not inflate). Target: (2) <= 1.5 x (1).
// See bench/README.md ("impulse_bench_channels").

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/common.h"
#include "scenes/scenes.h"

int main(int argc, char** argv) {
    using namespace impulse;
    const int frames = argc > 1 ? std::atoi(argv[1]) : 6;
    scenes::Renderer plain(scenes::load_scene(scenes::resolve_scene("drift")));
    scenes::Renderer with(scenes::load_scene(scenes::resolve_scene("drift")));
    scenes::ChannelSet set;
    set.dx = set.dy = set.motion = true;
    render::Frame f;
    scenes::FrameChannels ch;
    plain.render(0, f);  // the first frame integrates every impulse from birth: not timed
    with.render_channels(0, set, ch);
    std::vector<double> value_ms, channels_ms;
    for (int i = 1; i <= frames; ++i) {
        double t0 = bench::own_cpu_s();
        plain.render(i, f);
        value_ms.push_back(1e3 * (bench::own_cpu_s() - t0));
        t0 = bench::own_cpu_s();
        with.render_channels(i, set, ch);
        channels_ms.push_back(1e3 * (bench::own_cpu_s() - t0));
    }
    const bench::Stats v = bench::summarise(value_ms), c = bench::summarise(channels_ms);
    std::printf("impulse_bench_channels: drift 1920x1080, frames 1-%d, CPU ms a frame, median "
                "[min-max]; load %s\n", frames, bench::loadavg().c_str());
    std::printf("value alone                 %s\n", bench::cell(v).c_str());
    std::printf("value + dx + dy + motion    %s\n", bench::cell(c).c_str());
    std::printf("ratio                       %.2f (target <= 1.5)\n", c.med / v.med);
    return 0;
}
