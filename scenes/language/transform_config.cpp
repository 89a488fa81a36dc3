// SPDX-License-Identifier: Apache-2.0
// [shading.transform]: marble and wood (docs/scenes.md "[shading.transform]").

#include <array>

#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes::detail {

output::FieldTransform read_transform(std::optional<Reader> r, const CameraConfig& camera,
                                      int width, int height, uint64_t scene_seed) {
    using T = output::FieldTransform;
    T t;
    if (!r) return t;
    constexpr std::array<std::string_view, 2> kTypes = {"marble", "wood"};
    if (!r->has("type")) r->fail(nullptr, "type", "missing: expected one of marble, wood");
    const toml::node* type_node = r->node("type");
    t.type = r->choice("type", kTypes, 0) == 0 ? T::Type::Marble : T::Type::Wood;
    // The transform is a function of the texture point of each pixel: the orthographic view
    // gives it; a perspective pixel sees a footprint that a per-pixel sine would alias.
    if (camera.type == CameraConfig::Type::Perspective)
        r->fail(type_node, "type",
                "a transform works on the texture coordinates of each pixel: it needs an "
                "orthographic camera (camera.type = \"perspective\" here)");
    t.turbulence = r->number(
        "turbulence", t.turbulence, [](double v) { return v >= 0.0; },
        t.type == T::Type::Marble ? "a phase perturbation >= 0 (radians per standard deviation)"
                                  : "a ring displacement >= 0 (rings per standard deviation)");
    if (t.type == T::Type::Marble) {
        t.angle_rad = r->number("angle", 0.0);
        t.frequency = r->number(
            "frequency", t.frequency, [](double v) { return v >= 0.0; },
            "a frequency >= 0 (cycles per texture unit)");
        t.phase = r->number("phase", 0.0);
    } else {
        t.center_x = width / 2.0, t.center_y = height / 2.0;
        if (auto c = r->pair("center", "[x, y] in texture units, each within +-1e12", on_plane))
            t.center_x = (*c)[0], t.center_y = (*c)[1];
        t.ring_width = r->number(
            "ring_width", t.ring_width, [](double v) { return v > 0.0; },
            "a ring width > 0 (texture units)");
        t.growth = r->number(
            "growth", 0.0, [](double v) { return v >= 0.0 && v < 1.0; },
            "a ring width irregularity in [0, 1) (0: periodic rings)");
        t.sharpness = r->number(
            "sharpness", t.sharpness, [](double v) { return v >= 1.0 && v <= 100.0; },
            "an exponent in [1, 100] (larger: thinner latewood)");
        const auto seed = static_cast<uint64_t>(r->integer("seed", 1, 0, INT64_MAX));
        t.seed = seed ^ (scene_seed * 0x9E3779B97F4A7C15ull);
    }
    r->finish();
    return t;
}

}  // namespace impulse::scenes::detail
