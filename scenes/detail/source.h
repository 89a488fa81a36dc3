// SPDX-License-Identifier: Apache-2.0
#pragma once
// Layer sources read from scene files (internal to impulse::scenes): [[layer]] source = "fbm",
// "subdivision" or "solid".

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string_view>

#include "scenes/detail/reader.h"
#include "scenes/source.h"

namespace impulse::scenes::detail {

/// The values of a [[layer]]'s `source` key: "impulses" (the default) draws the point process.
inline constexpr std::array<std::string_view, 4> kLayerSourceNames = {"impulses", "fbm",
                                                                        "subdivision", "solid"};

/// What limits.max_memory_mib leaves the next source layer's tile while the scene loads. The
/// tiles are made as their layers are read and stay, so the limit bounds the tiles held so far
/// plus the peak of the one being made, not each tile alone (a scene of many fbm layers, each
/// within the limit, once held their sum before the Renderer's estimate refused it).
struct TileBudget {
    double limit_mib = 0.0;  ///< limits.max_memory_mib
    double held_mib = 0.0;   ///< the tiles of the source layers read before this one
    /// Throws SceneError at `t`'s `key` when making a tile needs `need_mib` at its peak and that
    /// does not fit beside the tiles held; `what` names it ("the surface", "the field").
    void check(Reader& t, std::string_view key, std::string_view what, double need_mib) const;
};

/// A fractional Brownian surface layer from its [layer.fbm] table (absent: the defaults; then
/// `layer`, the [[layer]] table, is where a budget error points) and the layer's seed: the
/// realised grid is made here, once. Throws SceneError at the key, also when making it does not
/// fit the budget.
std::shared_ptr<const LayerSource> read_fbm_source(std::optional<Reader> fbm, Reader& layer,
                                                   uint64_t seed, const TileBudget& budget);
/// A generalized stochastic subdivision layer from its [layer.subdivision] table (acf and the
/// model's keys, lengths in texture units; samples, size, neighbors, displacement) and the
/// layer's seed. Throws SceneError at the key, also when making it does not fit the budget.
std::shared_ptr<const LayerSource> read_subdivision_source(Reader* subdivision, uint64_t seed,
                                                           const std::filesystem::path& base,
                                                           const TileBudget& budget);

/// A slice of solid noise from its [layer.solid] table (absent: the defaults) and the layer's
/// seed; `base` resolves a designed kernel's table, `zoom` (the camera's smallest, pixels per
/// unit) sets a designed kernel's default nyquist 0.5 zoom and the aliasing warning of an
/// analytic kernel under 2 pixels (not given under a perspective camera, which filters the
/// gaussian kernel by the footprint and refuses the others). Throws SceneError at the key.
std::shared_ptr<const LayerSource> read_solid_source(std::optional<Reader> solid, uint64_t seed,
                                                     const std::filesystem::path& base, double zoom,
                                                     bool perspective);

}  // namespace impulse::scenes::detail
