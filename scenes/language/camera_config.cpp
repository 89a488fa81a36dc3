// SPDX-License-Identifier: Apache-2.0
// [camera] beyond the orthographic center/zoom (type, perspective placement, anti-aliasing) and
// layer.orientation fields (docs/scenes.md).

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <limits>
#include <sstream>

#include "output/io_module.h"
#include "scenes/detail/camera.h"
#include "scenes/detail/loader.h"
#include "numeric/errors.h"

namespace impulse::scenes {

render::PerspectiveCamera CameraConfig::perspective(int width, int height, double t) const {
    render::PerspectiveCamera c;
    c.width = width, c.height = height;
    c.x = position_x.value(t), c.y = position_y.value(t);
    c.altitude = altitude.value(t);
    c.pitch_deg = pitch.value(t);
    c.heading_deg = heading.value(t);
    c.fov_deg = fov.value(t);
    c.plane = plane;
    return c;
}

bool CameraConfig::antialiased() const {
    switch (antialias) {
        case AntiAliasMode::Off:
            return false;
        case AntiAliasMode::Blend:
        case AntiAliasMode::Nearest:
            return true;
        case AntiAliasMode::Auto:
            break;
    }
    if (type == Type::Perspective) return true;
    for (const auto& k : zoom.keys)
        if (k.second < 1.0) return true;
    return false;
}

render::AntiAlias CameraConfig::antialias_options() const {
    render::AntiAlias a;
    a.enabled = antialias != AntiAliasMode::Off;
    a.blend = antialias != AntiAliasMode::Nearest;
    a.anisotropic = anisotropic;
    a.filter_px = filter;
    a.cutoff = cutoff;
    return a;
}

sim::Shutter CameraConfig::shutter_at(double fps, const kernels::KernelCurvature& k) const {
    sim::Shutter s;
    s.open_s = shutter_open / fps;
    s.close_s = (shutter_open + shutter) / fps;
    // The midpoint rule over n strata of a straight path of length D misses the path's mean
    // of h by at most (D / n)^2 max|h''| / 24: within shutter_error of the peak when the
    // travel per copy is at most sqrt(24 shutter_error peak / max|h''|).
    s.max_step = k.curvature > 0.0 ? std::sqrt(24.0 * shutter_error * k.peak / k.curvature)
                                    : std::numeric_limits<double>::infinity();
    return s;
}

namespace detail {
namespace {

namespace fs = std::filesystem;

}  // namespace

namespace {

/// shutter, shutter_offset and shutter_error (docs/motion_blur.md).
void read_shutter(Reader& r, CameraConfig& c) {
    c.shutter = r.number(
        "shutter", 0.0, [](double v) { return v >= 0.0 && v <= 1.0; },
        "a fraction of the frame interval in [0, 1] (0: no motion blur, 0.5: a 180-degree "
        "shutter)");
    c.shutter_open = -0.5 * c.shutter;
    const toml::node* n = r.node("shutter_offset");
    if (n && n->is_string()) {
        const std::array<std::string_view, 3> names = {"center", "start", "end"};
        const size_t k = r.choice("shutter_offset", names, 0);
        c.shutter_open = k == 0 ? -0.5 * c.shutter : k == 1 ? 0.0 : -c.shutter;
    } else if (n) {
        c.shutter_open = r.number(
            "shutter_offset", 0.0, [](double v) { return v >= -1.0 && v <= 1.0; },
            "\"center\", \"start\", \"end\" or the shutter's opening in frame intervals from "
            "the frame, in [-1, 1]");
    }
    c.shutter_error = r.number(
        "shutter_error", 1e-3, [](double v) { return v > 0.0 && v <= 1.0; },
        "a fraction in (0, 1] of an impulse's peak");
}

}  // namespace

void read_camera_view(Reader& r, CameraConfig& c, int width, int height) {
    const std::array<std::string_view, 2> types = {"orthographic", "perspective"};
    c.type = r.choice("type", types, 0) == 1 ? CameraConfig::Type::Perspective
                                             : CameraConfig::Type::Orthographic;
    const bool persp = c.type == CameraConfig::Type::Perspective;
    static const char* kPerspKeys[] = {"position", "position_x", "position_y", "height",
                                       "pitch",    "heading",    "fov",        "plane"};
    static const char* kOrthoKeys[] = {"center", "center_x", "center_y", "zoom"};
    if (!persp) {
        for (const char* k : kPerspKeys)
            if (r.has(k))
                r.fail(r.node(k), k, "applies to perspective cameras (set type = \"perspective\")");
    } else {
        for (const char* k : kOrthoKeys)
            if (r.has(k))
                r.fail(r.node(k), k,
                       "applies to orthographic cameras; a perspective camera is placed with "
                       "position, height, pitch, heading and fov");
        c.position_x = numeric::Keyframed(width / 2.0);
        c.position_y = numeric::Keyframed(height / 2.0);
        if (r.node("position")) {
            auto p = r.pair("position",
                            "[x, y]: the camera's foot on the plane, texture units, each within "
                            "+-1e12",
                            on_plane);
            c.position_x = numeric::Keyframed((*p)[0]);
            c.position_y = numeric::Keyframed((*p)[1]);
        }
        if (r.has("position_x"))
            c.position_x = r.keyframed("position_x", width / 2.0, on_plane, kOnPlane);
        if (r.has("position_y"))
            c.position_y = r.keyframed("position_y", height / 2.0, on_plane, kOnPlane);
        c.altitude =
            r.keyframed("height", 100.0, kPositive, "a height > 0 above the plane (texture units)");
        c.pitch = r.keyframed(
            "pitch", 20.0, [](double v) { return v >= -90.0 && v <= 90.0; },
            "an angle in [-90, 90] degrees below the horizon (above it for the sky)");
        c.heading = r.keyframed("heading", 0.0);
        c.fov = r.keyframed(
            "fov", 60.0, [](double v) { return v > 0.0 && v < 180.0; },
            "a vertical field of view in (0, 180) degrees");
        const std::array<std::string_view, 2> planes = {"ground", "sky"};
        c.plane = r.choice("plane", planes, 0) == 1 ? render::Plane::Sky : render::Plane::Ground;
        // The camera must see some of the plane at every time.
        for (double t : key_check_times({&c.pitch, &c.fov, &c.altitude})) {
            try {
                render::PerspectiveView v(c.perspective(width, height, t));
            } catch (const ValueError&) {
                const double p = c.pitch.value(t), f = c.fov.value(t);
                std::ostringstream m;
                m << "the camera sees no part of the "
                  << (c.plane == render::Plane::Ground ? "ground" : "sky") << " plane";
                if (!c.pitch.is_constant() || !c.fov.is_constant()) m << " at t = " << t << " s";
                m << " (pitch " << num(p) << ", fov " << num(f)
                  << "): expected pitch > -fov/2 = " << num(-0.5 * f) << " degrees "
                  << (c.plane == render::Plane::Ground ? "below" : "above") << " the horizon";
                r.fail(r.node("pitch") ? r.node("pitch") : r.node("fov"), "pitch", m.str());
            }
        }
    }
    const std::array<std::string_view, 4> modes = {"auto", "blend", "nearest", "off"};
    c.antialias = static_cast<CameraConfig::AntiAliasMode>(r.choice("antialias", modes, 0));
    c.filter = r.number(
        "filter", 0.5, [](double v) { return v >= 0.1 && v <= 8.0; },
        "a pixel filter standard deviation in [0.1, 8] pixels");
    c.cutoff = r.number(
        "cutoff", 0.01, [](double v) { return v >= 1e-6 && v <= 0.5; },
        "a fraction in [1e-6, 0.5] of the texture's standard deviation");
    c.anisotropic = r.boolean("anisotropic", true);
    read_shutter(r, c);
    if (auto sea = r.table("sea")) read_sea(*sea, c, width, height);
}

namespace {

/// center = [x, y], or center_x / center_y (which may be keyframed), of a radial or circular
/// field.
void read_field_center(Reader& f, numeric::Keyframed& x, numeric::Keyframed& y) {
    if (f.node("center")) {
        auto c = f.pair("center", "[x, y] in texture units");
        x = numeric::Keyframed((*c)[0]);
        y = numeric::Keyframed((*c)[1]);
    } else if (f.has("center_x") || f.has("center_y")) {
        x = f.keyframed("center_x", 0.0);
        y = f.keyframed("center_y", 0.0);
    } else {
        f.fail(nullptr, "center", "missing: expected [x, y] in texture units");
    }
    f.node("center_x"), f.node("center_y");
}

/// type = "radial" or "circular": along or around the (keyframed) center.
std::shared_ptr<sim::OrientationField> read_centered_orientation(Reader& f, bool radial) {
    numeric::Keyframed cx, cy;
    read_field_center(f, cx, cy);
    if (radial) return sim::make_radial_orientation(cx, cy);
    return sim::make_circular_orientation(cx, cy, f.boolean("clockwise", false));
}

/// type = "polyline": along the nearest segment of points = [[x, y], ...], smoothed.
std::shared_ptr<sim::OrientationField> read_polyline_orientation(Reader& f) {
    const toml::node* pn = f.node("points");
    const toml::array* a = pn ? pn->as_array() : nullptr;
    static const char* kPoints = "expected at least two [x, y] points, consecutive points distinct";
    if (!a || a->size() < 2) f.fail(pn, "points", kPoints);
    std::vector<std::array<double, 2>> pts;
    for (const auto& e : *a) {
        const toml::array* q = e.as_array();
        if (!q || q->size() != 2 || !(*q)[0].is_number() || !(*q)[1].is_number())
            f.fail(pn, "points", kPoints);
        const std::array<double, 2> v{(*q)[0].value<double>().value_or(0),
                                      (*q)[1].value<double>().value_or(0)};
        if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || (!pts.empty() && pts.back() == v))
            f.fail(pn, "points", kPoints);
        pts.push_back(v);
    }
    const numeric::Keyframed smooth = f.keyframed(
        "smooth", 0.0, [](double v) { return v >= 0.0; },
        "a distance >= 0 in texture units (0: nearest segment)");
    return sim::make_polyline_orientation(std::move(pts), smooth);
}

/// type = "sine": along a sine wave of the given amplitude, wavelength, phase and direction.
std::shared_ptr<sim::OrientationField> read_sine_orientation(Reader& f) {
    const numeric::Keyframed amp = f.keyframed("amplitude", 16.0);
    const numeric::Keyframed wl =
        f.keyframed("wavelength", 128.0, kPositive, "a wavelength > 0 (texture units)");
    const numeric::Keyframed phase = f.keyframed("phase", 0.0);
    const numeric::Keyframed angle = f.keyframed("angle", 0.0);
    double ox = 0.0, oy = 0.0;
    if (auto o = f.pair("origin", "[x, y] in texture units")) ox = (*o)[0], oy = (*o)[1];
    return sim::make_sine_orientation(amp, wl, phase, angle, ox, oy);
}

/// The pixels of an orientation image (1 channel: angle; 2: direction), failing at `pn`.
sim::OrientationGrid read_orientation_pixels(Reader& f, const toml::node* pn,
                                             const fs::path& path) {
    std::string error;
    output::Pixels px;
    const auto one_or_two = [](int channels) {
        return channels == 1 || channels == 2 ? std::string()
                                : "expected an image with 1 channel (angle in radians) or "
                                  "2 (direction x, y), found " +
                                      std::to_string(channels);
    };
    if (!output::read_pixels(path.string(), px, error, one_or_two)) f.fail(pn, "path", error);
    sim::OrientationGrid g;
    g.width = px.width, g.height = px.height, g.channels = px.channels;
    g.values = std::move(px.values);
    // Integer images store [0, 1]: an angle channel spans [0, pi] (an orientation), a
    // direction map [-1, 1] (grey is no direction, as for the image flow).
    if (!px.is_float)
        for (float& v : g.values) v = g.channels == 1 ? v * 3.14159265f : 2.0f * v - 1.0f;
    return g;
}

/// type = "image": an orientation image placed by spacing and origin.
std::shared_ptr<sim::OrientationField> read_image_orientation(Reader& f, const fs::path& base) {
    const toml::node* pn = f.node("path");
    const std::string rel = f.string("path", "");
    if (rel.empty())
        f.fail(pn, "path",
               "expected the path of an orientation image (1 channel: angle in "
               "radians; 2 channels: direction x, y)");
    sim::OrientationGrid g = read_orientation_pixels(f, pn, resolve_path(pn, rel, base));
    g.spacing = f.number("spacing", 1.0, kPositive, "texture units per image pixel, > 0");
    if (auto o = f.pair("origin", "[x, y] in texture units"))
        g.origin_x = (*o)[0], g.origin_y = (*o)[1];
    try {
        return sim::make_grid_orientation(std::move(g));
    } catch (const ValueError& e) {
        f.fail(pn, "path", e.what());
    }
}

}  // namespace

void read_orientation(Reader& layer, sim::ProcessConfig& p, const fs::path& base,
                      const std::function<void(Reader&)>& layer_source) {
    const toml::node* n = layer.node("orientation");
    p.orientation = sim::OrientationMode::Fixed;
    if (!n) return;
    if (n->is_string()) {
        p.orientation = static_cast<sim::OrientationMode>(
            layer.choice("orientation", sim::kOrientationModeNames, 0));
        return;
    }
    static const char* kExpected =
        "a mode (fixed, random, flow, vorticity) or a field table such as { type = \"circular\", "
        "center = [x, y] }";
    if (!n->is_table()) layer.fail(n, "orientation", std::string("expected ") + kExpected);
    Reader f = *layer.table("orientation");
    const std::array<std::string_view, 11> types = {"constant", "radial", "circular", "polyline",
                                                    "sine",     "image",  "fixed",    "random",
                                                    "flow",     "vorticity", "layer"};
    if (!f.has("type"))
        f.fail(nullptr, "type",
               "missing: expected one of constant, radial, circular, polyline, sine, image, fixed, "
               "random, flow, vorticity, layer");
    const size_t type = f.choice("type", types, 0);
    std::shared_ptr<sim::OrientationField> field;
    switch (type) {
        case 0:  // constant
            field = sim::make_constant_orientation(f.keyframed("angle", 0.0));
            break;
        case 1:  // radial
        case 2:  // circular
            field = read_centered_orientation(f, type == 1);
            break;
        case 3:
            field = read_polyline_orientation(f);
            break;
        case 4:
            field = read_sine_orientation(f);
            break;
        case 5:
            field = read_image_orientation(f, base);
            break;
        case 10:  // another layer's field: the renderer sets the field for each frame
            layer_source(f);
            break;
        default: {  // the named modes as a table
            p.orientation = static_cast<sim::OrientationMode>(type - 6);
            f.finish();
            return;
        }
    }
    p.orientation = sim::OrientationMode::Field;
    p.orientation_field = std::move(field);
    p.orientation_jitter = f.keyframed(
        "jitter", 0.0, [](double v) { return v >= 0.0; },
        "an angle >= 0 in radians (uniform random offset per impulse)");
    f.finish();
}

}  // namespace detail
namespace detail {

CameraConfig read_camera(std::optional<Reader> r, int width, int height) {
    CameraConfig c;
    c.center_x = numeric::Keyframed(width / 2.0);
    c.center_y = numeric::Keyframed(height / 2.0);
    if (!r) return c;
    r->refuse_keyframes("center");
    if (auto ct = r->node("center")) {
        if (ct->is_array()) {
            auto p = r->pair("center", "[x, y] in texture units, each within +-1e12", detail::on_plane);
            c.center_x = numeric::Keyframed((*p)[0]);
            c.center_y = numeric::Keyframed((*p)[1]);
        } else {
            r->fail(ct, "center", "expected [x, y] in texture units");
        }
    }
    if (r->has("center_x"))
        c.center_x = r->keyframed("center_x", width / 2.0, detail::on_plane, detail::kOnPlane);
    if (r->has("center_y"))
        c.center_y = r->keyframed("center_y", height / 2.0, detail::on_plane, detail::kOnPlane);
    c.zoom = r->keyframed("zoom", 1.0, kPositive, "a number > 0 (pixels per texture unit)");
    detail::read_camera_view(*r, c, width, height);  // type, perspective, anti-aliasing
    r->finish();
    return c;
}

}  // namespace detail

}  // namespace impulse::scenes
