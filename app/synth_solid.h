// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse synth solid`: solid noise (synth/solid.h, synth/lattice.h) on a W x H x D grid,
// written as an EXR stack of D layers z0000... or an OpenVDB float grid "density", or at the
// points of a CSV file (x,y,z per line) written as x,y,z,value.

#include <string>

namespace CLI {
class App;
}

namespace impulse::app {

/// Options of `impulse synth solid`, as given (checked by run_synth_solid).
struct SynthSolidOptions {
    std::string method;              ///< sparse, perlin, value or wiener
    std::string kernel = "cosine";   ///< sparse: cosine, gaussian, gabor, spectrum, autocorrelation
    std::string radius;              ///< sparse: kernel radius (8; designed: from energy);
                                     ///< lattice methods: lattice spacing (8)
    std::string density = "16";      ///< sparse: impulses per kernel volume 4/3 pi R^3
    std::string covariance = "spherical";  ///< wiener: gaussian, markov, spherical, cosine
    std::string length;              ///< wiener: covariance length, lattice units (1); designed
                                     ///< kernels: the model's length, texture units (8)
    /// Designed kernels (--kernel spectrum|autocorrelation; kernels/spectral.h, dims = 3): one
    /// of model, expression (of k, or of r for a correlation), table (k,S CSV); the model's
    /// parameters; the design options.
    std::string model, expression, table;
    std::string variance = "1", nu = "1.5", exponent = "1.4", omega = "0.5";
    std::string nyquist = "0.5", rolloff = "0.2", energy = "0.99", window = "hann";
    std::string size;                ///< WxHxD
    std::string seed = "0";
    std::string points;              ///< CSV of x,y,z: point queries
    std::string output;              ///< .exr or .vdb (grid), .csv (points)
    std::string memory_budget;       ///< GiB; default half the physical memory
};

CLI::App* add_synth_solid(CLI::App& synth, SynthSolidOptions& options);

/// Checks everything before any work, evaluates and writes atomically; throws ValueError,
/// BudgetError or IoError (one line), nothing written then.
int run_synth_solid(const SynthSolidOptions& options);

}  // namespace impulse::app
