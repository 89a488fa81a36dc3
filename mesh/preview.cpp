// SPDX-License-Identifier: Apache-2.0
// The orthographic preview: project, z-buffer triangles and segments, downsample.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "mesh/mesh.h"
#include "numeric/errors.h"

namespace impulse::mesh {
namespace {

constexpr int kSuper = 2;  ///< supersampling per axis

/// The camera: screen axes and the direction towards the viewer; pixels from world.
struct Camera {
    Eigen::Vector3d right, up, toward;
    double scale = 1, cx = 0, cy = 0;
    int w = 0, h = 0;
    Eigen::Vector3d project(const Vec3& p) const {  // (pixel x, pixel y, depth: larger is nearer)
        const Eigen::Vector3d q = p.cast<double>();
        return {w * 0.5 + (q.dot(right) - cx) * scale, h * 0.5 - (q.dot(up) - cy) * scale, q.dot(toward)};
    }
};

Camera make_camera(const Mesh& mesh, const PreviewView& view) {
    const double a = view.azimuth_deg * std::numbers::pi / 180, e = view.elevation_deg * std::numbers::pi / 180;
    Camera c;
    c.toward = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
    c.right = Eigen::Vector3d(-std::sin(a), std::cos(a), 0.0);
    c.up = c.toward.cross(c.right);
    c.w = view.width * kSuper, c.h = view.height * kSuper;
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::max()), hi = -lo;
    for (const Vec3& p : mesh.positions) {
        const Eigen::Vector2d s(p.cast<double>().dot(c.right), p.cast<double>().dot(c.up));
        lo = lo.cwiseMin(s), hi = hi.cwiseMax(s);
    }
    c.cx = 0.5 * (lo.x() + hi.x()), c.cy = 0.5 * (lo.y() + hi.y());
    const double ext = std::max((hi.x() - lo.x()) / c.w, (hi.y() - lo.y()) / c.h);
    c.scale = ext > 0 ? 0.95 / ext : 1.0;
    return c;
}

struct Target {
    std::vector<float> rgb, depth;
    int w = 0, h = 0;
    void put(int x, int y, double z, const Vec3& c) {
        if (x < 0 || y < 0 || x >= w || y >= h) return;
        const size_t i = size_t(y) * w + x;
        if (z <= depth[i]) return;
        depth[i] = float(z);
        std::copy_n(c.data(), 3, rgb.data() + 3 * i);
    }
};

Vec3 colour(const Mesh& m, uint32_t v, const Vec3& fallback) { return m.colors.empty() ? fallback : m.colors[v]; }

void triangle(const Mesh& m, const Camera& cam, const uint32_t v[3], Target& t) {
    const Eigen::Vector3d p[3] = {cam.project(m.positions[v[0]]), cam.project(m.positions[v[1]]), cam.project(m.positions[v[2]])};
    const double area = (p[1].x() - p[0].x()) * (p[2].y() - p[0].y()) - (p[2].x() - p[0].x()) * (p[1].y() - p[0].y());
    if (area == 0) return;
    Eigen::Vector3d n = (m.positions[v[1]] - m.positions[v[0]]).cast<double>().cross((m.positions[v[2]] - m.positions[v[0]]).cast<double>()).normalized();
    if (n.dot(cam.toward) < 0) n = -n;  // two-sided
    const Eigen::Vector3d light = (cam.toward + 0.6 * cam.up - 0.5 * cam.right).normalized();
    const float lit = float(0.3 + 0.7 * std::max(0.0, n.dot(light)));
    const Vec3 grey(0.8f, 0.8f, 0.78f);
    const int x0 = std::max(0, int(std::floor(std::min({p[0].x(), p[1].x(), p[2].x()}))));
    const int x1 = std::min(t.w - 1, int(std::ceil(std::max({p[0].x(), p[1].x(), p[2].x()}))));
    const int y0 = std::max(0, int(std::floor(std::min({p[0].y(), p[1].y(), p[2].y()}))));
    const int y1 = std::min(t.h - 1, int(std::ceil(std::max({p[0].y(), p[1].y(), p[2].y()}))));
    for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x) {
            const double px = x + 0.5, py = y + 0.5;
            double b[3];
            for (int k = 0; k < 3; ++k) {  // barycentric weight of vertex k: the opposite edge's area
                const Eigen::Vector3d& a = p[(k + 1) % 3];
                const Eigen::Vector3d& c = p[(k + 2) % 3];
                b[k] = ((c.x() - a.x()) * (py - a.y()) - (px - a.x()) * (c.y() - a.y())) / area;
            }
            if (b[0] < 0 || b[1] < 0 || b[2] < 0) continue;
            const double z = b[0] * p[0].z() + b[1] * p[1].z() + b[2] * p[2].z();
            const Vec3 c = b[0] * colour(m, v[0], grey) + b[1] * colour(m, v[1], grey) + b[2] * colour(m, v[2], grey);
            t.put(x, y, z, lit * c);
        }
}

void segment(const Mesh& m, const Camera& cam, const uint32_t v[2], Target& t) {
    const Eigen::Vector3d a = cam.project(m.positions[v[0]]), b = cam.project(m.positions[v[1]]);
    const int n = std::max(1, int(std::ceil(std::max(std::abs(b.x() - a.x()), std::abs(b.y() - a.y())))));
    const Vec3 ink(0.12f, 0.2f, 0.38f);
    for (int s = 0; s <= n; ++s) {
        const double f = double(s) / n;
        const Eigen::Vector3d q = a + f * (b - a);
        const Vec3 c = float(1 - f) * colour(m, v[0], ink) + float(f) * colour(m, v[1], ink);
        for (int d = 0; d < kSuper; ++d) t.put(int(q.x()) + d, int(q.y()), q.z(), c);  // 1 px wide
    }
}

std::vector<float> downsample(const Target& t, const PreviewView& view) {
    std::vector<float> out(size_t(view.width) * view.height * 3);
    for (int y = 0; y < view.height; ++y)
        for (int x = 0; x < view.width; ++x)
            for (int c = 0; c < 3; ++c) {
                float sum = 0;
                for (int j = 0; j < kSuper; ++j)
                    for (int i = 0; i < kSuper; ++i) {
                        const size_t k = size_t(y * kSuper + j) * t.w + x * kSuper + i;
                        sum += t.depth[k] == -std::numeric_limits<float>::infinity() ? view.background[c] : t.rgb[3 * k + c];
                    }
                out[(size_t(y) * view.width + x) * 3 + c] = std::clamp(sum / (kSuper * kSuper), 0.0f, 1.0f);
            }
    return out;
}

}  // namespace

std::vector<float> render_preview(const Mesh& mesh, const PreviewView& view) {
    if (view.width < 16 || view.height < 16 || view.width > 8192 || view.height > 8192)
        throw ValueError("preview size: expected 16 to 8192 pixels a side");
    const Camera cam = make_camera(mesh, view);
    Target t;
    t.w = cam.w, t.h = cam.h;
    t.rgb.assign(size_t(t.w) * t.h * 3, 0.0f);
    t.depth.assign(size_t(t.w) * t.h, -std::numeric_limits<float>::infinity());
    size_t at = 0;
    for (const uint32_t size : mesh.face_sizes) {
        const uint32_t* f = mesh.indices.data() + at;
        at += size;
        if (size == 2) segment(mesh, cam, f, t);
        for (uint32_t k = 1; k + 1 < size; ++k) {
            const uint32_t tri[3] = {f[0], f[k], f[k + 1]};
            triangle(mesh, cam, tri, t);
        }
    }
    return downsample(t, view);
}

}  // namespace impulse::mesh
