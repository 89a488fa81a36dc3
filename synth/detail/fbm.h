// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to impulse::synth: the three fBm methods behind FbmSynth, and their memory needs.

#include <functional>
#include <memory>

#include "synth/synth.h"

namespace impulse::synth {

struct FbmSynth::Impl {
    virtual ~Impl() = default;
    virtual Surface realize(uint64_t seed) const = 0;
    virtual int fft_size() const = 0;
};

namespace detail {

std::unique_ptr<FbmSynth::Impl> make_fourier(const FbmOptions& options);
std::unique_ptr<FbmSynth::Impl> make_incremental(int size,
                                                 const std::function<double(double)>& structure);
std::unique_ptr<FbmSynth::Impl> make_exact(const FbmOptions& options);

/// Peak bytes of each method (its construction or one realisation, whichever is larger).
double fourier_bytes(const FbmOptions& options);
double incremental_bytes(int size);
double exact_bytes(const FbmOptions& options);

/// Side of Stein's embedding torus for an N x N output (see fbm_exact.cpp).
int exact_grid(int size, double hurst);

}  // namespace detail
}  // namespace impulse::synth
