// SPDX-License-Identifier: Apache-2.0
// [layer.region]: where a layer's impulses may be born (docs/scenes.md "[layer.region]").

#include <array>
#include <cmath>
#include <filesystem>

#include "output/output.h"
#include "render/render.h"
#include "scenes/detail/reader.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {
namespace {

namespace fs = std::filesystem;

const auto kPositive = [](double v) { return v > 0.0; };

/// Shape types, then the combinations (in sim::ShapeOp order), then the image mask.
constexpr std::array<std::string_view, 9> kRegionTypes = {
    "circle", "ellipse", "box", "capsule", "polygon", "union", "intersection", "subtract", "image"};
constexpr size_t kFirstOp = 5, kImage = 8;

std::string type_list(size_t n) {
    std::string list;
    for (size_t i = 0; i < n; ++i) list += (i ? ", " : "") + std::string(kRegionTypes[i]);
    return list;
}

/// A required [x, y] point.
std::array<double, 2> point(Reader& r, std::string_view key) {
    auto p = r.pair(key, "[x, y] in texture units");
    if (!p) r.fail(nullptr, key, "missing: expected [x, y] in texture units");
    return *p;
}

/// A required number > 0.
double positive(Reader& r, std::string_view key, const char* expected) {
    if (!r.has(key)) r.fail(nullptr, key, std::string("missing: expected ") + expected);
    return r.number(key, 0.0, kPositive, expected);
}

/// A shape table; combinations hold a list `shapes` of shape tables (nested at will).
std::shared_ptr<const sim::Shape> read_shape(Reader& r, size_t type) {
    switch (type) {
        case 0: {  // circle
            const auto c = point(r, "center");
            return sim::make_circle_shape(c[0], c[1],
                                          positive(r, "radius", "a radius > 0 (texture units)"));
        }
        case 1: {  // ellipse
            const auto c = point(r, "center");
            if (!r.has("radii")) r.fail(nullptr, "radii", "missing: expected [a, b] semi-axes > 0");
            const auto ab = *r.pair("radii", "[a, b] semi-axes > 0 (texture units)", kPositive);
            return sim::make_ellipse_shape(c[0], c[1], ab[0], ab[1], r.number("angle", 0.0));
        }
        case 2: {  // box
            const auto c = point(r, "center");
            if (!r.has("size")) r.fail(nullptr, "size", "missing: expected [width, height] > 0");
            const auto wh = *r.pair("size", "[width, height] > 0 (texture units)", kPositive);
            const double half = 0.5 * std::min(wh[0], wh[1]);
            const double corner = r.number(
                "corner", 0.0, [&](double v) { return v >= 0.0 && v <= half; },
                "a corner radius in [0, half the smaller side]");
            return sim::make_box_shape(c[0], c[1], 0.5 * wh[0], 0.5 * wh[1],
                                       r.number("angle", 0.0), corner);
        }
        case 3: {  // capsule
            const auto a = point(r, "from"), b = point(r, "to");
            return sim::make_capsule_shape(a[0], a[1], b[0], b[1],
                                           positive(r, "radius", "a radius > 0 (texture units)"));
        }
        case 4: {  // polygon
            const toml::node* pn = r.node("points");
            const toml::array* a = pn ? pn->as_array() : nullptr;
            static const char* kPoints = "expected at least 3 [x, y] points, not all on one line";
            if (!a) r.fail(pn, "points", pn ? kPoints : "missing: expected [[x, y], ...], 3 or more");
            std::vector<std::array<double, 2>> pts;
            for (const auto& e : *a) {
                const toml::array* q = e.as_array();
                if (!q || q->size() != 2 || !(*q)[0].is_number() || !(*q)[1].is_number())
                    r.fail(pn, "points", kPoints);
                pts.push_back({(*q)[0].value<double>().value_or(0), (*q)[1].value<double>().value_or(0)});
            }
            const auto rule = static_cast<sim::FillRule>(r.choice("fill", sim::kFillRuleNames, 1));
            std::shared_ptr<const sim::Shape> polygon;
            try {
                polygon = sim::make_polygon_shape(std::move(pts), rule);
            } catch (const ValueError&) {  // too few points, non-finite or all on one line
                r.fail(pn, "points", kPoints);
            }
            return polygon;
        }
        default: {  // union, intersection, subtract
            auto list = r.tables("shapes");
            if (list.empty())
                r.fail(r.node("shapes"), "shapes",
                       "missing: expected a list of shapes ([[...shapes]] tables)");
            std::vector<std::shared_ptr<const sim::Shape>> parts;
            for (auto& s : list) {
                if (!s.has("type"))
                    s.fail(nullptr, "type", "missing: expected one of " + type_list(kImage));
                const size_t t = s.choice_impl(
                    "type", std::vector<std::string_view>(kRegionTypes.begin(), kRegionTypes.begin() + kImage), 0);
                parts.push_back(read_shape(s, t));
                s.finish();
            }
            return sim::make_combined_shape(static_cast<sim::ShapeOp>(type - kFirstOp),
                                            std::move(parts));
        }
    }
}

}  // namespace

void read_region(Reader& layer, sim::ProcessConfig& process, const fs::path& base) {
    auto t = layer.table("region");
    if (!t) return;
    Reader& r = *t;
    if (!r.has("type")) r.fail(nullptr, "type", "missing: expected one of " + type_list(kRegionTypes.size()));
    const size_t type = r.choice("type", kRegionTypes, 0);
    const bool invert = r.boolean("invert", false);
    if (type == kImage) {
        // A grey mask: luminance of RGB, the first channel otherwise (output::read_image);
        // integer formats in [0, 1], float ones must lie there.
        if (r.has("feather"))
            r.fail(r.node("feather"), "feather",
                   "applies to shapes: an image mask's grey levels are its soft edge");
        const toml::node* pn = r.node("path");
        const std::string rel = r.string("path", "");
        if (rel.empty()) r.fail(pn, "path", "expected the path of a grey mask image");
        const fs::path path = fs::path(rel).is_absolute() ? fs::path(rel) : base / rel;
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) r.fail(pn, "path", "cannot read: no such file");
        sim::MaskGrid g;
        try {
            render::Frame f = output::read_image(path.string());
            g.width = f.width, g.height = f.height, g.values = std::move(f.data);
        } catch (const Error& e) {
            r.fail(pn, "path", e.what());
        }
        g.spacing = r.number("spacing", 1.0, kPositive, "texture units per image pixel, > 0");
        if (auto o = r.pair("origin", "[x, y] in texture units")) g.origin_x = (*o)[0], g.origin_y = (*o)[1];
        try {
            process.region = sim::make_mask_region(std::move(g), invert);
        } catch (const ValueError& e) {
            r.fail(pn, "path", e.what());
        }
        r.finish();
        return;
    }
    const double feather = r.number(
        "feather", 0.0, [](double v) { return v >= 0.0; },
        "a soft-edge width >= 0 (texture units; 0: a hard edge)");
    process.region = sim::make_shape_region(read_shape(r, type), feather, invert);
    r.finish();
}

}  // namespace impulse::scenes::detail
