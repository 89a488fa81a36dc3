// SPDX-License-Identifier: Apache-2.0
#include "app/synth_fbm.h"
#include "app/parse.h"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <iostream>

#include "output/output.h"
#include "render/render.h"
#include "synth/synth.h"
#include "numeric/errors.h"

namespace impulse::app {
namespace {

void check_output(const std::string& path) {
    const std::string e = output::lower_extension(path);
    if (e != ".exr" && e != ".png" && e != ".tif" && e != ".tiff")
        throw ValueError("-o " + path + ": expected .exr (float heights) or .png/.tif (16-bit)");
    const std::filesystem::path dir = std::filesystem::path(path).parent_path();
    const std::string d = dir.empty() ? "." : dir.string();
    if (!std::filesystem::is_directory(d) || ::access(d.c_str(), W_OK) != 0)
        throw IoError(path + ": output directory " + d + " does not exist or is not writable");
}

}  // namespace

CLI::App* add_synth_fbm(CLI::App& synth, SynthFbmOptions& o) {
    CLI::App* fbm = synth.add_subcommand(
        "fbm", "Fractional Brownian surface (fBm height field): Fourier, incremental or exact");
    fbm->add_option("--method", o.method,
                    "fourier (standard Fourier synthesis: stationary, not fBm), incremental "
                    "(Kaplan & Kuo 1996) or exact (Stein 2002)")
        ->required();
    fbm->add_option("--hurst", o.hurst, "Hurst exponent H in (0, 1): 1 - H is the roughness")
        ->required();
    fbm->add_option("--size", o.size, "Output N x N, N a power of two up to 8192")->required();
    fbm->add_option("--seed", o.seed, "Random seed, integer in [0, 2^63 - 1] (default 0)");
    fbm->add_option("-o,--output", o.output,
                    "Output: .exr (float heights, B(0,0) = 0, unit step variance) or .png/.tif "
                    "(16-bit height map, min..max)")
        ->required();
    fbm->add_flag("--seamless", o.seamless, "fourier only: the periodic N x N field (tiles)");
    fbm->add_option("--memory-budget", o.memory_budget,
                    "Refuse sizes needing more than this many GiB (default: half the memory)");
    return fbm;
}

int run_synth_fbm(const SynthFbmOptions& o) {
    synth::FbmOptions f;
    f.method = synth::parse_fbm_method(o.method);
    f.hurst = parse_whole<double>("--hurst", o.hurst, "a number in (0, 1)");
    f.size = parse_whole<int>("--size", o.size, "a power of two from 2 to 8192");
    f.seamless = o.seamless;
    const auto seed =
        parse_whole<long long>("--seed", o.seed, "an integer in [0, 9223372036854775807]");
    if (seed < 0) throw ValueError("--seed " + o.seed + ": expected an integer in [0, 2^63 - 1]");
    double budget = synth::default_memory_budget();
    if (!o.memory_budget.empty()) {
        budget = parse_whole<double>("--memory-budget", o.memory_budget, "GiB, > 0");
        if (!(budget > 0)) throw ValueError("--memory-budget " + o.memory_budget + ": expected > 0");
        budget *= double(1ull << 30);
    }
    synth::check_fbm(f, budget);
    check_output(o.output);

    const synth::Surface B = synth::fbm(f, uint64_t(seed));
    render::Frame frame{B.width, B.height, B.data};
    const auto [lo, hi] = std::minmax_element(B.data.begin(), B.data.end());
    const output::Metadata meta = {{"fbm:method", synth::to_string(f.method)},
                                   {"fbm:hurst", o.hurst},
                                   {"fbm:seed", std::to_string(seed)},
                                   {"fbm:seamless", f.seamless ? "1" : "0"},
                                   {"fbm:min", std::to_string(*lo)},
                                   {"fbm:max", std::to_string(*hi)}};
    output::write_image(o.output, frame, {*lo, *hi > *lo ? *hi : *lo + 1.0}, meta,
                        output::lower_extension(o.output) != ".exr");
    return 0;
}

}  // namespace impulse::app
