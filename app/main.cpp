// SPDX-License-Identifier: Apache-2.0
// The `impulse` command-line tool: parse, call the libraries, report. Library errors are typed
// exceptions; here they become one line on stderr and a non-zero exit (style.md "Errors").


#include <CLI/CLI.hpp>
#include <iostream>

#include "app/analyze.h"
#include "app/commands.h"
#include "app/synth_fbm.h"
#include "util/errors.h"

int main(int argc, char** argv) {
    CLI::App app{
        "impulse: animated, anti-aliased procedural textures from Lewis's shaped Poisson point\n"
        "process (sparse convolution noise) treated as a particle system."};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Show help for every command");

    impulse::app::RenderOptions ro;
    CLI::App* render = app.add_subcommand("render", "Render a scene to an image, an image sequence or a video");
    render->add_option("scene", ro.scene, "Scene file (TOML) or built-in scene name (see `impulse scenes`)")
        ->required();
    render->add_option("-o,--output", ro.output,
                       "Output: one image (.exr .png .tif), a sequence pattern (frame_####.png or "
                       "frame_%04d.exr), or a video (.mp4 .mov .mkv .webm)")
        ->required();
    render->add_option("--frames", ro.frames, "Inclusive 0-based frame range A-B, or one frame A (default: all)");
    render->add_option("--size", ro.size, "Override output.size as WxH, e.g. 1920x1080");
    render->add_option("--seed", ro.seed, "Scene-wide seed mixed into every layer's seed");
    render->add_option("--set", ro.sets, "Override any scene key by dotted path, e.g. layer.0.kernel.radius=8")
        ->allow_extra_args(false);
    render->add_option("--threads", ro.threads, "Worker threads (default: all cores); output does not depend on it")
        ->check(CLI::Range(1, 1024));
    render->add_option("--tile", ro.tile, "Tile size in pixels (default 128); output does not depend on it")
        ->check(CLI::Range(8, 4096));
    render->add_option("--codec", ro.codec, "Video codec: auto, h264, prores, ffv1, vp9 (overrides output.codec)");
    render->add_flag("--resume", ro.resume, "Image sequences: skip frames whose files already exist");
    render->add_flag("-q,--quiet", ro.quiet, "No progress display");

    CLI::App* scenes = app.add_subcommand("scenes", "List the built-in scenes");

    impulse::app::InfoOptions io;
    CLI::App* info = app.add_subcommand("info", "Print a scene's closed-form statistics and cost estimate");
    info->add_option("scene", io.scene, "Scene file or built-in name")->required();
    info->add_option("--set", io.sets, "Override a scene key");
    info->add_option("--size", io.size, "Override output.size as WxH");

    impulse::app::AnalyzeOptions ao;
    CLI::App* analyze = app.add_subcommand(
        "analyze", "Measure an image, sequence or video; with --scene, compare with its theory");
    analyze->add_option("input", ao.input,
                        "One image, a sequence pattern (frame_####.exr, frame_%04d.png) or a video")
        ->required();
    analyze->add_option("--scene", ao.scene, "Scene file or built-in name to compare with");
    analyze->add_option("--set", ao.sets, "Override a scene key (with --scene)");
    analyze->add_flag("--json", ao.json, "Print one JSON object instead of text");
    analyze->add_flag("--structure", ao.structure,
                      "Structure function along x, y, diagonal and the generalised Hurst "
                      "exponent H(s) (with its band over frames)");
    analyze->add_option("--variance-map", ao.variance_map,
                        "Write the per-pixel variance over the frames (realizations) as an image");
    analyze->add_option("--report", ao.report, "Write a self-contained HTML report (plots as SVG)");
    analyze->add_option("--frames", ao.frames, "Inclusive 0-based frame range A-B, or one frame A");
    analyze->add_option("--max-frames", ao.max_frames, "Analyse at most N frames")
        ->check(CLI::PositiveNumber);

    CLI::App* synth = app.add_subcommand("synth", "Synthesize a surface: fractional Brownian motion");
    synth->require_subcommand(1);
    impulse::app::SynthFbmOptions fo;
    CLI::App* synth_fbm = impulse::app::add_synth_fbm(*synth, fo);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    try {
        if (*render) return impulse::app::run_render(ro);
        if (*scenes) return impulse::app::run_scenes();
        if (*info) return impulse::app::run_info(io);
        if (*analyze) return impulse::app::run_analyze(ao);
        if (*synth_fbm) return impulse::app::run_synth_fbm(fo);
    } catch (const impulse::Error& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
