// SPDX-License-Identifier: Apache-2.0
// [[layer.flow]]: the flows that carry a layer's impulses (docs/scenes.md "[[layer.flow]]").

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>

#include "output/io_module.h"
#include "scenes/detail/loader.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {

namespace fs = std::filesystem;

std::pair<numeric::Keyframed, numeric::Keyframed> read_uniform_velocity(Reader& f) {
    numeric::Keyframed vx(0.0), vy(0.0);
    if (f.node("velocity")) {
        auto v = f.pair("velocity", "[vx, vy] in units per second");
        vx = numeric::Keyframed((*v)[0]);
        vy = numeric::Keyframed((*v)[1]);
    }
    if (f.has("vx")) vx = f.keyframed("vx", 0.0);
    if (f.has("vy")) vy = f.keyframed("vy", 0.0);
    return {vx, vy};
}

std::shared_ptr<sim::Flow> read_flows(
    Reader& layer, const sim::ProcessConfig& process, const fs::path& base,
    detail::CompositionReader& compose, size_t index,
    std::vector<std::pair<numeric::Keyframed, numeric::Keyframed>>* uniform) {
    auto list = layer.tables("flow");
    if (list.empty()) return nullptr;
    if (process.lifetime_s <= 0)
        layer.fail(layer.node("flow"), "flow",
                   "a flow moves particles that are born and die: set lifetime > 0 in this layer");
    auto sum = std::make_shared<sim::FlowSum>();
    const std::array<std::string_view, 8> types = {"uniform", "shear", "vortex", "source",
                                                   "curl",    "image", "layer",  "sequence"};
    for (auto& f : list) {
        if (!f.has("type"))
            f.fail(nullptr, "type",
                   "missing: expected one of uniform, shear, vortex, source, curl, image, layer, sequence");
        const size_t type = f.choice("type", types, 0);
        auto center = [&](numeric::Keyframed& x, numeric::Keyframed& y) {
            const toml::node* n = f.node("center");
            if (!n) {
                x = f.keyframed("center_x", 0.0);
                y = f.keyframed("center_y", 0.0);
                return;
            }
            auto p = f.pair("center", "[x, y] in texture units");
            x = numeric::Keyframed((*p)[0]);
            y = numeric::Keyframed((*p)[1]);
            f.node("center_x"), f.node("center_y");
        };
        switch (type) {
            case 0: {  // uniform
                const auto [vx, vy] = read_uniform_velocity(f);
                if (uniform) uniform->push_back({vx, vy});
                sum->push(sim::make_uniform_flow(vx, vy));
                break;
            }
            case 1: {  // shear
                auto rate = f.keyframed("rate", 0.1);
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto angle = f.keyframed("angle", 0.0);
                sum->push(sim::make_shear_flow(rate, cx, cy, angle));
                break;
            }
            case 2: {  // vortex
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto gamma = f.keyframed("circulation", 2000.0);
                auto core = f.keyframed("core", 40.0, kPositive, "a radius > 0");
                const auto model = static_cast<sim::VortexModel>(f.choice("model", sim::kVortexModelNames, 0));
                sum->push(sim::make_vortex_flow(model, cx, cy, gamma, core));
                break;
            }
            case 3: {  // source / sink
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto rate = f.keyframed("rate", 0.1);
                auto radius = f.keyframed("radius", 0.0, kNonNegative, "a radius >= 0 (0: everywhere)");
                if (!radius.is_constant() && !(radius.min() > 0))
                    f.fail(f.node("radius"), "radius",
                           "expected a radius > 0 at every key (radius 0, a divergence everywhere, "
                           "is another field, not a limit of this one)");
                sum->push(sim::make_source_flow(cx, cy, rate, radius));
                break;
            }
            case 4: {  // curl noise
                const double scale = f.number(
                    "scale", 64.0,
                    [](double v) { return v >= sim::kMinCurlScale && v <= sim::kMaxCurlScale; },
                    "a length in [1e-3, 1e9] texture units");
                auto speed = f.keyframed("speed", 10.0, kNonNegative, "a speed >= 0");
                const uint64_t seed = static_cast<uint64_t>(f.integer("seed", 1, 0, INT64_MAX));
                sum->push(sim::make_curl_noise_flow(mix_seed(process.seed, seed), scale, speed, process.period));
                break;
            }
            case 5: {  // image
                const toml::node* pn = f.node("path");
                const std::string rel = f.string("path", "");
                if (rel.empty()) f.fail(pn, "path", "expected the path of a 2-channel velocity image");
                const fs::path p = detail::resolve_path(pn, rel, base);
                std::string error;
                output::Pixels px;
                const auto need_two = [](int n) {
                    return n >= 2 ? std::string()
                                  : "expected an image with 2 or more channels (vx, vy), found " +
                                        std::to_string(n);
                };
                if (!output::read_pixels(p.string(), px, error, need_two)) f.fail(pn, "path", error);
                sim::VectorGrid g;
                g.width = px.width, g.height = px.height;
                // Integer images store [0, 1]: map to [-1, 1] so grey means still.
                const size_t nc = size_t(px.channels);
                for (size_t i = 0; i < size_t(g.width) * g.height; ++i) {
                    float vx = px.values[i * nc], vy = px.values[i * nc + 1];
                    if (!px.is_float) vx = 2 * vx - 1, vy = 2 * vy - 1;
                    g.vx.push_back(vx), g.vy.push_back(vy);
                }
                g.spacing = f.number("spacing", 1.0, kPositive, "texture units per image pixel, > 0");
                if (auto o = f.pair("origin", "[x, y] in texture units")) g.origin_x = (*o)[0], g.origin_y = (*o)[1];
                auto gain = f.keyframed("gain", 1.0);
                try {
                    sum->push(sim::make_grid_flow(std::move(g), gain));
                } catch (const ValueError& e) {
                    f.fail(pn, "path", e.what());
                }
                break;
            }
            case 6:  // another layer's field as stream function (scenes/language/compose_config.cpp)
                compose.read_flow(f, index, *sum);
                break;
            case 7:  // a velocity sequence from files (scenes/sequence_config.cpp)
                read_sequence_flow(f, process, layer, base, *sum);
                break;
        }
        f.finish();
    }
    return sum;
}

}  // namespace impulse::scenes::detail
