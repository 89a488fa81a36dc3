// SPDX-License-Identifier: Apache-2.0
// The [shading] table: colour ramps (named or explicit), height-field relief, background.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include "output/io_module.h"
#include "numeric/gaussian.h"
#include "numeric/quantile_bins.h"
#include "scenes/detail/loader.h"
#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes::detail {
namespace {

using Ramp = std::vector<output::ColorStop>;

/// Built-in ramps: display value t -> colour and opacity.
const std::map<std::string, Ramp>& named_ramps() {
    static const std::map<std::string, Ramp> ramps = {
        {"grey", {{0.0, 0, 0, 0, 1}, {1.0, 1, 1, 1, 1}}},
        // Clouds over the sky gradient: transparent below the mean, opaque above; thin cloud a
        // cool grey-white, pure white reached only at t = 1 (with a tone shoulder, never quite:
        // thick cloud keeps its gradation instead of a flat white plate).
        {"clouds", {{0.0, 1, 1, 1, 0}, {0.45, 1, 1, 1, 0}, {0.62, 0.88f, 0.90f, 0.95f, 0.85f}, {0.8, 0.95f, 0.96f, 0.98f, 1}, {1.0, 1, 1, 1, 1}}},
        // Fire: black, deep red, orange, yellow, a pale yellow-white core only at t = 1.
        {"fire", {{0.0, 0, 0, 0, 1}, {0.35, 0.5f, 0.02f, 0, 1}, {0.55, 0.92f, 0.3f, 0.02f, 1}, {0.75, 0.98f, 0.7f, 0.15f, 1}, {1.0, 1, 0.97f, 0.8f, 1}}},
        {"ocean", {{0.0, 0.0f, 0.08f, 0.2f, 1}, {0.5, 0.05f, 0.3f, 0.5f, 1}, {0.85, 0.5f, 0.75f, 0.85f, 1}, {1.0, 0.95f, 0.98f, 1, 1}}},
        {"terrain", {{0.0, 0.1f, 0.25f, 0.55f, 1}, {0.4, 0.25f, 0.5f, 0.2f, 1}, {0.65, 0.55f, 0.45f, 0.3f, 1}, {0.85, 0.6f, 0.6f, 0.6f, 1}, {1.0, 1, 1, 1, 1}}},
        {"marble", {{0.0, 0.15f, 0.15f, 0.18f, 1}, {0.3, 0.85f, 0.84f, 0.8f, 1}, {1.0, 0.97f, 0.96f, 0.94f, 1}}},
        {"wood", {{0.0, 0.35f, 0.18f, 0.07f, 1}, {0.5, 0.62f, 0.38f, 0.18f, 1}, {1.0, 0.8f, 0.58f, 0.33f, 1}}},
        {"ink", {{0.0, 0.02f, 0.02f, 0.1f, 1}, {0.5, 0.2f, 0.25f, 0.6f, 1}, {1.0, 0.96f, 0.95f, 0.9f, 1}}},
    };
    return ramps;
}

/// Reads an image's pixels as floats (all channels); false with a message on failure.
bool read_rgb_pixels(const std::string& path, std::vector<float>& px, int& channels, std::string& error) {
    output::Pixels image;
    if (!output::read_pixels(path, image, error)) return false;
    channels = image.channels;
    px = std::move(image.values);
    error = output::nonfinite_pixel(px.data(), px.size(), image.width, channels);
    return error.empty();  // a NaN would break the sort by luminance
}

}  // namespace

/// A colour: [r, g, b] or [r, g, b, a] with components in [0, 1], or "#rrggbb".
bool parse_color(const toml::node& n, float c[4]) {
    c[3] = 1.0f;
    if (auto s = n.value<std::string_view>()) {
        unsigned r, g, b;
        if (s->size() != 7 || std::sscanf(std::string(*s).c_str(), "#%02x%02x%02x", &r, &g, &b) != 3)
            return false;
        c[0] = r / 255.0f, c[1] = g / 255.0f, c[2] = b / 255.0f;
        return true;
    }
    const toml::array* a = n.as_array();
    if (!a || a->size() < 3 || a->size() > 4) return false;
    for (size_t i = 0; i < a->size(); ++i) {
        if (!(*a)[i].is_number()) return false;
        const double v = (*a)[i].value<double>().value_or(-1);
        if (!(v >= 0.0 && v <= 1.0)) return false;
        c[i] = static_cast<float>(v);
    }
    return true;
}

output::Shading read_shading(std::optional<Reader> r, const std::filesystem::path& base,
                             ShadingKeys& keys) {
    output::Shading s;
    keys = ShadingKeys{};
    if (!r) return s;
    if (const toml::node* n = r->node("ramp"); n && n->is_table()) {
        // The colour mapping of a colour exemplar (Lewis 1986 §3 resynthesis in colour): the
        // exemplar's pixels sorted by luminance into `stops` quantile bins, each bin's mean
        // colour placed where the same quantile of the (near-Gaussian) field falls on the
        // display scale, t = (Phi^-1(quantile) + 3) / 6 for the default mean +- 3 sd range.
        Reader t = *r->table("ramp");
        const toml::node* pn = t.node("exemplar");
        const std::string rel = t.string("exemplar", "");
        const int stops = static_cast<int>(t.integer("stops", 16, 2, 256));
        if (rel.empty()) t.fail(pn, "exemplar", "expected the path of a colour image to take the colours from");
        t.finish();
        const std::filesystem::path path = resolve_path(pn, rel, base);
        std::vector<float> px;
        int channels = 0;
        std::string error;
        if (!read_rgb_pixels(path.string(), px, channels, error)) t.fail(pn, "exemplar", error);
        const size_t npix = px.size() / channels;
        if (npix == 0) t.fail(pn, "exemplar", "expected an image with pixels");
        std::vector<float> luminance(npix);
        for (size_t i = 0; i < npix; ++i) {
            const float* c = px.data() + i * channels;
            luminance[i] = channels >= 3 ? 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2] : c[0];
        }
        // Pixel indices with each bin's pixels in its stretch (a bin of fewer pixels than stops
        // is its first pixel).
        const std::vector<size_t> order = numeric::order_into_quantile_bins(luminance, stops);
        for (int b = 0; b < stops; ++b) {
            const size_t i0 = numeric::quantile_bin_start(npix, b, stops),
                         i1 = std::max(i0 + 1, numeric::quantile_bin_start(npix, b + 1, stops));
            double sum[3] = {0, 0, 0};
            for (size_t k = i0; k < i1; ++k)
                for (int ch = 0; ch < 3; ++ch) sum[ch] += px[order[k] * channels + (channels >= 3 ? ch : 0)];
            output::ColorStop cs;
            cs.t = std::clamp((numeric::normal_quantile((b + 0.5) / stops) + 3.0) / 6.0, 0.0, 1.0);
            cs.r = float(sum[0] / (i1 - i0)), cs.g = float(sum[1] / (i1 - i0)), cs.b = float(sum[2] / (i1 - i0));
            s.ramp.push_back(cs);
        }
    } else if (n) {
        if (auto name = n->value<std::string_view>()) {
            auto it = named_ramps().find(std::string(*name));
            if (it == named_ramps().end()) {
                std::string list;
                for (const auto& [k, v] : named_ramps()) list += (list.empty() ? "" : ", ") + k;
                r->fail(n, "ramp", "expected one of " + list + ", or a list of [t, colour] stops");
            }
            s.ramp = it->second;
        } else if (const toml::array* a = n->as_array()) {
            const char* what = "expected stops [t, \"#rrggbb\"] or [t, [r, g, b(, a)]] with t increasing in [0, 1]";
            for (const auto& e : *a) {
                const toml::array* stop = e.as_array();
                if (!stop || stop->size() != 2 || !(*stop)[0].is_number()) r->fail(&e, "ramp", what);
                output::ColorStop cs;
                cs.t = (*stop)[0].value<double>().value_or(-1);
                float c[4];
                if (!(cs.t >= 0.0 && cs.t <= 1.0) || !parse_color((*stop)[1], c)) r->fail(&e, "ramp", what);
                if (!s.ramp.empty() && !(cs.t > s.ramp.back().t)) r->fail(&e, "ramp", what);
                cs.r = c[0], cs.g = c[1], cs.b = c[2], cs.a = c[3];
                s.ramp.push_back(cs);
            }
            if (s.ramp.empty()) r->fail(n, "ramp", what);
        } else {
            r->fail(n, "ramp", "expected a ramp name, a list of stops or { exemplar = \"path\" }, found " + type_name(*n));
        }
    }
    const auto elevation_ok = [](double v) { return v > 0.0 && v <= 90.0; };
    keys.relief = r->keyframed("relief", 0.0, [](double v) { return v >= 0.0; }, "a relief >= 0 (0: flat)");
    if (auto l = r->pair("light", "[azimuth, elevation] in degrees, elevation in (0, 90]")) {
        if (!elevation_ok((*l)[1]))
            r->fail(r->node("light"), "light", "expected [azimuth, elevation] in degrees, elevation in (0, 90]");
        for (const char* k : {"light_azimuth", "light_elevation"})
            if (r->has(k))
                r->fail(r->node(k), k, "give light = [azimuth, elevation] or light_azimuth and light_elevation, not both");
        keys.light_azimuth = (*l)[0];
        keys.light_elevation = (*l)[1];
    }
    if (r->has("light_azimuth")) keys.light_azimuth = r->keyframed("light_azimuth", 135.0);
    if (r->has("light_elevation"))
        keys.light_elevation = r->keyframed("light_elevation", 35.0, elevation_ok, "an elevation in (0, 90] degrees");
    keys.ambient = r->keyframed("ambient", s.ambient, [](double v) { return v >= 0.0 && v <= 1.0; }, "a fraction in [0, 1]");
    // The filmic tone curve's roll-off widths (output::tone_curve): structural, one curve.
    const auto width_ok = [](double v) { return v >= 0.0 && v <= 0.5; };
    s.toe = r->number("toe", 0.0, width_ok, "a width in [0, 0.5] (0: clip at black)");
    s.shoulder = r->number("shoulder", 0.0, width_ok, "a width in [0, 0.5] (0: clip at white)");
    s.relief = keys.relief.value(0.0);
    s.light_azimuth_deg = keys.light_azimuth.value(0.0);
    s.light_elevation_deg = keys.light_elevation.value(0.0);
    s.ambient = keys.ambient.value(0.0);
    // Filtering after shading (docs/shading.md): "after" averages the ramp over the field's
    // sub-pixel distribution where the frame is filtered, "before" shades the filtered value.
    static constexpr std::array<std::string_view, 2> kFilterNames = {"after", "before"};
    s.filter_after = r->choice("filter", kFilterNames, 0) == 0;
    for (const char* key : {"top", "bottom"}) {
        if (const toml::node* n = r->node(key)) {
            float c[4];
            if (!parse_color(*n, c)) r->fail(n, key, "expected a colour \"#rrggbb\" or [r, g, b] in [0, 1]");
            float* dst = std::string(key) == "top" ? s.top : s.bottom;
            dst[0] = c[0], dst[1] = c[1], dst[2] = c[2];
        }
    }
    r->finish();
    return s;
}

}  // namespace impulse::scenes::detail
