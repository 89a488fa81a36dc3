// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "fbm" | "subdivision" | "solid": a layer drawn by another synthesizer on the
// layer-source seam (scenes/source.h, docs/scenes.md).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>

#include "scenes/loader_detail.h"
#include "scenes/marginal.h"
#include "scenes/source_detail.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {

namespace fs = std::filesystem;

/// A [[layer]] drawn by another synthesizer (source = "fbm", "subdivision", "solid"): its seed,
/// mean, gain, marginal and
/// composition; the impulse process's keys are refused (scenes/source.h).
void read_source_layer(Reader& r, size_t i, uint64_t global_seed, const fs::path& base,
                       const Limits& limits, double zoom, detail::CompositionReader& compose,
                       LayerConfig& L) {
    const std::string kind(detail::kLayerSourceNames[r.choice("source", detail::kLayerSourceNames, 0)]);
    for (std::string_view key : {"kernel", "density", "amplitude", "period", "lifetime", "envelope",
                                 "loop", "integrator", "substeps", "jacobian", "orientation",
                                 "region", "max_travel", "flow"})
        if (r.has(key))
            r.fail(r.node(key), key,
                   "a " + kind + " layer has no " + std::string(key) +
                       ": it belongs to the impulse process (source = \"impulses\")");
    L.process.layer = static_cast<uint32_t>(i);
    L.process.seed = mix_seed(global_seed, static_cast<uint64_t>(r.integer("seed", 1, 0, INT64_MAX)));
    L.mean = r.keyframed("mean", 0.0);
    L.gain = r.keyframed("gain", 1.0);
    if (kind == "fbm") {
        L.source = detail::read_fbm_source(r.table(kind), L.process.seed, limits.max_memory_mib);
    } else if (kind == "solid") {
        L.source = detail::read_solid_source(r.table(kind), L.process.seed, base, zoom);
    } else {
        std::optional<Reader> t = r.table(kind);
        if (!t)
            r.fail(r.node("source"), "source",
                   "a subdivision layer needs its [layer.subdivision] table with acf (markov, "
                   "gaussian, oscillatory_markov, ...) and the model's lengths");
        L.source = detail::read_subdivision_source(&*t, L.process.seed, base, limits.max_memory_mib);
    }
    detail::read_marginal(r, L, base);
    compose.read_layer(r, i, L);
    r.finish();
}

}  // namespace impulse::scenes::detail
