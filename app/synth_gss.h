// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse synth gss`: generalized stochastic subdivision from the command line
// (docs/subdivision.md).

namespace CLI {
class App;
}

namespace impulse::app {

/// Adds the `gss` subcommand to `synth`; its callback runs the synthesis (errors propagate as
/// impulse::Error to main's one-line report).
void add_synth_gss(CLI::App& synth);

}  // namespace impulse::app
