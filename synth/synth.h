// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::synth — synthesizers other than the shaped point process: generalized stochastic
// subdivision (Lewis 1986 §2, Lewis 1987).

#include "synth/subdivision.h"
