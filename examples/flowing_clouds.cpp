// SPDX-License-Identifier: Apache-2.0
// Builds a flowing-cloud scene in code — no scene file — and writes it to a video.
//
//   build/examples/flowing_clouds out/clouds_from_code.mp4
//
// Not one of the built-in scenes: a one-layer relative of scenes/drift.toml (flowing clouds
// seen straight up, in wind and curl noise; drift adds a finer second layer, a sky gradient and
// 1080p). It shows the C++ API: fill the configuration structs, call prepare_layer, render
// frames into float buffers, shade, encode.
#include <cstdio>
#include <exception>
#include <string>

#include <impulse/output/output.h>
#include <impulse/render/render.h>
#include <impulse/scenes/scenes.h>

using namespace impulse;

int main(int argc, char** argv) {
    const std::string out = argc > 1 ? argv[1] : "clouds_from_code.mp4";
    try {
        scenes::Scene scene;
        scene.output.width = 960;
        scene.output.height = 540;
        scene.output.frames = 90;
        scene.output.fps = 30;
        scene.camera.center_x = numeric::Keyframed(480.0);
        scene.camera.center_y = numeric::Keyframed(270.0);

        scenes::LayerConfig layer;
        layer.kernel.type = kernels::KernelType::Gaussian;
        layer.kernel.radius = 54.0;
        layer.kernel.sigma = 18.0;
        layer.density = 12.0;
        layer.process.seed = 2026;
        layer.process.lifetime_s = 4.0;  // impulses fade in and out over 4 s (Hann)
        layer.process.substeps = 1;
        auto flow = std::make_shared<sim::FlowSum>();
        flow->push(sim::make_uniform_flow(30.0, 4.0));  // wind, pixels per second
        // Speed rises from 6 to 14 px/s over the clip: any numeric parameter can be keyframed.
        numeric::Keyframed gusts;
        gusts.keys = {{0.0, 6.0}, {3.0, 14.0}};
        gusts.ease = numeric::Ease::Smooth;
        flow->push(sim::make_curl_noise_flow(7, 240.0, gusts, std::nullopt));
        layer.flow = flow;
        scenes::prepare_layer(layer);
        scene.layers.push_back(layer);

        scene.shading.ramp = {{0.0, 1, 1, 1, 0}, {0.45, 1, 1, 1, 0}, {0.8, 1, 1, 1, 1}, {1.0, 1, 1, 1, 1}};

        scenes::Renderer renderer(scene);
        output::VideoOptions vo;
        vo.width = scene.output.width;
        vo.height = scene.output.height;
        vo.fps = scene.output.fps;
        vo.preset = "veryfast";
        output::quiet_video_logs();
        output::VideoWriter video;
        video.open(out, vo);
        render::Frame field;
        std::vector<float> rgb;
        for (int64_t f = 0; f < scene.output.frames; ++f) {
            renderer.render(f, field);  // frame f into a float buffer
            output::shade(field, renderer.mapping(), scene.shading, rgb);
            video.write_frame(rgb.data());
        }
        video.close();
        std::printf("wrote %s (%lld frames)\n", out.c_str(), static_cast<long long>(scene.output.frames));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
