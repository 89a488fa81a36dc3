// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse synth fbm`: a fractional Brownian surface by standard Fourier synthesis, Kaplan &
// Kuo's incremental Fourier synthesis or Stein's exact embedding (synth/synth.h), written as a
// float EXR (raw heights, sigma^2 = 1 per pixel step) or a 16-bit PNG/TIFF height map.

#include <string>

namespace CLI {
class App;
}

namespace impulse::app {

/// Options of `impulse synth fbm`, as given (numbers are checked by run_synth_fbm).
struct SynthFbmOptions {
    std::string method;           ///< fourier, incremental or exact
    std::string hurst;            ///< H in (0, 1)
    std::string size;             ///< N, a power of two up to 8192
    std::string seed = "0";       ///< integer in [0, 2^63 - 1]
    std::string output;           ///< .exr (float), .png or .tif (16-bit, min..max)
    bool seamless = false;        ///< fourier only: the periodic N x N field
    std::string memory_budget;    ///< GiB; default half the physical memory
};

/// Adds the `fbm` subcommand to `synth`, filling `options`; returns it.
CLI::App* add_synth_fbm(CLI::App& synth, SynthFbmOptions& options);

/// Checks everything (H, N, the method, the memory budget, the output path) before any work,
/// synthesises and writes atomically. Throws ValueError, BudgetError or IoError (one line);
/// nothing is written then.
int run_synth_fbm(const SynthFbmOptions& options);

}  // namespace impulse::app
