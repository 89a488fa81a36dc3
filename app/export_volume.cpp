// SPDX-License-Identifier: Apache-2.0
// `impulse export volume`: periodic solid noise (synth::SolidNoise with period_cells, Lewis 1989
// with Lewis 1986 §3.2's wrap-around) as a slice atlas and a raw float32 volume, with a JSON
// sidecar (docs/export.md "Volume"); and the sidecar helpers of app/detail/export.h.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <numeric>
#include <regex>

#include "app/commands.h"
#include "app/export.h"
#include "app/detail/export.h"
#include "app/parse.h"
#include "numeric/errors.h"
#include "output/atlas.h"
#include "output/output.h"
#include "scenes/scenes.h"
#include "synth/synth.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

constexpr double kMaxVoxels = double(1 << 27);  // 512 MiB of float32: the raw file and the grid

/// --size N (a cube) or WxHxD, each in [2, 4096], at most kMaxVoxels in all.
std::array<int, 3> volume_size(const std::string& text) {
    static const std::regex cube(R"(\d{1,4})"), box(R"((\d{1,4})x(\d{1,4})x(\d{1,4}))");
    std::smatch m;
    std::array<int, 3> n{};
    if (std::regex_match(text, m, cube)) n = {std::stoi(text), std::stoi(text), std::stoi(text)};
    else if (std::regex_match(text, m, box)) n = {std::stoi(m[1].str()), std::stoi(m[2].str()), std::stoi(m[3].str())};
    const std::string expected = "--size " + text.substr(0, 40) + ": expected N or WxHxD voxels, each in [2, 4096]";
    if (std::min({n[0], n[1], n[2]}) < 2 || std::max({n[0], n[1], n[2]}) > 4096) throw ValueError(expected);
    if (double(n[0]) * n[1] * n[2] > kMaxVoxels)
        throw ValueError(expected + ", at most 2^27 voxels in all (512 MiB of float32)");
    return n;
}

/// The kernel radius nearest `radius` whose cells (side R) tile every side of the volume: the
/// common divisor g = gcd(W, H, D) over a whole number of cells, R = g / max(1, round(g / radius)).
double periodic_radius(const std::array<int, 3>& n, double radius) {
    const int g = std::gcd(std::gcd(n[0], n[1]), n[2]);
    const double cells = std::max(1.0, std::round(g / radius));
    return g / cells;
}

synth::SolidParams volume_noise(const ExportOptions& o, const std::array<int, 3>& n) {
    synth::SolidParams p;
    const double asked = parse_whole<double>("--radius", o.radius.empty() ? "8" : o.radius, "a length > 0 (voxels)");
    if (!(asked > 0) || !(asked <= 4096)) throw ValueError("--radius " + o.radius + ": expected a length in (0, 4096] voxels");
    const double radius = periodic_radius(n, asked);
    if (radius != asked)
        std::cerr << "--radius " << fmt(asked) << ": " << fmt(radius) << " used, so each side is a whole number of "
                  << "cells of the kernel's radius (the noise's period)\n";
    const std::string kernel = o.kernel.empty() ? "cosine" : o.kernel;
    if (kernel != "cosine" && kernel != "gaussian") throw ValueError("--kernel " + kernel + ": expected one of cosine, gaussian");
    p.kernel.type = kernel == "cosine" ? kernels::KernelType::Cosine : kernels::KernelType::Gaussian;
    p.kernel.radius = radius, p.kernel.sigma = radius / 3.0;
    p.density = parse_whole<double>("--density", o.density.empty() ? "16" : o.density, "impulses per kernel volume in (0, 1000]");
    const auto seed = parse_whole<long long>("--seed", o.seed.empty() ? "0" : o.seed, "an integer in [0, 2^63 - 1]");
    if (seed < 0) throw ValueError("--seed " + o.seed + ": expected an integer in [0, 2^63 - 1]");
    p.seed = uint64_t(seed);
    for (int d = 0; d < 3; ++d) p.period_cells[size_t(d)] = std::llround(n[size_t(d)] / radius);
    synth::SolidNoise{p};  // its own checks (density), before any work
    return p;
}

std::string raw_path(const std::string& image) { return fs::path(image).replace_extension(".raw").string(); }

std::string volume_sidecar(const ExportOptions& o, const synth::SolidParams& p, const std::array<int, 3>& n,
                           const output::AtlasLayout& l, const output::ValueMapping& mapping) {
    const synth::SolidTheory th = synth::SolidNoise(p).theory();
    const std::string size = "[" + std::to_string(n[0]) + ", " + std::to_string(n[1]) + ", " + std::to_string(n[2]) + "]";
    JsonObject j;
    j.add("generator", json_string("impulse export volume"));
    j.add("image", json_string(fs::path(o.output).filename().string()));
    j.add("raw", json_string(fs::path(raw_path(o.output)).filename().string()));
    j.add("raw_format", json_string("float32 little-endian, x fastest, then y, then z (slice z = k is image cell k)"));
    j.add("size", size);
    j.add("layout", "{\"rows\": " + std::to_string(l.rows) + ", \"columns\": " + std::to_string(l.columns) +
                        ", \"order\": \"row-major from the top-left, one cell per z slice\"}");
    j.add("cell", "{\"width\": " + std::to_string(l.cell_width) + ", \"height\": " + std::to_string(l.cell_height) + "}");
    j.add("tileable", "true");
    j.add("period_voxels", size);
    j.add("kernel", json_string(p.kernel.type == kernels::KernelType::Cosine ? "cosine" : "gaussian"));
    j.add("radius_voxels", fmt(p.kernel.radius));
    j.add("density", fmt(p.density));
    j.add("seed", std::to_string(p.seed));
    j.add("mean", fmt(th.mean));
    j.add("variance", fmt(th.variance));
    j.add("display_range", "[" + fmt(mapping.lo) + ", " + fmt(mapping.hi) + "]");
    return j.text();
}

}  // namespace

std::string json_string(const std::string& s) {
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\') out += '\\', out += c;
        else if (static_cast<unsigned char>(c) < 0x20) {
            char buffer[8];
            std::snprintf(buffer, sizeof buffer, "\\u%04x", c);
            out += buffer;
        } else {
            out += c;
        }
    }
    return out + "\"";
}

std::string JsonObject::text() const {
    std::string out = "{\n";
    for (size_t i = 0; i < m_members.size(); ++i)
        out += "  " + json_string(m_members[i].first) + ": " + m_members[i].second + (i + 1 < m_members.size() ? ",\n" : "\n");
    return out + "}\n";
}

void add_scene_fields(JsonObject& j, const scenes::Scene& sc) {
    j.add("scene", json_string(fs::path(sc.path).filename().string()));
    j.add("scene_hash", json_string(sc.hash));
    j.add("seed", std::to_string(sc.seed));
}

std::string sidecar_path(const std::string& image) { return fs::path(image).replace_extension(".json").string(); }

void write_text(const std::string& path, const std::string& text) { output::write_file_atomic(path, text.data(), text.size()); }

void add_volume_export(CLI::App& e, ExportOptions& o) {
    CLI::App* v = e.add_subcommand("volume", "Periodic solid noise: a slice atlas (EXR/PNG) and a raw float32 volume");
    v->add_option("-o,--output", o.output, "OUT.exr (raw values) or OUT.png; beside it OUT.raw and OUT.json")->required();
    v->add_option("--size", o.volume_size, "N or WxHxD voxels, each in [2, 4096]")->required();
    v->add_option("--radius", o.radius, "Kernel radius in voxels (default 8; adjusted so the sides are whole cells)");
    v->add_option("--density", o.density, "Impulses per kernel volume, in (0, 1000] (default 16)");
    v->add_option("--kernel", o.kernel, "cosine or gaussian (default cosine)");
    v->add_option("--seed", o.seed, "Seed, integer in [0, 2^63 - 1] (default 0)");
    v->add_option("--layout", o.layout, "RxC rows x columns of slices (default: the squarest grid)");
    v->add_option("--bits", o.bits, "PNG: 8 or 16 bits (default 8)");
}

int run_volume_export(const ExportOptions& o) {
    const std::string e = output::lower_extension(o.output);
    if (e != ".exr" && e != ".png") throw ValueError(o.output + ": expected an image ending in .exr or .png");
    ensure_directory(o.output);
    const int bits = parse_int("--bits", o.bits.empty() ? "8" : o.bits, 8, 16);
    if (bits != 8 && bits != 16) throw ValueError("--bits " + o.bits + ": expected 8 or 16");
    const std::array<int, 3> n = volume_size(o.volume_size);
    const synth::SolidParams p = volume_noise(o, n);
    const output::AtlasLayout layout = output::atlas_layout(o.layout, n[2], n[0], n[1]);
    const synth::SolidNoise noise(p);
    const std::vector<float> grid = noise.grid(n[0], n[1], n[2], synth::SolidPoint{}, 1.0);
    std::vector<float> atlas(size_t(layout.width()) * layout.height(), 0.0f);
    const size_t slice = size_t(n[0]) * n[1];
    for (int k = 0; k < n[2]; ++k) output::place_cell(layout, k, 1, grid.data() + k * slice, atlas);
    const double sd = std::sqrt(noise.theory().variance), mean = noise.theory().mean;
    const output::ValueMapping mapping{mean - 3 * sd, mean + 3 * sd};
    output::write_image(o.output, render::Frame{layout.width(), layout.height(), atlas}, mapping,
                        {{"seed", std::to_string(p.seed)}}, bits == 16);
    output::write_file_atomic(raw_path(o.output), grid.data(), grid.size() * sizeof(float));
    write_text(sidecar_path(o.output), volume_sidecar(o, p, n, layout, mapping));
    std::cout << "wrote " << o.output << " (" << n[2] << " slices of " << n[0] << "x" << n[1] << "), "
              << raw_path(o.output) << " and " << sidecar_path(o.output) << "\n";
    return 0;
}

}  // namespace impulse::app
