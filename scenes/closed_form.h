// SPDX-License-Identifier: Apache-2.0
#pragma once
// The closed-form theory of a scene as seen through frames of it, for `impulse analyze`
// (analysis::ClosedForm): expected mean, variance, periodogram and autocovariance of a sum of
// layers (Campbell's theorem, design.md §1), the correlation of frames in time, and the sampling
// errors the comparison judges them with (design.md §5). scenes/ builds on analysis/ (design.md
// levels); analysis/ takes this through its interface.

#include <memory>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "scenes/scene.h"
#include "scenes/theory.h"

namespace impulse::scenes {

/// The scene `scene` (a file or a built-in name) with its --set overrides, loaded at `size`
/// (render's --size: the same view at another resolution; {0, 0}: the scene's own), as a closed
/// form for analysis::analyze_frames; nullptr when `scene` is empty. Throws what load_scene
/// throws.
std::unique_ptr<analysis::ClosedForm> closed_form(const std::string& scene,
                                                  const std::vector<std::string>& sets,
                                                  OutputSize size = {});

}  // namespace impulse::scenes
