// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse farm`: a render on a Slurm cluster. Writes an sbatch array script (one task per chunk
// of frames, each `impulse render --frames A-B --resume`, so a failed or preempted task is
// resubmitted and carries on) and an encode script run after every task succeeded; with
// --submit, submits both and prints the array's job id.

#include <string>

#include "app/commands.h"

namespace CLI {
class App;
}

namespace impulse::app {

/// Options of `impulse farm`, as given (checked by run_farm).
struct FarmOptions {
    RenderOptions render;     ///< scene, -o pattern, --frames, --size, --seed, --set, --codec ...
    std::string chunk;        ///< frames per array task, > 0
    std::string partition;    ///< sbatch --partition ("": the cluster's default)
    std::string time;         ///< sbatch --time per task ("": the partition's default)
    std::string cpus;         ///< sbatch --cpus-per-task, also the render's --threads
    std::string max_running;  ///< at most this many tasks at once (--array=...%N)
    std::string video;        ///< the encode job's output (default: beside the frames, SCENE.mp4)
    std::string script;       ///< the array script (default: beside the frames, SCENE.sbatch)
    bool submit = false;      ///< submit with sbatch and print the job id
};

/// Adds the `farm` subcommand to `app`, filling `options`; returns it.
CLI::App* add_farm(CLI::App& app, FarmOptions& options);

/// Checks the options and loads the scene (every error before anything is written), writes the
/// two scripts, and with --submit runs sbatch. Throws ValueError or IoError (one line).
int run_farm(const FarmOptions& options);

}  // namespace impulse::app
