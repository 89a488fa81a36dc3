// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse synth solid --kernel spectrum|autocorrelation`: a solid noise kernel designed from a
// 3-D spectrum or an isotropic 3-D correlation (kernels/spectral.h with dims = 3), scaled so the
// noise has that spectrum (synth::solid_designed_kernel).

#include <sstream>
#include <string>

#include "app/synth_solid.h"
#include "kernels/kernel.h"

namespace CLI {
class App;
}

namespace impulse::app {

/// --model, --expression, --table, the model's parameters and the design options.
void add_solid_design_options(CLI::App& solid, SynthSolidOptions& o);
/// Whether --kernel names a designed kernel (spectrum, autocorrelation).
bool is_designed_kernel(const std::string& kernel);
/// The designed kernel for `density` impulses per kernel volume; `radius` 0: the energy rule.
/// Appends the design to `desc`. ValueError (one line, naming the option) on bad input, a
/// negative 3-D spectrum or a correlation below the 3-D bound.
kernels::KernelParams solid_design_kernel(const SynthSolidOptions& o, double radius, double density,
                                          std::ostringstream& desc);

}  // namespace impulse::app
