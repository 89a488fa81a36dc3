// SPDX-License-Identifier: Apache-2.0
// [camera.sea]: a sea below a sky camera's horizon (docs/perspective.md §9). The sea is a flat
// mirror roughened by a few travelling waves: each pixel below the horizon reflects its ray at
// the wave normal and sees the cloud deck along the reflected ray. Without waves that reflected
// ray is the ray of the *mirror camera* (the camera reflected in the sea: depth below the sea,
// so height + 2 depth below the deck, pitch negated) at the pixel mirrored about the image's
// centre row; with waves it is a nearby pixel of the same picture. So the deck is rendered
// twice, once per camera, both anti-aliased by the perspective pipeline, and the sea is a per-
// pixel look-up: a step after the layers, before shading, that needs no other renderer.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>

#include "scenes/detail/camera.h"
#include "scenes/detail/loader.h"

namespace impulse::scenes::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr int kWaves = 8;          ///< wave trains, wavelengths lambda, 0.7 lambda, ... 0.08 lambda
constexpr double kGravity = 9.81;  ///< texture units per s^2: one texture unit read as a metre
constexpr double kWaterF0 = 0.02;  ///< Fresnel reflectance of water at normal incidence (n = 1.33)
constexpr int kBackgroundRows = 2048;  ///< rows of the background table (output::Shading)

/// Schlick's approximation of the Fresnel reflectance at incidence cos theta = c.
double schlick(double c) {
    const double m = 1.0 - std::clamp(c, 0.0, 1.0);
    const double m2 = m * m;
    return kWaterF0 + (1.0 - kWaterF0) * m2 * m2 * m;
}

/// One train of the wave field: height a cos(k . x - omega t + phase), slope amplitude a |k|.
struct Wave {
    double kx, ky, omega, phase, slope;
};

/// The sea's waves: 8 trains, wavelengths falling by 0.7, directions spread +-35 degrees about
/// the wind, phases from the golden ratio, deep-water frequencies omega = sqrt(g k) (so the
/// long waves outrun the short ones), and equal slope amplitudes sqrt(2 / 8) roughness, so the
/// rms slope of their sum is `roughness` (each train's mean square slope is slope^2 / 2).
std::array<Wave, kWaves> waves_of(const SeaConfig& sea) {
    std::array<Wave, kWaves> w{};
    for (int j = 0; j < kWaves; ++j) {
        const double k = 2.0 * kPi / (sea.wavelength * std::pow(0.7, j));
        // Heading convention: 0 travels towards -y, 90 towards +x.
        const double dir = (sea.wind_deg + 35.0 * std::sin(2.4 * j)) * kDeg;
        const double golden = 0.6180339887498949 * (j + 1);
        w[size_t(j)] = {k * std::sin(dir), -k * std::cos(dir), std::sqrt(kGravity * k),
                        2.0 * kPi * (golden - std::floor(golden)), sea.roughness * std::sqrt(2.0 / kWaves)};
    }
    return w;
}

/// The camera's frame on the plane: horizontal forward, right, and the heading's sines.
struct Frame3 {
    double cp, sp;     ///< cos and sin of the pitch (above the horizon)
    double fx, fy;     ///< forward on the plane (texture coordinates)
    double rx, ry;     ///< right on the plane
    double f;          ///< focal length, pixels
    double cx, cy;     ///< principal point, pixels
};

Frame3 frame_of(const render::PerspectiveCamera& c) {
    Frame3 g;
    g.cp = std::cos(c.pitch_deg * kDeg), g.sp = std::sin(c.pitch_deg * kDeg);
    const double h = c.heading_deg * kDeg;
    g.fx = std::sin(h), g.fy = -std::cos(h);
    g.rx = std::cos(h), g.ry = std::sin(h);
    g.f = 0.5 * c.height / std::tan(0.5 * c.fov_deg * kDeg);
    g.cx = 0.5 * c.width, g.cy = 0.5 * c.height;
    return g;
}

/// Bilinear look-up of `m` at continuous pixel coordinates (px, py) (pixel centres at + 0.5),
/// clamped to the image.
float bilinear(const render::Frame& m, double px, double py) {
    const double x = std::clamp(px - 0.5, 0.0, double(m.width - 1));
    const double y = std::clamp(py - 0.5, 0.0, double(m.height - 1));
    const int x0 = std::min(int(x), m.width - 2 < 0 ? 0 : m.width - 2);
    const int y0 = std::min(int(y), m.height - 2 < 0 ? 0 : m.height - 2);
    const int x1 = std::min(x0 + 1, m.width - 1), y1 = std::min(y0 + 1, m.height - 1);
    const double fx = x - x0, fy = y - y0;
    const double top = m.at(x0, y0) + fx * (m.at(x1, y0) - m.at(x0, y0));
    const double bottom = m.at(x0, y1) + fx * (m.at(x1, y1) - m.at(x0, y1));
    return static_cast<float>(top + fy * (bottom - top));
}

/// The mirror camera's picture and its principal point and scale: a mirror camera of `scale`
/// times the frame's height has focal length scale f (the same fov), so a ray that the frame's
/// camera would image at (a, b) from its centre is imaged at (cx + scale a, cy - scale b).
struct MirrorImage {
    const render::Frame& frame;
    double cx, cy, scale;
};

/// Row j of the sea: every pixel's ray reflected at the wave normal and looked up in `mirror`.
/// Ray d = f F + a R + b U in the camera's frame (F forward, R right, U up; a, b pixel offsets
/// from the principal point): it meets the sea at horizontal distance depth / (-d_z) * d_h,
/// where the wave slope s (band-limited to the pixel's footprint: each train's slope is
/// attenuated by its Gaussian filter exp(-k^2 sigma^2 / 2)) tilts the normal to
/// n = (-s, 1) / |.|; r = d - 2 (d . n) n is projected by the mirror camera (forward
/// F' = (cos p, 0, -sin p), up U' = (sin p, 0, cos p)). With s = 0, r is f F' + a R - b U': the
/// mirror pixel is (a, -b), the pixel mirrored about the centre row.
void sea_row(const Frame3& g, const render::PerspectiveCamera& cam, const SeaConfig& sea,
             const std::array<Wave, kWaves>& waves, double filter_px, double t, double mean,
             const MirrorImage& mirror, int j, float* row) {
    const double b = g.cy - (j + 0.5);
    // d in (forward-horizontal, right, up) components, before normalising.
    const double dF = g.f * g.cp - b * g.sp, dZ = g.f * g.sp + b * g.cp;
    if (!(dZ < 0.0)) return;  // at or above the horizon: the sky
    // The footprint's sd along and across at the centre column, for the wave filter.
    const double len0 = std::sqrt(dF * dF + dZ * dZ);
    const double dist = sea.depth * len0 / -dZ;        // along the ray, texture units
    const double sin_dep = -dZ / len0;
    const double across = filter_px * dist / g.f, along = across / std::max(sin_dep, 1e-6);
    std::array<double, kWaves> atten{};
    for (int w = 0; w < kWaves; ++w) {
        const Wave& v = waves[size_t(w)];
        const double k2 = v.kx * v.kx + v.ky * v.ky;
        const double kf = (v.kx * g.fx + v.ky * g.fy), kr = (v.kx * g.rx + v.ky * g.ry);
        const double s2 = (kf * kf * along * along + kr * kr * across * across);
        atten[size_t(w)] = k2 > 0 ? v.slope * std::exp(-0.5 * s2) : 0.0;
    }
    const double x0 = cam.x, y0 = cam.y;
    for (int i = 0; i < cam.width; ++i) {
        const double a = (i + 0.5) - g.cx;
        const double len = std::sqrt(dF * dF + a * a + dZ * dZ);
        const double d0 = dF / len, d1 = a / len, d2 = dZ / len;
        const double reach = sea.depth / -d2;  // along the ray to the sea
        const double px = x0 + reach * (d0 * g.fx + d1 * g.rx);
        const double py = y0 + reach * (d0 * g.fy + d1 * g.ry);
        double sx = 0.0, sy = 0.0;  // slope of the height, texture x and y
        for (int w = 0; w < kWaves; ++w) {
            const Wave& v = waves[size_t(w)];
            const double k = std::sqrt(v.kx * v.kx + v.ky * v.ky);
            const double s = -atten[size_t(w)] * std::sin(v.kx * px + v.ky * py - v.omega * t + v.phase);
            sx += s * v.kx / k, sy += s * v.ky / k;
        }
        // The slope in the camera's frame, and the normal (-sF, -sR, 1) normalised.
        const double sF = sx * g.fx + sy * g.fy, sR = sx * g.rx + sy * g.ry;
        const double inv = 1.0 / std::sqrt(sF * sF + sR * sR + 1.0);
        const double n0 = -sF * inv, n1 = -sR * inv, n2 = inv;
        const double dn = d0 * n0 + d1 * n1 + d2 * n2;
        double r0 = d0 - 2.0 * dn * n0, r1 = d1 - 2.0 * dn * n1, r2 = d2 - 2.0 * dn * n2;
        r2 = std::max(r2, 1e-4);  // a ray reflected into the water grazes the horizon
        const double wF = r0 * g.cp - r2 * g.sp;  // along the mirror camera's axis
        const double F = schlick(-dn);
        float m = static_cast<float>(mean);
        if (wF > 0.0) {
            const double mu = g.f * r1 / wF, mv = g.f * (r0 * g.sp + r2 * g.cp) / wF;
            m = bilinear(mirror.frame, mirror.cx + mirror.scale * mu,
                         mirror.cy - mirror.scale * mv);
        }
        row[i] = static_cast<float>(mean + F * (m - mean));
    }
}

/// The sky gradient of `s` at elevation e (radians) when the horizon is at row fraction s_h:
/// top at the top of the frame (elevation e_top), bottom at the horizon, linear in elevation.
/// Doubles, rounded once where the caller stores a float: GCC 12's x86-64 vectoriser dropped
/// the rounding of two of three float channels that were widened again at once (the sea's
/// reflected sky, below), so x86-64 and arm64 differed by an ulp (docs/contributing.md
/// "Other CPUs").
void sky_at(const output::Shading& s, double e, double e_top, double out[3]) {
    const double u = std::clamp(1.0 - e / std::max(e_top, 1e-9), 0.0, 1.0);
    for (int k = 0; k < 3; ++k) out[k] = s.top[k] + u * (s.bottom[k] - s.top[k]);
}

}  // namespace

void read_sea(Reader& r, CameraConfig& c, int width, int height) {
    if (c.type != CameraConfig::Type::Perspective || c.plane != render::Plane::Sky)
        r.fail(nullptr, "sea", "a sea lies below a sky camera's horizon: expected type = "
                               "\"perspective\" and plane = \"sky\"");
    SeaConfig& s = c.sea;
    s.enabled = true;
    s.depth = r.number("depth", s.depth, [](double v) { return v > 0.0 && v <= 1e6; },
                       "a distance in (0, 1e6] texture units below the camera");
    s.roughness = r.number("roughness", s.roughness, [](double v) { return v >= 0.0 && v <= 0.5; },
                           "an rms wave slope in [0, 0.5]");
    s.wavelength = r.number("wavelength", s.wavelength, [](double v) { return v > 0.0 && v <= 1e6; },
                            "a wavelength in (0, 1e6] texture units");
    s.wind_deg = r.number("wind", s.wind_deg, [](double v) { return std::abs(v) <= 360.0; },
                          "a direction in [-360, 360] degrees");
    if (const toml::node* n = r.node("color")) {
        float col[4];
        if (!parse_color(*n, col)) r.fail(n, "color", "expected a colour \"#rrggbb\" or [r, g, b] in [0, 1]");
        s.color[0] = col[0], s.color[1] = col[1], s.color[2] = col[2];
    }
    // The horizon must be in the frame (the mirror camera must see the deck) at every key.
    for (double t : key_check_times({&c.pitch, &c.fov, &c.altitude})) {
        const double p = c.pitch.value(t), f = c.fov.value(t);
        if (!(p < 0.5 * f)) {
            std::ostringstream m;
            m << "the horizon is above the frame";
            if (!c.pitch.is_constant() || !c.fov.is_constant()) m << " at t = " << t << " s";
            m << " (pitch " << num(p) << ", fov " << num(f) << "), so no sea shows: expected pitch < fov/2 = "
              << num(0.5 * f) << " degrees";
            r.fail(nullptr, "sea", m.str());
        }
    }
    s.mirror_resolution = r.number(
        "mirror_resolution", s.mirror_resolution, [](double v) { return v >= 0.125 && v <= 1.0; },
        "a fraction in [0.125, 1] of the frame's size");
    s.mirror_min_height =
        static_cast<int>(r.integer("mirror_min_height", s.mirror_min_height, 1, 32768));
    (void)width, (void)height;
    r.finish();
}

std::array<int, 2> mirror_size(const SeaConfig& sea, int width, int height) {
    // Rounded up, and as wide as the frame's view at that height (the same rays at the edges).
    const int scaled = int(std::ceil(sea.mirror_resolution * height - 1e-9));
    const int h = std::clamp(std::max(scaled, sea.mirror_min_height), 1, height);
    const int w = std::max(1, int(std::ceil(double(width) * h / height - 1e-9)));
    return {w, h};
}

CameraConfig mirror_camera(const CameraConfig& c) {
    CameraConfig m = c;
    m.sea = SeaConfig{};
    for (auto& k : m.altitude.keys) k.second += 2.0 * c.sea.depth;
    for (auto& k : m.pitch.keys) k.second = -k.second;
    return m;
}

void apply_sea(const render::PerspectiveCamera& camera, const SeaConfig& sea, double filter_px,
               double t_s, double mean, const render::Frame& mirror, render::Frame& field) {
    const Frame3 g = frame_of(camera);
    const auto waves = waves_of(sea);
    // Rows from the first below the horizon: b < -f tan p, with b = cy - (j + 0.5).
    const double horizon = g.cy + g.f * g.sp / g.cp - 0.5;
    const int first = std::clamp(int(std::floor(horizon)), 0, field.height);
    const MirrorImage image{mirror, 0.5 * mirror.width, 0.5 * mirror.height,
                            double(mirror.height) / camera.height};
    tbb::parallel_for(first, field.height, [&](int j) {
        sea_row(g, camera, sea, waves, filter_px, t_s, mean, image, j,
                field.data.data() + size_t(j) * field.width);
    });
}

std::vector<float> sea_background(const CameraConfig& camera, const output::Shading& shading,
                                  double t_s) {
    const double p = camera.pitch.value(t_s) * kDeg;
    const double tan_half = std::tan(0.5 * camera.fov.value(t_s) * kDeg);
    const double e_top = p + 0.5 * camera.fov.value(t_s) * kDeg;  // elevation of the top row
    const SeaConfig& sea = camera.sea;
    std::vector<float> bg(3 * kBackgroundRows);
    for (int i = 0; i < kBackgroundRows; ++i) {
        // Row fraction s in [0, 1] (top to bottom) and the elevation of the centre column's ray.
        const double s = double(i) / (kBackgroundRows - 1);
        const double e = p + std::atan((1.0 - 2.0 * s) * tan_half);
        float* o = bg.data() + 3 * i;
        if (e >= 0.0) {
            double sky[3];
            sky_at(shading, e, e_top, sky);
            for (int k = 0; k < 3; ++k) o[k] = static_cast<float>(sky[k]);
            continue;
        }
        // Below the horizon: the sky at the mirrored elevation -e, reflected with Fresnel
        // reflectance F(incidence cos theta = sin(-e)) over the water's own colour.
        double sky[3];
        sky_at(shading, -e, e_top, sky);
        const double F = schlick(std::sin(-e));
        for (int k = 0; k < 3; ++k) o[k] = static_cast<float>(F * sky[k] + (1.0 - F) * sea.color[k]);
    }
    return bg;
}

}  // namespace impulse::scenes::detail
