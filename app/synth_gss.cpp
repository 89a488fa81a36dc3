// SPDX-License-Identifier: Apache-2.0
// `impulse synth gss`: generalized stochastic subdivision (Lewis 1986 §2, Lewis 1987) to a CSV
// (1-D) or an image (2-D), from nothing or by refining given data. Every input is checked
// before anything is written; a failure is one line and a non-zero exit.

#include "app/synth_gss.h"

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/commands.h"
#include "app/parse.h"
#include "output/output.h"
#include "render/render.h"
#include "synth/synth.h"
#include "numeric/errors.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

struct GssCli {
    std::string acf, size = "257", output, refine, json, seed = "0", singular = "reduce";
    std::string displacement = "correlated";
    std::string origin;
    std::vector<std::string> params;
    int dim = 2, factor = 0, neighbors = 8, top_spacing = 0;
    double tolerance = 1e-4, debias = 0.05;
    bool periodic = false, quiet = false;
};

std::string lower_ext(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

std::vector<synth::AcfParam> parse_params(const std::vector<std::string>& params) {
    std::vector<synth::AcfParam> out;
    for (const auto& p : params) {
        const size_t eq = p.find('=');
        if (eq == std::string::npos || eq == 0)
            throw ValueError("--param " + p + ": expected KEY=VALUE, e.g. length=16");
        out.push_back({p.substr(0, eq), p.substr(eq + 1)});
    }
    return out;
}

/// "N" or "WxH" (1-D: "N" only).
std::pair<int, int> parse_size(const std::string& text, int dim) {
    if (dim == 1 && text.find('x') != std::string::npos)
        throw ValueError("--size " + text + ": expected N samples for --dim 1, e.g. 1025");
    const std::vector<long long> n = parse_dimensions(text);
    if (n.empty() || n.size() > 2)
        throw ValueError("--size " + text + ": expected " +
                         (dim == 1 ? "N samples, e.g. 1025" : "WxH samples, e.g. 513x513"));
    for (const long long v : n)
        if (v < 1 || v > (1 << 20))
            throw ValueError("--size " + text + ": expected 1 .. 2^20 per axis");
    const int w = static_cast<int>(n[0]);
    return {w, n.size() == 2 ? static_cast<int>(n[1]) : dim == 1 ? 1 : w};
}

/// 1-D data for --refine from a CSV of rows "i,value" (or one value per row).
std::vector<double> read_csv_values(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw IoError(path + ": cannot open");
    std::vector<double> v;
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
        ++n;
        if (line.empty() || line[0] == '#') continue;
        const std::string field =
            line.substr(line.find(',') == std::string::npos ? 0 : line.find(',') + 1);
        char* end = nullptr;
        const double d = std::strtod(field.c_str(), &end);
        if (end == field.c_str()) {
            if (v.empty() && n == 1) continue;  // a header
            throw ValueError(path + ":" + std::to_string(n) + ": expected i,value");
        }
        if (!std::isfinite(d))
            throw ValueError(path + ":" + std::to_string(n) + ": expected a finite value, found " +
                             field);
        v.push_back(d);
    }
    return v;
}

/// The seed image as one channel (1 channel, or the luminance of RGB / RGBA).
render::Frame read_seed_image(const std::string& path) {
    const output::ImageInfo info = output::probe_image(path);
    if (info.channels != 1 && info.channels != 3 && info.channels != 4)
        throw ValueError(path + ": " + std::to_string(info.channels) +
                         " channels: expected 1 (a height map) or 3 / 4 (RGB(A): its luminance)");
    return output::read_image(path);  // refuses NaN / inf (IoError naming the pixel)
}

void check_output(const std::string& path, int dim) {
    const std::string e = lower_ext(path);
    if (dim == 1 && e != ".csv")
        throw ValueError("-o " + path + ": 1-D output is a CSV file (i,value): expected .csv");
    if (dim == 2 && !output::is_image_path(path))
        throw ValueError("-o " + path +
                         ": 2-D output is an image: expected .exr (float), .png or .tif");
    const fs::path dir = fs::path(path).parent_path();
    if (!dir.empty() && !fs::is_directory(dir))
        throw IoError("-o " + path + ": directory " + dir.string() + " does not exist");
}

/// Writes `text` to `path` through a temporary name (no partial file under `path`).
void write_text(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".tmp";
    {
        std::ofstream out(tmp, std::ios::binary);
        out << text;
        if (!out) throw IoError(path + ": cannot write");
    }
    fs::rename(tmp, path);
}

void write_field(const std::string& path, const synth::Field& f, int dim, const std::string& acf,
                 uint64_t seed) {
    if (dim == 1) {
        std::ostringstream s;
        s.precision(9);
        s << "i,value\n";
        for (int i = 0; i < f.width; ++i)
            s << f.x0 + i << "," << float(f.values[size_t(i)]) << "\n";
        write_text(path, s.str());
        return;
    }
    render::Frame frame;
    frame.resize(f.width, f.height);
    double sum = 0, sum2 = 0;
    for (size_t i = 0; i < f.values.size(); ++i) {
        frame.data[i] = float(f.values[i]);
        sum += f.values[i], sum2 += f.values[i] * f.values[i];
    }
    // 8/16-bit formats: mean +- 3 standard deviations to [0, 1] (EXR keeps the raw values).
    const double n = double(f.values.size()), m = sum / n;
    const double sd = std::sqrt(std::max(sum2 / n - m * m, 1e-30));
    output::write_image(path, frame, {m - 3 * sd, m + 3 * sd},
                        {{"synth", "gss"},
                         {"acf", acf},
                         {"seed", std::to_string(seed)},
                         {"origin", std::to_string(f.x0) + "," + std::to_string(f.y0)}});
}

synth::GssOptions options_of(const GssCli& c, uint64_t seed) {
    synth::GssOptions o;
    o.dims = c.dim;
    o.max_neighbors = c.neighbors;
    o.tolerance = c.tolerance;
    o.debias = c.debias;
    o.top_spacing = c.top_spacing;
    o.seed = seed;
    if (c.displacement != "correlated" && c.displacement != "independent")
        throw ValueError("--displacement " + c.displacement +
                         ": expected correlated or independent");
    o.correlated = c.displacement == "correlated";
    if (c.singular == "pinv")
        o.singular = synth::Singular::PseudoInverse;
    else if (c.singular != "reduce")
        throw ValueError("--singular " + c.singular + ": expected reduce or pinv");
    synth::validate(o);
    return o;
}

void run_gss(const GssCli& c, bool size_given) {
    const uint64_t seed =
        uint64_t(whole_number("--seed", c.seed, c.seed, "an integer in [0, 9223372036854775807]"));
    const synth::GssOptions o = options_of(c, seed);
    check_output(c.output, c.dim);
    synth::Field field;
    std::string acf_name;
    if (!c.refine.empty()) {
        if (size_given)
            throw ValueError("--size: with --refine the size is (W - 1) F + 1 of the input");
        if (c.periodic || !c.origin.empty())
            throw ValueError(
                "--refine: the output covers the input exactly (no --periodic, --origin)");
        if (c.factor == 0)
            throw ValueError("--refine " + c.refine + ": expected --factor F (2, 4, 8, ...)");
        if (c.factor < 2 || (c.factor & (c.factor - 1)))
            throw ValueError("--factor " + std::to_string(c.factor) +
                             ": expected a power of two >= 2 (2, 4, 8, ...)");
        std::vector<double> data;
        int w = 0, h = 1;
        if (lower_ext(c.refine) == ".csv") {
            if (c.dim != 1)
                throw ValueError("--refine " + c.refine + ": a CSV seed is 1-D: expected --dim 1");
            data = read_csv_values(c.refine);
            w = int(data.size());
        } else {
            const render::Frame img = read_seed_image(c.refine);
            if (c.dim == 1 && img.height != 1)
                throw ValueError("--refine " + c.refine + ": a 1-D seed image has one row, found " +
                                 std::to_string(img.height));
            w = img.width, h = img.height;
            data.assign(img.data.begin(), img.data.end());
        }
        synth::Acf acf;
        if (c.acf.empty()) {
            const synth::AcfEstimate e = synth::estimate_acf(data, w, h, c.factor);
            if (!c.quiet) std::cout << e.summary << "\n";
            acf = e.acf;
        } else {
            acf = synth::make_acf(c.acf, parse_params(c.params));
        }
        acf_name = acf.name;
        field = synth::refine(data, w, h, c.factor, acf, o);
    } else {
        if (c.acf.empty())
            throw ValueError(
                "--acf: expected a model (markov, gaussian, ...), expression or table");
        if (c.factor) throw ValueError("--factor: only with --refine");
        const synth::Acf acf = synth::make_acf(c.acf, parse_params(c.params));
        acf_name = acf.name;
        const auto [w, h] = parse_size(c.size, c.dim);
        int64_t x0 = 0, y0 = 0;
        if (!c.origin.empty()) {
            const size_t comma = c.origin.find(',');
            auto coord = [&](const std::string& t) {
                char* end = nullptr;
                const long long v = std::strtoll(t.c_str(), &end, 10);
                if (t.empty() || end != t.c_str() + t.size() || std::llabs(v) > (1ll << 40))
                    throw ValueError("--origin " + c.origin + ": expected X" +
                                     (c.dim == 2 ? ",Y" : "") + " integers within +-2^40");
                return int64_t(v);
            };
            if ((comma == std::string::npos) != (c.dim == 1))
                throw ValueError("--origin " + c.origin + ": expected " +
                                 (c.dim == 1 ? "X" : "X,Y"));
            x0 = coord(c.origin.substr(0, comma));
            if (c.dim == 2) y0 = coord(c.origin.substr(comma + 1));
        }
        field = synth::synthesize(acf, o, x0, y0, w, h, c.periodic);
    }
    write_field(c.output, field, c.dim, acf_name, seed);
    if (!c.json.empty()) write_text(c.json, synth::plan_json(field.plan));
    if (!c.quiet)
        std::cout << "wrote " << c.output << " (" << field.width
                  << (c.dim == 2 ? "x" + std::to_string(field.height) : "") << " samples, "
                  << field.plan.levels.size() << " levels from spacing " << field.plan.top_spacing
                  << ")\n";
}

}  // namespace

void add_synth_gss(CLI::App& synth) {
    auto c = std::make_shared<GssCli>();
    CLI::App* g = synth.add_subcommand(
        "gss",
        "Generalized stochastic subdivision (Lewis 1987): any autocorrelation, 1-D or 2-D, "
        "or refine existing data");
    g->add_option("--acf", c->acf,
                  "Autocorrelation: markov, gaussian, markaussian, matern, oscillatory_markov, "
                  "oscillatory_gaussian; the spectrum-defined lorentzian, bandpass, power (R by "
                  "the inverse Hankel transform); expression (--param expr=...), table (--param "
                  "file=...); with --refine and no --acf it is estimated from the data");
    g->add_option("--param", c->params,
                  "KEY=VALUE of the model: variance, length, exponent, nu, omega; k0, f0, width, "
                  "slope, k_low, k_high, nyquist (spectrum-defined models, cycles per sample; "
                  "nyquist default 0.5); aspect, angle (degrees), separable (2-D anisotropy); "
                  "lengths in output samples")
        ->allow_extra_args(false);
    g->add_option("--size", c->size, "N (1-D) or WxH: 2^k + 1 per axis, 2^k with --periodic");
    g->add_option("--dim", c->dim, "1 or 2 (default 2)");
    g->add_option("--seed", c->seed, "Seed of the displacement noise (default 0)");
    g->add_option("-o,--output", c->output,
                  "Output: .csv (1-D, rows i,value), .exr (2-D float), .png, .tif")
        ->required();
    g->add_flag("--periodic", c->periodic, "A periodic field (tiles with itself)");
    g->add_option(
        "--origin", c->origin,
        "X or X,Y: position of the first sample; regions of one seed agree where they overlap");
    g->add_option(
        "--refine", c->refine,
        "Seed data (EXR/TIFF/PNG, 1 channel or luminance; 1-D: CSV i,value) kept exactly at "
        "every F-th node");
    g->add_option("--factor", c->factor, "Refinement factor F, a power of two");
    g->add_option("--json", c->json,
                  "Write the per-level spacing, neighbours, coefficients, variance");
    g->add_option("--neighbors", c->neighbors,
                  "Largest neighbourhood size 2N per axis (even, 2..16; default 8)");
    g->add_option(
        "--tolerance", c->tolerance,
        "Error threshold: the smallest N whose error is within this fraction of R(0) of the "
        "largest's (0: always the largest)");
    g->add_option("--singular", c->singular,
                  "Remedy for a singular autocorrelation: reduce (default) or pinv");
    g->add_option("--debias", c->debias,
                  "2-D diagonal-bias remedy: outer-coefficient ratio (0: off)");
    g->add_option("--top-spacing", c->top_spacing,
                  "Spacing of the coarsest level (power of two; 0: automatic)");
    g->add_option(
        "--displacement", c->displacement,
        "correlated (default: the new nodes' covariance made R again) or independent (the "
        "paper's)");
    g->add_flag("-q,--quiet", c->quiet, "Print nothing on success");
    g->callback([c, g] {
        try {
            run_gss(*c, g->count("--size") > 0);
        } catch (const std::exception& e) {
            std::cerr << "error: " << e.what() << "\n";
            throw CLI::RuntimeError(1);
        }
    });
}

}  // namespace impulse::app
