// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::sim — the shaped Poisson point process as a particle system (Lewis 1986 §3.1):
// consistent cell-seeded births in space and time, flows, integration, the Jacobian
// compensation and orientation, and the set of live impulses at any frame.
// Knows nothing of rendering, cameras or the command line.

#include "numeric/box.h"
#include "numeric/keyframed.h"
#include "sim/amplitude.h"          // amplitude laws, temporal envelopes
#include "sim/birth_region.h"       // shapes and masks that thin births
#include "sim/flow.h"               // flows: velocity, divergence, curl
#include "sim/frame_window.h"       // the frames of a sampled sequence in use
#include "sim/layout.h"             // seeding cells in space and time
#include "sim/normal.h"             // the normal amplitude, the same bits on every CPU
#include "sim/orientation.h"        // orientation fields
#include "sim/process.h"            // ProcessConfig: what defines a layer's impulses
#include "sim/simulator.h"          // LayerSimulator: the live impulses at any frame
#include "sim/stream.h"             // a layer's field as a stream function
#include "sim/velocity_sequence.h"  // sampled flows that vary in time

namespace impulse::sim {

// Time-varying scalars and texture-space boxes come from the base library.
using numeric::Box;
using numeric::Ease;
using numeric::Keyframed;
using numeric::Region;

}  // namespace impulse::sim
