// SPDX-License-Identifier: Apache-2.0
// The `impulse` command-line tool: parse, call the libraries, report. Library errors are typed
// exceptions; here they become one line on stderr and a non-zero exit
// (docs/contributing.md "Errors").

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string_view>

#include "app/analyze.h"
#include "app/commands.h"
#include "app/encode.h"
#include "app/export.h"
#include "app/farm.h"
#include "app/preview.h"
#include "app/synth_fbm.h"
#include "app/synth_gss.h"
#include "app/synth_solid.h"
#include "numeric/errors.h"

namespace {

/// `impulse mesh ...` and `impulse trajectories ...` run in the companion tool impulse-mesh
/// installed beside this one (app/mesh_main.cpp): they need assimp and OpenVDB, which would
/// otherwise load with every command. Returns only when it cannot be started.
int run_mesh_companion(char** argv) {
    std::error_code ec;
    const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
    const std::string tool = (self.parent_path() / "impulse-mesh").string();
    argv[0] = const_cast<char*>(tool.c_str());
    ::execv(tool.c_str(), argv);
    std::cerr << "error: impulse " << argv[1] << " runs " << tool << ": " << std::strerror(errno)
              << " (it is built and installed beside impulse)\n";
    return 1;
}

bool is_mesh_command(int argc, char** argv) {
    if (argc < 2) return false;
    const std::string_view c = argv[1];
    return c == "mesh" || c == "trajectories";
}

CLI::App* add_render(CLI::App& app, impulse::app::RenderOptions& ro) {
    CLI::App* render = app.add_subcommand("render", "Render a scene to an image, an image sequence or a video");
    render->add_option("scene", ro.scene, "Scene file (TOML) or built-in scene name (see `impulse scenes`)")
        ->required();
    render->add_option("-o,--output", ro.output,
                       "Output: one image (.exr .png .tif .jpg), a sequence pattern (frame_####.png "
                       "or frame_%04d.exr; a single # is 4 digits), or a video (.mp4 .mov .mkv "
                       ".webm). Default: out/SCENE.mp4, or out/SCENE.png for one frame");
    render->add_option("--frames", ro.frames, "Inclusive 0-based frame range A-B, or one frame A (default: all)");
    render->add_option("--size", ro.size,
                       "The scene's picture at WxH pixels, e.g. 480x270 for a quick preview: the "
                       "same view (an orthographic camera's zoom scales with the height; kernels "
                       "and flows are in texture units)");
    render->add_option("--crop", ro.crop,
                       "A WxH window at the scene's own scale (sets output.size; the camera's "
                       "centre defaults to the window's middle)");
    render->add_option("--seed", ro.seed, "Scene-wide seed mixed into every layer's seed");
    render->add_option("--set", ro.sets, "Override any scene key by dotted path, e.g. layer.0.kernel.radius=8")
        ->allow_extra_args(false);
    render->add_option("--threads", ro.threads, "Worker threads (default: all cores); output does not depend on it")
        ->check(CLI::Range(1, 1024));
    render->add_option("--tile", ro.tile, "Tile size in pixels (default 128); output does not depend on it")
        ->check(CLI::Range(8, 4096));
    render->add_option("--channels", ro.channels,
                       "Channels besides the field, comma-separated: value, dx, dy, normal, "
                       "motion (docs/channels.md); an EXR holds any, a PNG normal or value alone");
    render->add_option("--codec", ro.codec, "Video codec: auto, h264, prores, ffv1, vp9 (overrides output.codec)");
    render->add_flag("--resume", ro.resume,
                     "Image sequences: keep the frames already present that check out (they decode "
                     "whole; size, channels and, in EXR and PNG, scene hash, seed and frame match), "
                     "render the others, and remove temporaries left by killed runs");
    render->add_flag("-q,--quiet", ro.quiet, "No progress display");
    return render;
}

CLI::App* add_analyze(CLI::App& app, impulse::app::AnalyzeOptions& ao) {
    CLI::App* analyze = app.add_subcommand(
        "analyze", "Measure an image, sequence or video; with --scene, compare with its theory");
    analyze->add_option("input", ao.input,
                        "One image, a sequence pattern (frame_####.exr, frame_%04d.png; from the "
                        "first frame present) or a video");
    analyze->add_option("--scene", ao.scene, "Scene file or built-in name to compare with");
    analyze->add_option("--set", ao.sets, "Override a scene key (with --scene)");
    analyze->add_option("--size", ao.size,
                        "The scene's theory at WxH pixels, as render --size (default: the size and "
                        "crop the frames' metadata records)");
    analyze->add_option("--channel", ao.channel,
                        "The channel of a multi-channel image to analyse (default: value if the "
                        "image has one, else the luminance)");
    analyze->add_option("--json", ao.json_file,
                        "Print one JSON object instead of text; --json FILE writes it to FILE")
        ->expected(0, 1);
    analyze->add_flag("--structure", ao.structure,
                      "Structure function along x, y, diagonal and the generalised Hurst "
                      "exponent H(s) (with its band over frames)");
    analyze->add_option("--variance-map", ao.variance_map,
                        "Write the per-pixel variance over the frames (realizations) as an image");
    analyze->add_option("--report", ao.report, "Write a self-contained HTML report (plots drawn by Vega, from libjs-vega)");
    analyze->add_option("--frames", ao.frames, "Inclusive 0-based frame range A-B, or one frame A");
    analyze->add_option("--max-frames", ao.max_frames, "Analyse at most N frames")
        ->check(CLI::PositiveNumber);
    return analyze;
}

CLI::App* add_preview(CLI::App& app, impulse::app::PreviewOptions& po) {
    CLI::App* preview = app.add_subcommand(
        "preview", "Play a scene in the browser as it renders; follows its file (app/preview.cpp)");
    preview->add_option("scene", po.scene, "Scene file or built-in name")->required();
    preview->add_option("--port", po.port, "Port on 127.0.0.1 (default 8080; 0: any free port)");
    preview->add_option("--host", po.host,
                        "Address to listen on (default 127.0.0.1: this machine only)");
    preview->add_option("--size", po.size,
                        "Preview size WxH, the same view (default: within 640x360)");
    preview->add_option("--expose", po.expose,
                        "Numeric keys with a slider, KEY or KEY=LO:HI, comma-separated, e.g. "
                        "layer.0.kernel.radius,layer.0.density")
        ->delimiter(',');
    preview->add_option("--set", po.sets, "Override a scene key (as render --set)");
    return preview;
}

}  // namespace

int main(int argc, char** argv) {
    if (is_mesh_command(argc, argv)) return run_mesh_companion(argv);
    CLI::App app{
        "impulse: animated, anti-aliased procedural textures from Lewis's shaped Poisson point\n"
        "process (sparse convolution noise) treated as a particle system."};
    app.require_subcommand(1);
    app.set_version_flag("--version", "impulse " IMPULSE_VERSION);
    app.footer(
        "Exit status: 0 done; 1 an error (one line on stderr); 2 a bad command line; 128 + the\n"
        "signal's number when stopped by SIGINT (130), SIGTERM (143) or SIGHUP (129): the frames\n"
        "written so far are kept whole and a video is closed so it plays.");
    app.set_help_all_flag("--help-all", "Show help for every command");

    impulse::app::RenderOptions ro;
    CLI::App* render = add_render(app, ro);

    CLI::App* scenes = app.add_subcommand("scenes", "List the built-in scenes");

    impulse::app::InfoOptions io;
    CLI::App* info = app.add_subcommand("info", "Print a scene's closed-form statistics and cost estimate");
    info->add_option("scene", io.scene, "Scene file or built-in name")->required();
    info->add_option("--set", io.sets, "Override a scene key");
    info->add_option("--size", io.size, "The scene at WxH pixels, the same view (as render --size)");
    info->add_option("--crop", io.crop, "A WxH window at the scene's scale (as render --crop)");

    impulse::app::AnalyzeOptions ao;
    CLI::App* analyze = add_analyze(app, ao);

    impulse::app::EncodeOptions eo;
    CLI::App* encode = impulse::app::add_encode(app, eo);
    impulse::app::FarmOptions fm;
    CLI::App* farm = impulse::app::add_farm(app, fm);
    impulse::app::PreviewOptions po;
    CLI::App* preview = add_preview(app, po);
    impulse::app::ExportOptions xo;
    CLI::App* export_command = impulse::app::add_export(app, xo);

    // Past a file size limit (ulimit -f) a write fails with EFBIG and is reported with the file's
    // name, instead of the process being killed by SIGXFSZ with nothing said.
    std::signal(SIGXFSZ, SIG_IGN);

    CLI::App* synth = app.add_subcommand(
        "synth", "Synthesize a field with another algorithm than the point process: "
                 "stochastic subdivision (gss), fractional Brownian surfaces (fbm), solid noise (solid)");
    synth->require_subcommand(1);
    impulse::app::add_synth_gss(*synth);
    impulse::app::SynthFbmOptions fo;
    CLI::App* synth_fbm = impulse::app::add_synth_fbm(*synth, fo);
    impulse::app::SynthSolidOptions so;
    CLI::App* synth_solid = impulse::app::add_synth_solid(*synth, so);

    // Listed here for --help; run by the companion tool (run_mesh_companion).
    app.add_subcommand("mesh", "Solid noise on meshes: texture, porous, deform, sphere, view "
                               "(impulse mesh --help; docs/mesh.md)");
    app.add_subcommand("trajectories", "Paths of particles forced by vector solid noise, as "
                                       "polylines (impulse trajectories --help)");

    try {
        app.parse(argc, argv);
    } catch (const CLI::RuntimeError& e) {
        return e.get_exit_code();  // a subcommand that ran in its callback (synth gss) failed
    } catch (const CLI::ParseError& e) {
        // CLI11's own codes (105, 106, ...) are not what scripts test for: 2, as getopt tools.
        return app.exit(e) == 0 ? 0 : 2;
    }
    ao.json = analyze->count("--json") > 0;
    // `analyze --json INPUT`: the one name given is the input, the JSON goes to stdout.
    if (ao.input.empty() && !ao.json_file.empty()) std::swap(ao.input, ao.json_file);
    try {
        if (*render) return impulse::app::run_render(ro);
        if (*scenes) return impulse::app::run_scenes();
        if (*info) return impulse::app::run_info(io);
        if (*preview) return impulse::app::run_preview(po);
        if (*analyze) return impulse::app::run_analyze(ao);
        if (*encode) return impulse::app::run_encode(eo);
        if (*farm) return impulse::app::run_farm(fm);
        if (*export_command) return impulse::app::run_export(*export_command, xo);
        if (*synth_fbm) return impulse::app::run_synth_fbm(fo);
        if (*synth_solid) return impulse::app::run_synth_solid(so);
        if (*synth) return 0;  // gss ran in its callback
    } catch (const impulse::Error& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
