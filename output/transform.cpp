// SPDX-License-Identifier: Apache-2.0
// Marble and wood: procedural transforms of the noise field (Lewis 1989 §5.1).

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "numeric/errors.h"
#include "output/output.h"

namespace impulse::output {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// Uniform in [0, 1) from (seed, k): the splitmix64 finaliser of a Weyl sequence, a pure
/// function of the ring's identity.
double ring_uniform(uint64_t seed, uint64_t k) {
    uint64_t z = seed + 0x9E3779B97F4A7C15ull * (k + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return static_cast<double>(z >> 11) * 0x1.0p-53;
}

/// More rings than this out to the view's far corner are refused (a ring_width far below the
/// view's size, or a centre far from the view): the table would take minutes and gigabytes.
constexpr double kMaxRings = 1e7;

/// Ring boundaries R_0 = 0 < R_1 < ... covering [0, r_max] for growth > 0.
std::vector<double> ring_radii(const FieldTransform& t, double r_max) {
    auto refuse = [&](double count) {
        std::ostringstream s;
        s << "wood: rings of width " << t.ring_width << " out to the view's far corner, " << r_max
          << " texture units from the centre, would number about " << count
          << ", over the limit of " << kMaxRings
          << " (widen ring_width, or bring the centre nearer the view)";
        throw ValueError(s.str());
    };
    if (!(r_max / t.ring_width <= kMaxRings)) refuse(r_max / t.ring_width);  // on average
    std::vector<double> radii{0.0};
    for (uint64_t k = 0; radii.back() <= r_max; ++k) {
        if (radii.size() > kMaxRings) refuse(r_max / t.ring_width);  // narrow rings by chance
        radii.push_back(radii.back() +
                        t.ring_width * (1.0 + t.growth * (2.0 * ring_uniform(t.seed, k) - 1.0)));
    }
    return radii;
}

}  // namespace

ValueMapping transform_range(const FieldTransform& t) {
    switch (t.type) {
        case FieldTransform::Type::Marble: return {-1.0, 1.0};
        case FieldTransform::Type::Wood: return {0.0, 1.0};
        case FieldTransform::Type::None: break;
    }
    return {0.0, 0.0};
}

namespace {

/// 1 / m, m = max over [0, 1] of s^a (1 - s), reached at s = a / (a + 1).
double wood_inverse_peak(double a) { return (a + 1.0) / std::pow(a / (a + 1.0), a); }

double wood_xtab(double s, double a, double inv_peak) {
    return 1.0 - std::pow(s, a) * (1.0 - s) * inv_peak;
}

}  // namespace

double wood_profile(double s, double a) { return wood_xtab(s, a, wood_inverse_peak(a)); }

PointTransform::PointTransform(const FieldTransform& t, double r_max)
    : m_t(t),
      m_radii(t.type == FieldTransform::Type::Wood && t.growth > 0 ? ring_radii(t, r_max)
                                                                    : std::vector<double>{}),
      m_inv_width(1.0 / t.ring_width),
      m_inv_peak(wood_inverse_peak(t.sharpness)) {}

double PointTransform::marble(double u, double z) const {
    // Perlin 1985, Lewis 1989 §5.1: the stripes' phase perturbed by the noise.
    return std::sin(kTwoPi * m_t.frequency * u + m_t.phase + m_t.turbulence * z);
}

double PointTransform::rings(double r) const {
    if (m_radii.empty()) return r * m_inv_width;
    // Ring k = the last boundary <= r; D = k + the fraction of ring k crossed.
    const size_t k = std::min<size_t>(
        m_radii.size() - 2, std::upper_bound(m_radii.begin(), m_radii.end(), r) - m_radii.begin() - 1);
    return static_cast<double>(k) + (r - m_radii[k]) / (m_radii[k + 1] - m_radii[k]);
}

double PointTransform::wood(double r, double z) const { return wood_shifted(r, m_t.turbulence * z); }

double PointTransform::wood_shifted(double r, double shift) const {
    // Lewis 1989 §5.1: wood = xtab[r + eta], r through the ring count D(r).
    const double d = rings(r) + shift;
    return wood_xtab(d - std::floor(d), m_t.sharpness, m_inv_peak);
}

void apply_transform(const FieldTransform& t, const View& view, double mean, double sd,
                     Frame& field) {
    if (t.type == FieldTransform::Type::None) return;
    const int w = field.width, h = field.height;
    const double inv_sd = 1.0 / sd;
    if (t.type == FieldTransform::Type::Marble) {
        const PointTransform marble(t, 0.0);
        const double cx = std::cos(t.angle_rad), cy = std::sin(t.angle_rad);
        tbb::parallel_for(0, h, [&](int j) {
            float* row = field.data.data() + size_t(j) * w;
            const double y = view.y0 + (j + 0.5) * view.scale;
            for (int i = 0; i < w; ++i) {
                const double x = view.x0 + (i + 0.5) * view.scale;
                row[i] = static_cast<float>(marble.marble(x * cx + y * cy, (row[i] - mean) * inv_sd));
            }
        });
        return;
    }
    // Wood: the ring count D(r) at the distance from the axis, perturbed by the noise in rings.
    const double dx0 = view.x0 - t.center_x, dx1 = view.x0 + w * view.scale - t.center_x;
    const double dy0 = view.y0 - t.center_y, dy1 = view.y0 + h * view.scale - t.center_y;
    const double r_max = std::sqrt(std::max(dx0 * dx0, dx1 * dx1) + std::max(dy0 * dy0, dy1 * dy1));
    const PointTransform wood(t, r_max);
    tbb::parallel_for(0, h, [&](int j) {
        float* row = field.data.data() + size_t(j) * w;
        const double y = view.y0 + (j + 0.5) * view.scale - t.center_y;
        for (int i = 0; i < w; ++i) {
            const double x = view.x0 + (i + 0.5) * view.scale - t.center_x;
            const double shift = t.turbulence * (row[i] - mean) * inv_sd;  // rings
            row[i] = static_cast<float>(wood.wood_shifted(std::sqrt(x * x + y * y), shift));
        }
    });
}

}  // namespace impulse::output
