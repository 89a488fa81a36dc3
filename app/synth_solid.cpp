// SPDX-License-Identifier: Apache-2.0
#include "app/synth_solid.h"
#include "app/synth_solid_design.h"
#include "app/parse.h"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "numeric/errors.h"
#include "output/files.h"
#include "output/volume.h"
#include "synth/synth.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

std::array<int, 3> parse_size(const std::string& s) {
    const std::vector<long long> n = parse_dimensions(s);
    if (n.empty() || std::any_of(n.begin(), n.end(), [](long long v) { return v <= 0 || v > 1 << 20; }))
        throw ValueError("--size " + s + ": expected WxHxD, three positive integers up to 1048576");
    if (n.size() != 3) throw ValueError("--size " + s + ": expected WxHxD, three positive integers");
    return {static_cast<int>(n[0]), static_cast<int>(n[1]), static_cast<int>(n[2])};
}

/// The points of a CSV of x,y,z lines (blank lines and # comments skipped); names a bad line.
std::vector<synth::SolidPoint> read_points(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw IoError(path + ": cannot read: " + std::strerror(errno));
    std::vector<synth::SolidPoint> pts;
    std::string line;
    for (int no = 1; std::getline(in, line); ++no) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#') continue;
        std::array<double, 3> v{};
        size_t pos = 0;
        bool ok = true;
        for (int c = 0; c < 3 && ok; ++c) {
            const size_t comma = c < 2 ? line.find(',', pos) : line.size();
            if (comma == std::string::npos) { ok = false; break; }
            std::string f = line.substr(pos, comma - pos);
            f.erase(0, f.find_first_not_of(" \t"));
            f.erase(f.find_last_not_of(" \t") + 1);
            const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), v[c]);
            ok = ec == std::errc() && end == f.data() + f.size() && !f.empty() && std::isfinite(v[c]);
            pos = comma + 1;
        }
        if (!ok) throw ValueError(path + ":" + std::to_string(no) + ": \"" + line + "\": expected x,y,z (three finite numbers)");
        pts.push_back({v[0], v[1], v[2], 0.0});
    }
    return pts;
}

void write_csv(const std::string& path, const std::vector<synth::SolidPoint>& p, const std::vector<float>& v) {
    const std::string tmp = output::partial_path(path);
    {
        std::ofstream out(tmp);
        char buf[128];
        for (size_t i = 0; i < p.size() && out; ++i) {
            std::snprintf(buf, sizeof buf, "%.9g,%.9g,%.9g,%.9g\n", p[i].x, p[i].y, p[i].z, double(v[i]));
            out << buf;
        }
        out.close();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw IoError(path + ": write failed: " + std::strerror(errno));
        }
    }
    output::commit_partial(tmp, path);  // flushed, renamed, its folder flushed
}

}  // namespace

CLI::App* add_synth_solid(CLI::App& synth, SynthSolidOptions& o) {
    CLI::App* s = synth.add_subcommand("solid", "Solid noise (Lewis 1989): sparse convolution or a lattice noise, "
                                                "on a W x H x D grid or at points");
    s->add_option("--method", o.method, "sparse, perlin, value or wiener")->required();
    s->add_option("--kernel", o.kernel,
                  "sparse: cosine (default), gaussian (sigma = R/3), gabor, or designed from a 3-D "
                  "spectrum or an isotropic correlation: spectrum, autocorrelation");
    s->add_option("--radius", o.radius,
                  "sparse: kernel radius R (default 8; designed kernels: from --energy); lattice "
                  "methods: lattice spacing (default 8)");
    s->add_option("--density", o.density, "sparse: impulses per kernel volume 4/3 pi R^3, in (0, 1000] (16)");
    s->add_option("--covariance", o.covariance, "wiener: gaussian, markov, spherical (default) or cosine");
    s->add_option("--length", o.length,
                  "wiener: covariance length in lattice spacings (default 1); designed kernels: the "
                  "model's length in texture units (default 8)");
    add_solid_design_options(*s, o);
    s->add_option("--size", o.size, "Grid WxHxD, sample (i, j, k) at (i, j, k) texture units");
    s->add_option("--seed", o.seed, "Random seed, integer in [0, 2^63 - 1] (default 0)");
    s->add_option("--points", o.points, "CSV of x,y,z lines: evaluate there, -o values.csv");
    s->add_option("-o,--output", o.output, ".exr (D layers z0000...), .vdb (float grid \"density\") or .csv")
        ->required();
    s->add_option("--memory-budget", o.memory_budget, "Refuse grids needing more GiB (default: half the memory)");
    return s;
}

int run_synth_solid(const SynthSolidOptions& o) {
    const std::string method = o.method;
    if (method != "sparse" && method != "perlin" && method != "value" && method != "wiener")
        throw ValueError("--method " + method + ": expected one of sparse, perlin, value, wiener");
    const bool designed = method == "sparse" && is_designed_kernel(o.kernel);
    const std::string radius_text = o.radius.empty() ? (designed ? "0" : "8") : o.radius;
    const double radius = parse_whole<double>("--radius", radius_text, "a number > 0");
    if (!(radius > 0.0 || (designed && o.radius.empty())) || !(radius <= 1e6))
        throw ValueError("--radius " + radius_text + ": expected a number in (0, 1e6]");
    const auto seed = parse_whole<long long>("--seed", o.seed, "an integer in [0, 9223372036854775807]");
    if (seed < 0) throw ValueError("--seed " + o.seed + ": expected an integer in [0, 2^63 - 1]");
    const bool points = !o.points.empty();
    if (points == !o.size.empty())
        throw ValueError(points ? "--points and --size: give one (points or a grid)"
                                : "--size WxHxD or --points FILE: one is required");
    const std::string e = output::lower_extension(o.output);
    if (points ? e != ".csv" : (e != ".exr" && e != ".vdb"))
        throw ValueError("-o " + o.output + (points ? ": expected a .csv for point values" : ": expected .exr or .vdb"));
    const fs::path dir = fs::path(o.output).parent_path();
    const std::string d = dir.empty() ? "." : dir.string();
    if (!fs::is_directory(d) || ::access(d.c_str(), W_OK) != 0)
        throw IoError(o.output + ": output directory " + d + " does not exist or is not writable");

    std::array<int, 3> n{};
    if (!points) {
        n = parse_size(o.size);
        double budget = synth::default_memory_budget();
        if (!o.memory_budget.empty()) {
            budget = parse_whole<double>("--memory-budget", o.memory_budget, "GiB, > 0");
            if (!(budget > 0)) throw ValueError("--memory-budget " + o.memory_budget + ": expected > 0");
            budget *= double(1ull << 30);
        }
        // The volume, its interleaved or VDB copy and one slab of the batch.
        const double samples = double(n[0]) * n[1] * n[2];
        const double bytes = samples * 4.0 * (e == ".vdb" ? 3.0 : 2.0) +
                             synth::SolidNoise::batch_bytes(std::min(samples, double(1 << 22)));
        if (bytes > budget) {
            std::ostringstream s;
            s << "--size " << o.size << ": needs an estimated " << std::llround(bytes / (1 << 20))
              << " MiB, over the memory budget of " << std::llround(budget / (1 << 20)) << " MiB";
            throw BudgetError(s.str());
        }
    }
    const std::vector<synth::SolidPoint> pts = points ? read_points(o.points) : std::vector<synth::SolidPoint>{};

    std::vector<float> values;
    std::ostringstream desc;
    desc << "impulse synth solid --method " << method << " --radius " << radius_text << " --seed " << seed;
    if (method == "sparse") {
        synth::SolidParams p;
        p.density = parse_whole<double>("--density", o.density, "impulses per kernel volume in (0, 1000]");
        if (designed) {
            if (!(p.density > 0.0)) throw ValueError("--density " + o.density + ": expected a number in (0, 1000]");
            p.kernel = solid_design_kernel(o, radius, p.density, desc);
        } else {
            const auto type = kernels::kernel_type_from_string(o.kernel);
            if (!type || *type == kernels::KernelType::Sampled)
                throw ValueError("--kernel " + o.kernel +
                                 ": expected one of cosine, gaussian, gabor, spectrum, autocorrelation");
            p.kernel.type = *type;
            p.kernel.radius = radius;
            p.kernel.sigma = radius / 3.0;
            p.kernel.frequency = 2.0 / radius;
        }
        p.seed = uint64_t(seed);
        const synth::SolidNoise noise(p);  // validates density
        desc << " --kernel " << o.kernel << " --density " << o.density << " (variance "
             << noise.theory().variance << ")";
        if (points) noise.evaluate(pts, values);
        else values = noise.grid(n[0], n[1], n[2], {});
    } else {
        synth::LatticeParams p;
        p.method = synth::parse_lattice_method(method);
        p.spacing = radius;
        p.seed = uint64_t(seed);
        if (p.method == synth::LatticeMethod::Wiener) {
            const std::string length = o.length.empty() ? "1" : o.length;
            const double l = parse_whole<double>("--length", length, "a number > 0");
            p.covariance = synth::wiener_covariance(o.covariance, l);
            desc << " --covariance " << o.covariance << " --length " << length;
        }
        const synth::LatticeNoise noise(p);  // wiener: refuses a covariance the lattice cannot realize
        if (points) noise.evaluate(pts, values);
        else values = noise.grid(n[0], n[1], n[2], {});
    }
    if (points) write_csv(o.output, pts, values);
    else if (e == ".exr") output::write_exr_stack(o.output, {n, std::move(values)}, desc.str());
    else output::write_vdb(o.output, {n, std::move(values)}, desc.str());
    return 0;
}

}  // namespace impulse::app
