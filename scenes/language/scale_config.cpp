// SPDX-License-Identifier: Apache-2.0
// [layer.scale]: a kernel scale field s(x, t) (docs/scenes.md "Kernel scale fields"; Lewis 1986
// §3.1: "the kernel can be varied as a function of the position"). The fields here give s at each
// impulse's position; render::accumulate draws the scaled kernels (scale classes 1/8 octave
// apart, each impulse split between its two bracketing classes with int h^2 kept).
//
// Every field is evaluated with + - * / and sqrt only (no libm call), so its values, like the
// evaluator's, have the same bits on every machine.

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "output/io_module.h"
#include "scenes/detail/loader.h"

namespace impulse::scenes::detail {
namespace {

namespace fs = std::filesystem;

constexpr double kMinScale = render::kMinKernelScale, kMaxScale = render::kMaxKernelScale;
bool in_range(double v) { return v >= kMinScale && v <= kMaxScale; }
const char* const kRange = "a kernel scale in [0.0625, 16] (four octaves either way)";

/// s = value(t) everywhere.
class ConstantScale final : public ScaleField {
public:
    explicit ConstantScale(numeric::Keyframed value) : m_value(std::move(value)) {}
    void scales(double t_s, size_t n, const double*, const double*, float* s) const override {
        std::fill(s, s + n, static_cast<float>(m_value.value(t_s)));
    }
    double max_scale() const override { return m_value.max(); }
    double min_scale() const override { return m_value.min(); }

private:
    numeric::Keyframed m_value;
};

/// s from values[0] to values[1] linearly in a parameter u in [0, 1] (held beyond): the
/// projection on the segment from -> to (linear), or the distance from the centre over the
/// radius (radial).
class RampScale final : public ScaleField {
public:
    RampScale(bool radial, std::array<double, 2> a, std::array<double, 2> b,
              std::array<double, 2> values)
        : m_radial(radial), m_a(a), m_b(b), m_values(values) {}
    void scales(double, size_t n, const double* x, const double* y, float* s) const override {
        const double dx = m_b[0] - m_a[0], dy = m_b[1] - m_a[1];
        const double inv = m_radial ? 1.0 / m_b[0] : 1.0 / (dx * dx + dy * dy);
        for (size_t i = 0; i < n; ++i) {
            const double px = x[i] - m_a[0], py = y[i] - m_a[1];
            const double u = m_radial ? std::sqrt(px * px + py * py) * inv : (px * dx + py * dy) * inv;
            const double c = std::clamp(u, 0.0, 1.0);
            s[i] = static_cast<float>(m_values[0] + c * (m_values[1] - m_values[0]));
        }
    }
    double max_scale() const override { return std::max(m_values[0], m_values[1]); }
    double min_scale() const override { return std::min(m_values[0], m_values[1]); }

private:
    bool m_radial;
    std::array<double, 2> m_a, m_b;  ///< linear: from, to; radial: centre, {radius, 0}
    std::array<double, 2> m_values;
};

/// A sampled field, bilinear, held at the edges; pixel (i, j) at origin + (i + 0.5, j + 0.5)
/// spacing (as orientation and flow images).
class ImageScale final : public ScaleField {
public:
    ImageScale(int w, int h, std::vector<float> values, double ox, double oy, double spacing)
        : m_w(w), m_h(h), m_values(std::move(values)), m_ox(ox), m_oy(oy), m_spacing(spacing) {
        m_max = *std::max_element(m_values.begin(), m_values.end());
        m_min = *std::min_element(m_values.begin(), m_values.end());
    }
    void scales(double, size_t n, const double* x, const double* y, float* s) const override {
        for (size_t i = 0; i < n; ++i) {
            const double u = std::clamp((x[i] - m_ox) / m_spacing - 0.5, 0.0, m_w - 1.0);
            const double v = std::clamp((y[i] - m_oy) / m_spacing - 0.5, 0.0, m_h - 1.0);
            const int i0 = std::min(static_cast<int>(u), m_w - 1), j0 = std::min(static_cast<int>(v), m_h - 1);
            const int i1 = std::min(i0 + 1, m_w - 1), j1 = std::min(j0 + 1, m_h - 1);
            const double fu = u - i0, fv = v - j0;
            auto at = [&](int a, int b) { return double(m_values[size_t(b) * m_w + a]); };
            const double top = at(i0, j0) + fu * (at(i1, j0) - at(i0, j0));
            const double bottom = at(i0, j1) + fu * (at(i1, j1) - at(i0, j1));
            s[i] = static_cast<float>(top + fv * (bottom - top));
        }
    }
    double max_scale() const override { return m_max; }
    double min_scale() const override { return m_min; }

private:
    int m_w, m_h;
    std::vector<float> m_values;
    double m_ox, m_oy, m_spacing, m_max = 1.0, m_min = 1.0;
};

/// A required [x, y] point.
std::array<double, 2> required_point(Reader& f, std::string_view key) {
    auto p = f.pair(key, "[x, y] in texture units");
    if (!p) f.fail(nullptr, key, "missing: expected [x, y] in texture units");
    return *p;
}

/// values = [s0, s1], both kernel scales.
std::array<double, 2> ramp_values(Reader& f) {
    static const std::string kExpected = std::string("[s0, s1], each ") + kRange;
    auto v = f.pair("values", kExpected.c_str(), in_range);
    if (!v) f.fail(nullptr, "values", "missing: expected " + kExpected);
    return *v;
}

/// type = "linear": from `from` (values[0]) to `to` (values[1]).
std::shared_ptr<const ScaleField> read_linear_scale(Reader& f) {
    const auto a = required_point(f, "from"), b = required_point(f, "to");
    if (a == b) f.fail(f.node("to"), "to", "expected a point other than `from`");
    return std::make_shared<RampScale>(false, a, b, ramp_values(f));
}

/// type = "radial": values[0] at `center`, values[1] at `radius` and beyond.
std::shared_ptr<const ScaleField> read_radial_scale(Reader& f) {
    const auto c = required_point(f, "center");
    if (!f.has("radius")) f.fail(nullptr, "radius", "missing: expected a radius > 0 in texture units");
    const double r = f.number("radius", 1.0, kPositive, "a radius > 0 in texture units");
    return std::make_shared<RampScale>(true, c, std::array<double, 2>{r, 0.0}, ramp_values(f));
}

/// type = "image": 1 channel; float images hold s, integer images map [0, 1] to `range`.
std::shared_ptr<const ScaleField> read_image_scale(Reader& f, const fs::path& base) {
    const toml::node* pn = f.node("path");
    const std::string rel = f.string("path", "");
    if (rel.empty()) f.fail(pn, "path", "expected the path of a 1-channel kernel scale image");
    std::string error;
    output::Pixels px;
    const auto one = [](int channels) {
        return channels == 1 ? std::string()
                             : "expected an image with 1 channel (the kernel scale), found " +
                                   std::to_string(channels);
    };
    if (!output::read_pixels(resolve_path(pn, rel, base).string(), px, error, one))
        f.fail(pn, "path", error);
    std::array<double, 2> range{1.0, 2.0};
    if (auto r = f.pair("range", "[s0, s1]: the scales of grey levels 0 and 1 (integer images)",
                        in_range))
        range = *r;
    for (size_t i = 0; i < px.values.size(); ++i) {
        float& v = px.values[i];
        if (!px.is_float) v = static_cast<float>(range[0] + v * (range[1] - range[0]));
        if (in_range(v)) continue;  // false for NaN
        std::ostringstream m;
        m << "scale image: found " << v << " at pixel (" << i % px.width << ", " << i / px.width
          << "): expected " << kRange;
        f.fail(pn, "path", m.str());
    }
    const double spacing = f.number("spacing", 1.0, kPositive, "texture units per image pixel, > 0");
    double ox = 0.0, oy = 0.0;
    if (auto o = f.pair("origin", "[x, y] in texture units")) ox = (*o)[0], oy = (*o)[1];
    return std::make_shared<ImageScale>(px.width, px.height, std::move(px.values), ox, oy, spacing);
}

/// Refuses what the scale field cannot be drawn with (one line at the key).
void check_scale_use(Reader& layer, const LayerConfig& L) {
    if (L.marginal)
        layer.fail(layer.node("scale"), "scale",
                   "a kernel scale field changes the impulses per kernel from place to place, "
                   "so the layer's value law: remove [layer.marginal]");
}

}  // namespace

void read_scale(Reader& layer, const fs::path& base, LayerConfig& L) {
    if (!layer.has("scale")) return;
    check_scale_use(layer, L);
    const toml::node* n = layer.node("scale");
    if (n->is_number() || (n->is_table() && n->as_table()->contains("keys"))) {
        // A number or keyframes: the constant field.
        L.scale = std::make_shared<ConstantScale>(layer.keyframed("scale", 1.0, in_range, kRange));
        return;
    }
    static const char* kTypes = "linear, radial, image, constant";
    if (!n->is_table())
        layer.fail(n, "scale",
                   std::string("expected a number (") + kRange + ") or a field table with type = " +
                       kTypes);
    Reader f = *layer.table("scale");
    constexpr std::array<std::string_view, 4> types = {"linear", "radial", "image", "constant"};
    if (!f.has("type")) f.fail(nullptr, "type", std::string("missing: expected one of ") + kTypes);
    switch (f.choice("type", types, 0)) {
        case 0: L.scale = read_linear_scale(f); break;
        case 1: L.scale = read_radial_scale(f); break;
        case 2: L.scale = read_image_scale(f, base); break;
        default:
            L.scale = std::make_shared<ConstantScale>(f.keyframed("value", 1.0, in_range, kRange));
    }
    f.finish();
}

}  // namespace impulse::scenes::detail
