// SPDX-License-Identifier: Apache-2.0
// `impulse export flipbook|flowmap`: parse, check the scene for what the export claims (a loop,
// a tile), render, lay out and write the image and its JSON sidecar (docs/export.md). The volume
// export is in app/export_volume.cpp.

#include "app/export.h"

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <tuple>

#include "app/commands.h"
#include "app/detail/export.h"
#include "app/parse.h"
#include "numeric/errors.h"
#include "output/atlas.h"
#include "output/output.h"
#include "scenes/scenes.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

RenderOptions render_options(const ExportOptions& o) {
    RenderOptions r;
    r.scene = o.scene, r.sets = o.sets, r.seed = o.seed, r.size = o.size;
    return r;
}

std::string layer_name(size_t i) { return "layer[" + std::to_string(i) + "]"; }

/// A looping atlas needs a camera that does not move (its keys are not wrapped into the loop).
void check_still_camera(const scenes::Scene& sc, const std::string& why) {
    const scenes::CameraConfig& c = sc.camera;
    if (c.type != scenes::CameraConfig::Type::Orthographic)
        throw ValueError(sc.path + ": camera.type = \"perspective\": " + why + " needs an orthographic camera");
    if (!c.zoom.is_constant() || !c.center_x.is_constant() || !c.center_y.is_constant())
        throw ValueError(sc.path + ": camera.zoom or camera.center is keyframed: " + why +
                         " needs a still camera (the camera's keys are not looped)");
}

/// The loop every moving layer shares, in seconds (docs/scenes.md "[[layer]]", its `loop` key); throws naming the key.
double shared_loop(const scenes::Scene& sc) {
    double loop_s = 0.0;
    for (size_t i = 0; i < sc.layers.size(); ++i) {
        const scenes::LayerConfig& l = sc.layers[i];
        if (l.source)
            throw ValueError(sc.path + ": " + layer_name(i) + " draws a source field: --loop checks impulse layers' loop only");
        if (l.process.lifetime_s <= 0.0) continue;  // a still layer repeats with any period
        if (l.process.loop_s <= 0.0)
            throw ValueError(sc.path + ": " + layer_name(i) + " has no loop: add `loop = SECONDS` (whole frames, "
                             ">= its lifetime) to the layer for a looping flipbook (--loop)");
        if (loop_s > 0.0 && l.process.loop_s != loop_s)
            throw ValueError(sc.path + ": " + layer_name(i) + ".loop = " + fmt(l.process.loop_s) +
                             " but an earlier layer's loop is " + fmt(loop_s) + ": --loop needs one period");
        loop_s = l.process.loop_s;
    }
    if (loop_s == 0.0) throw ValueError(sc.path + ": no layer has a lifetime: a still picture, not a loop (drop --loop)");
    check_still_camera(sc, "--loop");
    return loop_s;
}

/// The texture's period when the picture is whole tiles of it in every layer; throws naming
/// the key to add or to change (Lewis 1986 §3.2: wrap-around boundaries).
std::array<double, 2> check_tileable(const scenes::Scene& sc) {
    check_still_camera(sc, "--tileable");
    const render::View v = sc.camera.view(sc.output.width, sc.output.height, sc.frame_time(0));
    const std::array<double, 2> extent = {v.width * v.scale, v.height * v.scale};
    const std::string spans = "the picture spans " + fmt(extent[0]) + " x " + fmt(extent[1]) +
                              " texture units (output.size / camera.zoom)";
    for (size_t i = 0; i < sc.layers.size(); ++i) {
        const scenes::LayerConfig& l = sc.layers[i];
        if (l.source) throw ValueError(sc.path + ": " + layer_name(i) + " draws a source field: --tileable checks impulse layers' period only");
        if (!l.process.period)
            throw ValueError(sc.path + ": " + layer_name(i) + " has no period: add `period = [" + fmt(extent[0]) + ", " +
                             fmt(extent[1]) + "]` to the layer for a tileable flipbook (--tileable; " + spans + ")");
        for (int a = 0; a < 2; ++a) {
            const double tiles = extent[size_t(a)] / (*l.process.period)[size_t(a)];
            if (std::abs(tiles - std::round(tiles)) > 1e-9 * tiles || std::round(tiles) < 1)
                throw ValueError(sc.path + ": " + layer_name(i) + ".period = [" + fmt((*l.process.period)[0]) + ", " +
                                 fmt((*l.process.period)[1]) + "]: " + spans + ", not a whole number of periods");
        }
    }
    return extent;
}

struct FlipbookPlan {
    long long first = 0, last = 0;
    double loop_s = 0.0;                        ///< > 0 with --loop
    std::optional<std::array<double, 2>> tile;  ///< with --tileable: one tile, texture units
};

FlipbookPlan plan_flipbook(const ExportOptions& o, const scenes::Scene& sc) {
    FlipbookPlan p;
    p.last = sc.output.frames - 1;
    if (o.tileable) p.tile = check_tileable(sc);
    if (o.loop) {
        p.loop_s = shared_loop(sc);
        const long long period = std::llround(p.loop_s * sc.output.fps);
        p.last = period - 1;
        if (!o.frames.empty()) {
            const auto [a, b] = parse_frame_range(o.frames, std::numeric_limits<long long>::max());
            if (b - a + 1 != period)
                throw ValueError("--frames " + o.frames + " with --loop: a loop is " + std::to_string(period) +
                                 " frames (loop = " + fmt(p.loop_s) + " s at " + fmt(sc.output.fps) + " fps), e.g. 0-" +
                                 std::to_string(period - 1));
            p.first = a, p.last = b;
        }
    } else if (!o.frames.empty()) {
        std::tie(p.first, p.last) = parse_frame_range(o.frames, sc.output.frames);
    }
    return p;
}

void check_atlas_output(const std::string& path) {
    const std::string e = output::lower_extension(path);
    if (e != ".exr" && e != ".png") throw ValueError(path + ": expected an image ending in .exr or .png");
    ensure_directory(path);
}

std::unique_ptr<tbb::global_control> thread_cap(int threads) {
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
}

/// Renders the plan's frames into the atlas: raw values (EXR, grey PNG) or shaded colour.
std::vector<float> render_atlas(scenes::Renderer& renderer, const FlipbookPlan& p,
                                const output::AtlasLayout& layout, int channels) {
    const scenes::Scene& sc = renderer.scene();
    const output::ValueMapping mapping = renderer.mapping();
    std::vector<float> atlas(size_t(layout.width()) * layout.height() * channels, 0.0f), rgb;
    render::Frame frame;
    for (long long f = p.first; f <= p.last; ++f) {
        renderer.render(f, frame);
        const float* cell = frame.data.data();
        if (channels == 3) {
            output::shade(frame, mapping, sc.shading_at(sc.frame_time(f)), rgb);
            cell = rgb.data();
        }
        place_cell(layout, int(f - p.first), channels, cell, atlas);
    }
    return atlas;
}

std::string flipbook_sidecar(const scenes::Scene& sc, const std::string& image, const FlipbookPlan& p,
                             const output::AtlasLayout& l, const output::ValueMapping& mapping) {
    const render::View v = sc.camera.view(sc.output.width, sc.output.height, sc.frame_time(p.first));
    JsonObject j;
    j.add("generator", json_string("impulse export flipbook"));
    add_scene_fields(j, sc);
    j.add("image", json_string(fs::path(image).filename().string()));
    j.add("values", json_string(output::lower_extension(image) == ".exr" ? "raw field (channel Y)" : "display"));
    j.add("frames", std::to_string(p.last - p.first + 1));
    j.add("first_frame", std::to_string(p.first));
    j.add("fps", fmt(sc.output.fps));
    j.add("layout", "{\"rows\": " + std::to_string(l.rows) + ", \"columns\": " + std::to_string(l.columns) +
                        ", \"order\": \"row-major from the top-left\"}");
    j.add("cell", "{\"width\": " + std::to_string(l.cell_width) + ", \"height\": " + std::to_string(l.cell_height) + "}");
    j.add("loop", p.loop_s > 0 ? "true" : "false");
    if (p.loop_s > 0) j.add("loop_s", fmt(p.loop_s));
    j.add("tileable", p.tile ? "true" : "false");
    if (p.tile) j.add("period", "[" + fmt((*p.tile)[0]) + ", " + fmt((*p.tile)[1]) + "]");
    j.add("pixels_per_texture_unit", fmt(1.0 / v.scale));
    j.add("display_range", "[" + fmt(mapping.lo) + ", " + fmt(mapping.hi) + "]");
    return j.text();
}

/// Refuses an atlas whose pixels would exceed the scene's memory limit, with the estimate.
void check_atlas_memory(const scenes::Scene& sc, const output::AtlasLayout& l, int channels) {
    const double mib = double(l.width()) * l.height() * channels * sizeof(float) / (1024.0 * 1024.0);
    if (mib > sc.limits.max_memory_mib)
        throw ValueError("an atlas of " + std::to_string(l.width()) + "x" + std::to_string(l.height()) + " pixels (" +
                         std::to_string(channels) + " float channels) needs " + std::to_string(std::llround(mib)) +
                         " MiB, over limits.max_memory_mib = " + fmt(sc.limits.max_memory_mib) +
                         ": fewer frames or a smaller --size");
}

int run_flipbook(const ExportOptions& o) {
    check_atlas_output(o.output);
    scenes::Scene scene = load_render_scene(render_options(o));
    if (scene.volume) throw ValueError(scene.path + ": a volume scene: `impulse export volume` writes solid noise");
    const FlipbookPlan plan = plan_flipbook(o, scene);
    const output::AtlasLayout layout =
        output::atlas_layout(o.layout, plan.last - plan.first + 1, scene.output.width, scene.output.height);
    const bool exr = output::lower_extension(o.output) == ".exr";
    const int channels = !exr && colour_shading(scene) ? 3 : 1;
    check_atlas_memory(scene, layout, channels);
    const auto cap = thread_cap(o.threads);
    scenes::Renderer renderer(std::move(scene));
    const scenes::Scene& sc = renderer.scene();
    const std::vector<float> atlas = render_atlas(renderer, plan, layout, channels);
    const output::ValueMapping mapping = renderer.mapping();
    const output::Metadata meta = {{"seed", std::to_string(sc.seed)}, {"scene_hash", sc.hash},
                                   {"atlas", std::to_string(layout.rows) + "x" + std::to_string(layout.columns)}};
    if (channels == 3)
        output::write_rgb_image(o.output, layout.width(), layout.height(), atlas, meta, sc.output.bits == 16);
    else
        output::write_image(o.output, render::Frame{layout.width(), layout.height(), atlas}, mapping, meta,
                            sc.output.bits == 16, sc.output.compression);
    const std::string json = sidecar_path(o.output);
    write_text(json, flipbook_sidecar(sc, o.output, plan, layout, mapping));
    std::cout << "wrote " << o.output << " (" << plan.last - plan.first + 1 << " frames, " << layout.rows << "x"
              << layout.columns << " cells of " << layout.cell_width << "x" << layout.cell_height << ") and " << json << "\n";
    return 0;
}

/// The layer's velocity at every pixel centre of an orthographic frame (Flow::add; texture
/// units per second), at the layer's time of the frame.
void sample_flow(const scenes::Scene& sc, size_t layer, long long frame, std::vector<double>& vx,
                 std::vector<double>& vy) {
    const render::View v = sc.camera.view(sc.output.width, sc.output.height, sc.frame_time(frame));
    sim::Flow& flow = *sc.layers[layer].flow;
    flow.prepare(v.box());
    const size_t w = size_t(v.width);
    vx.assign(w * size_t(v.height), 0.0), vy.assign(vx.size(), 0.0);
    std::vector<double> x(w), y(w);
    const double t = sc.layer_time(layer, frame);
    for (int j = 0; j < v.height; ++j) {
        for (size_t i = 0; i < w; ++i) x[i] = v.x0 + (double(i) + 0.5) * v.scale, y[i] = v.y0 + (j + 0.5) * v.scale;
        flow.add(t, w, x.data(), y.data(), &vx[j * w], &vy[j * w], nullptr, nullptr);
    }
}

size_t flow_layer(const ExportOptions& o, const scenes::Scene& sc) {
    const int n = int(sc.layers.size());
    const size_t layer = size_t(parse_int("--layer", o.layer.empty() ? "0" : o.layer, 0, std::max(0, n - 1)));
    if (!sc.layers[layer].flow)
        throw ValueError(sc.path + ": " + layer_name(layer) + " has no flow: add a [[layer.flow]] table to it "
                         "(docs/scenes.md) or choose another --layer");
    return layer;
}

double flow_vmax(const ExportOptions& o, const std::vector<double>& vx, const std::vector<double>& vy) {
    if (!o.vmax.empty()) {
        const double v = parse_whole<double>("--vmax", o.vmax, "a speed > 0 (texture units per second)");
        if (!(v > 0) || !std::isfinite(v)) throw ValueError("--vmax " + o.vmax + ": expected a speed > 0 (texture units per second)");
        return v;
    }
    double vmax = 0.0;
    for (size_t i = 0; i < vx.size(); ++i) vmax = std::max({vmax, std::abs(vx[i]), std::abs(vy[i])});
    if (!(vmax > 0))
        throw ValueError("the flow is still over the picture at this frame: nothing to encode (--vmax V for a map of 0.5)");
    return vmax;
}

int run_flowmap(const ExportOptions& o) {
    check_atlas_output(o.output);
    const int bits = parse_int("--bits", o.bits.empty() ? "8" : o.bits, 8, 16);
    if (bits != 8 && bits != 16) throw ValueError("--bits " + o.bits + ": expected 8 or 16");
    const scenes::Scene sc = load_render_scene(render_options(o));
    if (sc.volume) throw ValueError(sc.path + ": a volume scene: flow maps are of 2-D layers");
    if (sc.camera.type != scenes::CameraConfig::Type::Orthographic)
        throw ValueError(sc.path + ": camera.type = \"perspective\": a flow map needs an orthographic camera");
    const size_t layer = flow_layer(o, sc);
    const long long frame = parse_frame_range(o.frame.empty() ? "0" : o.frame, sc.output.frames).first;
    std::vector<double> vx, vy;
    sample_flow(sc, layer, frame, vx, vy);
    const double vmax = flow_vmax(o, vx, vy);
    const bool exr = output::lower_extension(o.output) == ".exr";
    std::vector<float> rgb;
    if (exr) {  // raw velocities, texture units per second
        rgb.assign(vx.size() * 3, 0.0f);
        for (size_t i = 0; i < vx.size(); ++i) rgb[3 * i] = float(vx[i]), rgb[3 * i + 1] = float(vy[i]);
    } else {
        output::encode_flow(vx, vy, vmax, rgb);
    }
    const output::Metadata meta = {{"seed", std::to_string(sc.seed)}, {"scene_hash", sc.hash}, {"vmax", fmt(vmax)}};
    output::write_rgb_image(o.output, sc.output.width, sc.output.height, rgb, meta, bits == 16);
    const render::View v = sc.camera.view(sc.output.width, sc.output.height, sc.frame_time(frame));
    JsonObject j;
    j.add("generator", json_string("impulse export flowmap"));
    add_scene_fields(j, sc);
    j.add("image", json_string(fs::path(o.output).filename().string()));
    j.add("encoding", json_string(exr ? "raw: R = vx, G = vy, texture units per second" : "R, G = 0.5 + 0.5 v / vmax"));
    j.add("bits", exr ? "32" : std::to_string(bits));
    j.add("vmax", fmt(vmax));
    j.add("units", json_string("texture units per second; +x right, +y down the picture"));
    j.add("layer", std::to_string(layer));
    j.add("frame", std::to_string(frame));
    j.add("time_s", fmt(sc.layer_time(layer, frame)));
    j.add("fps", fmt(sc.output.fps));
    j.add("pixels_per_texture_unit", fmt(1.0 / v.scale));
    const std::string json = sidecar_path(o.output);
    write_text(json, j.text());
    std::cout << "wrote " << o.output << " (vmax " << fmt(vmax) << " texture units/s) and " << json << "\n";
    return 0;
}

void add_scene_options(CLI::App* c, ExportOptions& o) {
    c->add_option("scene", o.scene, "Scene file (TOML) or built-in scene name")->required();
    c->add_option("-o,--output", o.output, "OUT.exr (raw float values) or OUT.png; the sidecar is OUT.json")->required();
    c->add_option("--size", o.size, "The scene's picture at WxH pixels (as render --size)");
    c->add_option("--seed", o.seed, "Scene-wide seed (as render --seed)");
    c->add_option("--set", o.sets, "Override a scene key (as render --set)")->allow_extra_args(false);
    c->add_option("--threads", o.threads, "Worker threads; output does not depend on it")->check(CLI::Range(1, 1024));
}

}  // namespace

CLI::App* add_export(CLI::App& app, ExportOptions& o) {
    CLI::App* e = app.add_subcommand("export", "What game engines take: flipbook atlases, flow maps, "
                                               "periodic solid-noise volumes, each with a JSON sidecar (docs/export.md)");
    e->require_subcommand(1);
    CLI::App* f = e->add_subcommand("flipbook", "A sequence's frames as rows x columns of one EXR or PNG atlas");
    add_scene_options(f, o);
    f->add_option("--frames", o.frames, "Inclusive 0-based frame range A-B (default: all, or one loop with --loop)");
    f->add_option("--layout", o.layout, "RxC rows x columns (default: the squarest grid that holds the frames)");
    f->add_flag("--loop", o.loop, "Check the frames are one seamless loop (every moving layer's `loop`)");
    f->add_flag("--tileable", o.tileable, "Check every cell tiles (every layer's `period` fits the picture)");
    CLI::App* m = e->add_subcommand("flowmap", "A layer's velocity field as a two-channel flow map");
    add_scene_options(m, o);
    m->add_option("--layer", o.layer, "The layer whose flow is written (default 0)");
    m->add_option("--frame", o.frame, "The frame whose time the flow is taken at (default 0)");
    m->add_option("--vmax", o.vmax, "The speed that maps to 0 and 1, texture units per second (default: the largest component)");
    m->add_option("--bits", o.bits, "PNG: 8 or 16 bits per channel (default 8)");
    add_volume_export(*e, o);
    return e;
}

int run_export(const CLI::App& e, const ExportOptions& o) {
    if (e.got_subcommand("flipbook")) return run_flipbook(o);
    if (e.got_subcommand("flowmap")) return run_flowmap(o);
    return run_volume_export(o);
}

}  // namespace impulse::app
