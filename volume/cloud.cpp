// SPDX-License-Identifier: Apache-2.0
// Cloud density: octaves of 3-D processes, their solid kernels splatted into bricks, shaped.

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "numeric/errors.h"
#include "volume/cloud.h"

namespace impulse::volume {
namespace {

constexpr int kBrick = 16;  ///< brick edge in voxels: one task sums one brick

/// Envelope e(q) tabulated at q = i / (n - 1), linear in between (float, one multiply-add):
/// Lewis 1989 §4.1's pre-warped table, looked up by the squared distance (no square root).
struct EnvelopeTable {
    static constexpr int kN = 4097;
    std::vector<float> v;
    explicit EnvelopeTable(const kernels::Kernel& k) : v(kN + 1, 0.0f) {
        for (int i = 0; i < kN; ++i) v[size_t(i)] = float(k.envelope(double(i) / (kN - 1)));
    }
    float operator()(float q) const {
        const float s = q * float(kN - 1);
        const int i = int(s);
        const float f = s - float(i);
        return v[size_t(i)] + f * (v[size_t(i) + 1] - v[size_t(i)]);
    }
};

/// The voxels [lo, hi] (per axis) within `radius` of an impulse at coordinate c: centres
/// i + 1/2 in [c - R, c + R], clipped to [0, n - 1] (empty when lo > hi).
std::pair<int, int> voxel_span(double c, double R, int n) {
    const int lo = std::max(0, int(std::ceil(c - R - 0.5)));
    const int hi = std::min(n - 1, int(std::floor(c + R - 0.5)));
    return {lo, hi};
}

}  // namespace

namespace {

using Bins = std::vector<std::vector<uint32_t>>;

/// Bins impulses into the bricks their support's box meets, in impulse order (the summation
/// order); `half(i, c)` is impulse i's half-extent along axis c.
template <class HalfExtent>
Bins bin_impulses(const Impulses3& imp, const std::array<int, 3>& n, const HalfExtent& half) {
    const int bx = (n[0] + kBrick - 1) / kBrick, by = (n[1] + kBrick - 1) / kBrick,
              bz = (n[2] + kBrick - 1) / kBrick;
    Bins bins(size_t(bx) * by * bz);
    for (size_t i = 0; i < imp.size(); ++i) {
        const auto [x0, x1] = voxel_span(imp.x[i], half(i, 0), n[0]);
        const auto [y0, y1] = voxel_span(imp.y[i], half(i, 1), n[1]);
        const auto [z0, z1] = voxel_span(imp.z[i], half(i, 2), n[2]);
        if (x0 > x1 || y0 > y1 || z0 > z1) continue;
        for (int k = z0 / kBrick; k <= z1 / kBrick; ++k)
            for (int j = y0 / kBrick; j <= y1 / kBrick; ++j)
                for (int b = x0 / kBrick; b <= x1 / kBrick; ++b)
                    bins[(size_t(k) * by + j) * bx + b].push_back(uint32_t(i));
    }
    return bins;
}

/// Runs `body(i, lo, hi)` for every impulse i of every brick, one task per brick, with the
/// impulse's voxel box clipped to the brick (lo, hi inclusive, per axis).
template <class HalfExtent, class Body>
void for_each_brick(const Impulses3& imp, const std::array<int, 3>& n, const HalfExtent& half,
                    const Body& body) {
    const Bins bins = bin_impulses(imp, n, half);
    const int bx = (n[0] + kBrick - 1) / kBrick, by = (n[1] + kBrick - 1) / kBrick;
    tbb::parallel_for(size_t(0), bins.size(), [&](size_t b) {
        const int ib = int(b % bx), jb = int(b / bx % by), kb = int(b / (size_t(bx) * by));
        const int b0[3] = {ib * kBrick, jb * kBrick, kb * kBrick};
        for (uint32_t i : bins[b]) {
            const double c[3] = {imp.x[i], imp.y[i], imp.z[i]};
            std::array<int, 3> lo, hi;
            for (int a = 0; a < 3; ++a) {
                const auto [l, h] = voxel_span(c[a], half(i, a), n[a]);
                lo[a] = std::max(l, b0[a]), hi[a] = std::min(h, b0[a] + kBrick - 1);
            }
            body(i, lo, hi);
        }
    });
}

/// The stretched kernel k(|S^-1 R^T d|) (cloud.h `splat`): with u = R e_x and c = 1/aspect^2 - 1,
/// |S^-1 R^T d|^2 = |d|^2 + c (d.u)^2, looked up as q = that / R^2 in the same table.
void splat_oriented(const synth::SolidKernel& kernel, const Impulses3& imp, DensityGrid& grid,
                    double aspect) {
    const auto& n = grid.size;
    const double R = kernel.radius();
    const EnvelopeTable table(kernel.shape());
    const bool axes = !imp.ax.empty();
    auto axis = [&](size_t i, int a) -> double {
        if (!axes) return a == 0 ? 1.0 : 0.0;
        return a == 0 ? imp.ax[i] : a == 1 ? imp.ay[i] : imp.az[i];
    };
    // The ellipsoid's box: half-extent along e_a = |row a of R S| R = R sqrt(1 + (s^2 - 1) u_a^2).
    auto half = [&](size_t i, int a) {
        const double u = axis(i, a);
        return R * std::sqrt(1.0 + (aspect * aspect - 1.0) * u * u);
    };
    const double c = 1.0 / (aspect * aspect) - 1.0;
    const float cf = float(c), inv_r2 = float(1.0 / (R * R));
    for_each_brick(imp, n, half, [&](size_t i, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
        const float w = imp.weight[i];
        const double ux = axis(i, 0), uy = axis(i, 1), uz = axis(i, 2);
        const float uxf = float(ux), uyf = float(uy), uzf = float(uz);
        for (int k = lo[2]; k <= hi[2]; ++k) {
            const float dz = float(k + 0.5 - imp.z[i]);
            for (int j = lo[1]; j <= hi[1]; ++j) {
                const float dy = float(j + 0.5 - imp.y[i]);
                const float s = dy * uyf + dz * uzf, base = dy * dy + dz * dz;
                // The row's chord through the ellipsoid, A X^2 + B X + C < 0 in X = dx (double),
                // widened by a voxel each way: the float test below decides each voxel.
                const double A = 1.0 + c * ux * ux, B = 2.0 * c * ux * s,
                             C = double(base) + c * double(s) * s - R * R;
                const double disc = B * B - 4.0 * A * C;
                if (disc <= 0.0) continue;
                const double r = std::sqrt(disc), X0 = (-B - r) / (2.0 * A), X1 = (-B + r) / (2.0 * A);
                const int x0 = std::max(lo[0], int(std::floor(imp.x[i] + X0 - 0.5)) - 1);
                const int x1 = std::min(hi[0], int(std::ceil(imp.x[i] + X1 - 0.5)) + 1);
                float* row = grid.values.data() + (size_t(k) * n[1] + j) * n[0];
                for (int x = x0; x <= x1; ++x) {
                    const float dx = float(x + 0.5 - imp.x[i]);
                    const float p = dx * uxf + s;
                    const float q = (dx * dx + base + cf * p * p) * inv_r2;
                    if (q < 1.0f) row[x] += w * table(q);
                }
            }
        }
    });
}

}  // namespace

void splat(const synth::SolidKernel& kernel, const Impulses3& imp, DensityGrid& grid, double aspect) {
    if (aspect != 1.0) return splat_oriented(kernel, imp, grid, aspect);
    const auto& n = grid.size;
    const double R = kernel.radius();
    const EnvelopeTable table(kernel.shape());
    const float inv_r2 = float(1.0 / (R * R));
    auto half = [R](size_t, int) { return R; };
    for_each_brick(imp, n, half, [&](size_t i, const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
        const float w = imp.weight[i];
        for (int k = lo[2]; k <= hi[2]; ++k) {
            const float dz = float(k + 0.5 - imp.z[i]);
            for (int j = lo[1]; j <= hi[1]; ++j) {
                const float dy = float(j + 0.5 - imp.y[i]);
                const float dyz = (dy * dy + dz * dz) * inv_r2;
                if (dyz >= 1.0f) continue;
                float* row = grid.values.data() + (size_t(k) * n[1] + j) * n[0];
                for (int x = lo[0]; x <= hi[0]; ++x) {
                    const float dx = float(x + 0.5 - imp.x[i]);
                    const float q = dx * dx * inv_r2 + dyz;
                    if (q < 1.0f) row[x] += w * table(q);
                }
            }
        }
    });
}

struct CloudVolume::State {
    CloudConfig c;
    std::vector<synth::SolidKernel> kernels;
    std::vector<Simulator3> octaves;
    std::vector<double> lambda;  ///< per octave, impulses per unit volume
    size_t last_count = 0;
};

namespace {

void validate(const CloudConfig& c) {
    for (int a = 0; a < 3; ++a)
        if (c.size[a] < 1 || c.size[a] > 2048)
            throw ValueError("volume size = " + std::to_string(c.size[a]) + ": expected 1 .. 2048 voxels per axis");
    if (c.kernel.type == kernels::KernelType::Gabor)
        throw ValueError("volume kernel = gabor: expected a radial bump (cosine, gaussian)");
    if (!(c.density > 0.0) || c.density > 1000.0)
        throw ValueError("volume density = " + std::to_string(c.density) + ": expected in (0, 1000]");
    if (c.octaves < 1 || c.octaves > 6)
        throw ValueError("volume octaves = " + std::to_string(c.octaves) + ": expected 1 .. 6");
    if (!(c.lacunarity > 1.0)) throw ValueError("volume lacunarity: expected > 1");
    if (!(c.gain > 0.0 && c.gain <= 1.0)) throw ValueError("volume gain: expected in (0, 1]");
    if (!(c.lifetime_s > 0.0)) throw ValueError("volume lifetime: expected > 0 seconds");
    if (!(c.fps > 0.0)) throw ValueError("volume fps: expected > 0");
    if (!(c.aspect > 0.0 && c.aspect <= 16.0))
        throw ValueError("volume kernel aspect = " + std::to_string(c.aspect) + ": expected in (0, 16]");
    if (c.orientation == sim::OrientationMode::Field)
        throw ValueError("volume orientation: expected fixed, random, flow or vorticity");
}

}  // namespace

CloudVolume::CloudVolume(CloudConfig config) : m_state(std::make_unique<State>()) {
    validate(config);
    State& S = *m_state;
    S.c = std::move(config);
    for (int o = 0; o < S.c.octaves; ++o) {
        kernels::KernelParams kp = S.c.kernel;
        kp.radius = S.c.kernel.radius / std::pow(S.c.lacunarity, o);
        kp.sigma = S.c.kernel.sigma / std::pow(S.c.lacunarity, o);
        S.kernels.emplace_back(kp, 3);
        const synth::SolidKernel& k = S.kernels.back();
        Process3 p;
        p.seed = S.c.seed;
        p.layer = uint32_t(o);
        p.intensity = S.c.density / k.support_volume();
        p.amplitude = S.c.amplitude;
        p.cell_size = k.radius();
        p.lifetime_s = S.c.lifetime_s;
        p.envelope = S.c.envelope;
        p.jacobian = S.c.jacobian;
        p.fps = S.c.fps;
        p.substeps = S.c.substeps;
        // A radial kernel (aspect 1) looks the same turned any way: its axes are not carried
        // (nor the vorticity integrated), the field is the same.
        p.orientation = S.c.aspect == 1.0 ? sim::OrientationMode::Fixed : S.c.orientation;
        S.lambda.push_back(p.intensity);
        // the support reaches aspect R along the axis (culling and the birth region's margin)
        S.octaves.emplace_back(p, S.c.flow, k.radius() * std::max(1.0, S.c.aspect));
    }
    const double n = expected_impulses();
    if (n > 5e7) {
        std::ostringstream s;
        s << "volume: an estimated " << n << " live impulses per frame, over the limit of 5e7 "
          << "(fewer octaves, a lower density or a larger radius)";
        throw BudgetError(s.str());
    }
}
CloudVolume::~CloudVolume() = default;
CloudVolume::CloudVolume(CloudVolume&&) noexcept = default;
const CloudConfig& CloudVolume::config() const { return m_state->c; }
size_t CloudVolume::last_impulse_count() const { return m_state->last_count; }

CloudTheory CloudVolume::theory() const {
    // Campbell's theorem per octave: births at beta = lambda / T per unit volume and second,
    // each adding (g^o a w(age) h)^2: lambda g^2o E[a^2] (int_0^T w^2 dt / T) int h^2 d^3x,
    // int h^2 d^3x = |det S| int k^2 d^3x (substitute y = S^-1 R^T x; R drops out) = aspect
    // int k^2 d^3x for every impulse, whatever its axis.
    const State& S = *m_state;
    CloudTheory t;
    const double ea2 = sim::amplitude_second_moment(S.c.amplitude);
    const double w2 = sim::envelope_sq_integral(S.c.envelope, S.c.lifetime_s) / S.c.lifetime_s;
    for (size_t o = 0; o < S.kernels.size(); ++o) {
        const double g = std::pow(S.c.gain, double(o));
        const double v = S.lambda[o] * g * g * ea2 * w2 * S.c.aspect * S.kernels[o].integral_sq();
        t.octave_variance.push_back(v);
        t.variance += v;
    }
    return t;
}

double CloudVolume::expected_impulses() const {
    const State& S = *m_state;
    const Box3 view{0, 0, 0, double(S.c.size[0]), double(S.c.size[1]), double(S.c.size[2])};
    double n = 0.0;
    for (size_t o = 0; o < S.octaves.size(); ++o)
        n += 1.75 * S.lambda[o] * S.octaves[o].birth_region(view).volume();
    return n;
}

DensityGrid CloudVolume::field(int64_t frame) {
    State& S = *m_state;
    DensityGrid g;
    g.size = S.c.size;
    g.values.assign(size_t(g.size[0]) * g.size[1] * g.size[2], 0.0f);
    const Box3 view{0, 0, 0, double(g.size[0]), double(g.size[1]), double(g.size[2])};
    Impulses3 imp;
    S.last_count = 0;
    for (size_t o = 0; o < S.octaves.size(); ++o) {
        S.octaves[o].impulses_at(frame, view, imp);
        const float gain = float(std::pow(S.c.gain, double(o)));
        for (float& w : imp.weight) w *= gain;
        S.last_count += imp.size();
        splat(S.kernels[o], imp, g, S.c.aspect);
    }
    return g;
}

namespace {

/// How far (standard deviations of f) the profile lowers the field where p = 0: far enough
/// that nothing survives there (f beyond 4 sd is rare).
constexpr double kProfileDepth = 4.0;

double smoothstep(double a, double b, double x) {
    const double t = std::clamp((x - a) / (b - a), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

/// The height profile p(z) times the fade at the side walls: 1 inside, 0 at the grid's faces.
double profile(const CloudShape& s, double fx, double fy, double fz) {
    const double v = smoothstep(s.base - s.softness, s.base, fz) *
                     (1.0 - smoothstep(s.top, s.top + s.softness, fz));
    const double side = smoothstep(0.0, s.softness, std::min(fx, 1.0 - fx)) *
                        smoothstep(0.0, s.softness, std::min(fy, 1.0 - fy));
    return v * side;
}

}  // namespace

DensityGrid CloudVolume::density(int64_t frame) {
    DensityGrid g = field(frame);
    const CloudShape& s = m_state->c.shape;
    if (!s.enabled) return g;
    // d = max(0, gain (f / sd - threshold - (1 - p))): the profile lowers the field towards the
    // faces so the cloud thins out and stays inside the box (docs/volume.md "Shaping").
    const double sd = std::sqrt(theory().variance);
    const auto& n = g.size;
    tbb::parallel_for(0, n[2], [&](int k) {
        const double fz = (k + 0.5) / n[2];
        for (int j = 0; j < n[1]; ++j) {
            const double fy = (j + 0.5) / n[1];
            float* row = g.values.data() + (size_t(k) * n[1] + j) * n[0];
            for (int i = 0; i < n[0]; ++i) {
                const double p = profile(s, (i + 0.5) / n[0], fy, fz);
                const double d = s.gain * (row[i] / sd - s.threshold - kProfileDepth * (1.0 - p));
                row[i] = float(std::max(0.0, d));
            }
        }
    });
    return g;
}

}  // namespace impulse::volume
