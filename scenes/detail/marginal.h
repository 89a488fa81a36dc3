// SPDX-License-Identifier: Apache-2.0
#pragma once
// A layer's `marginal` key: distribution shaping g = F_y^-1(F_x(.)) (Lewis 1986 §4) and the
// optional spectrum pre-correction (kernels/shaping.h). Internal to impulse::scenes.

#include <filesystem>
#include <memory>

#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes::detail {

/// Reads `marginal = { type = ..., <parameters>, precorrect = false, cdf = "gaussian" }` from a
/// [[layer]] whose kernel, density, amplitude, lifetime, envelope, mean, gain and process
/// intensity are already set; fills layer.marginal, layer.marginal_cdf and, with
/// precorrect = true, replaces layer.kernel and sets layer.precorrection. Does nothing when the
/// key is absent. Throws SceneError at the offending key.
void read_marginal(Reader& layer_reader, LayerConfig& layer, const std::filesystem::path& base);

/// The transfer g for an impulse layer with cdf = "shot_noise" (the default) at layer time t_s:
/// F_x the exact law of the unshaped layer (kernels::ShotNoiseCdf) for its kernel at t_s,
/// amplitude law, gain, envelope and birth thinning over the last lifetime (256 ages), and
/// density; `values` is the kernel's value law when the kernel is fixed (null: computed here,
/// ~10-50 ms). Deterministic. Throws ValueError for a layer of variance 0.
std::shared_ptr<const kernels::MarginalTransform> shot_noise_marginal(
    const LayerConfig& layer, const kernels::MarginalParams& target, double t_s,
    const kernels::KernelValueLaw* values);

/// The transfer for a layer with cdf = "empirical": F_x measured on a calibration render of the
/// layer's own values (gain and mean applied) at frame 0: 1024 x 1024 samples over a square of
/// side min(256 R, sqrt(2e6 / lambda)) texture units from the origin (R the kernel radius,
/// about 2 million impulses at most), so the sample holds thousands of correlation areas.
/// Deterministic: a pure function of the layer.
std::shared_ptr<const kernels::MarginalTransform> calibrate_marginal(const LayerConfig& layer,
                                                                     const sim::Timing& timing);

}  // namespace impulse::scenes::detail
