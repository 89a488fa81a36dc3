// SPDX-License-Identifier: Apache-2.0
#pragma once
// 3-D velocity fields for the volume particle system (part of impulse::volume).

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "sim/sim.h"

namespace impulse::volume {

/// An axis-aligned box in 3-D texture units (voxels).
struct Box3 {
    double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
    Box3 expanded(double m) const { return {x0 - m, y0 - m, z0 - m, x1 + m, y1 + m, z1 + m}; }
    double volume() const { return (x1 - x0) * (y1 - y0) * (z1 - z0); }
};

/// Where a flow writes its curl (the vorticity omega = curl v, radians per second): three arrays
/// of n values each. Every array non-null.
struct CurlOut3 {
    double *x = nullptr, *y = nullptr, *z = nullptr;
};

/// A velocity field v(x, t) in units per second with its divergence and curl. `add` accumulates
/// (+=) into the outputs so a sum of flows is a loop over its terms; `div` and `curl` may be null
/// (not wanted; asking for them never changes the velocity's bits). Each flow's curl is that of
/// its own field (analytic flows: exact; a sequence: of its interpolant), for the vorticity
/// orientation (docs/volume.md "Orientation"). Deterministic and thread-safe.
class Flow3 {
public:
    virtual ~Flow3() = default;
    virtual void add(double t_s, size_t n, const double* x, const double* y, const double* z,
                     double* vx, double* vy, double* vz, double* div,
                     const CurlOut3* curl = nullptr) const = 0;
    /// True when div v = 0 everywhere (ln J then stays exactly 0).
    virtual bool divergence_free() const { return false; }
    /// Upper bound of |v| over `region` at all times.
    virtual double max_speed(const Box3& region) const = 0;
    /// Called single-threaded before a frame is integrated over `region` (caches). Default:
    /// nothing. Results do not depend on it, only speed.
    virtual void prepare(const Box3& region) { (void)region; }
    /// Called single-threaded before a frame is integrated with the times its steps evaluate,
    /// [t0_s, t1_s] (a sequence loads its frames). Default: nothing.
    virtual void prepare_span(double t0_s, double t1_s) { (void)t0_s, (void)t1_s; }
};

/// Sum of flows (a scene's [[volume.flow]] list).
class FlowSum3 final : public Flow3 {
public:
    void push(std::unique_ptr<Flow3> f) { m_terms.push_back(std::move(f)); }
    bool empty() const { return m_terms.empty(); }
    void add(double t_s, size_t n, const double* x, const double* y, const double* z, double* vx,
             double* vy, double* vz, double* div, const CurlOut3* curl = nullptr) const override;
    bool divergence_free() const override;
    double max_speed(const Box3& region) const override;
    void prepare(const Box3& region) override;
    void prepare_span(double t0_s, double t1_s) override;

private:
    std::vector<std::unique_ptr<Flow3>> m_terms;
};

/// Uniform wind v (units per second); curl 0.
std::unique_ptr<Flow3> make_uniform_flow3(const std::array<double, 3>& v);
/// Uniform divergence: v = r(t) (x - c), div v = 3 r(t) (per second), so J = exp(3 int r dt)
/// along a path; r(t) = rate + pulse sin(2 pi t / period) (pulse = 0: a steady source or sink;
/// period > 0 when pulse != 0); curl 0.
std::unique_ptr<Flow3> make_divergent_flow3(const std::array<double, 3>& center, double rate,
                                            double pulse = 0.0, double period_s = 0.0);
/// Curl noise (Bridson et al. 2007): v = curl psi of a vector potential psi whose three
/// components are independent sparse-convolution solid noises with the compact kernel
/// (1 - r^2/s^2)^3 of radius `scale` (Poisson impulses, 4 per cell of side s, keyed by the counter
/// RNG from `seed`); divergence-free exactly (the curl is taken analytically). `speed` is the RMS
/// speed (Campbell's theorem on the potential's gradient); its curl, grad(div psi) - lap psi, from
/// the kernel's exact second derivatives. Throws ValueError for scale <= 0.
std::unique_ptr<Flow3> make_curl_flow3(uint64_t seed, double scale, double speed);

/// One frame of a 3-D velocity sequence: 3 floats a sample (vx, vy, vz in voxels per second),
/// sample (i, j, k) at 3 ((k H + j) W + i).
struct VolumeFrame {
    std::array<int, 3> size{};
    std::vector<float> v;
};
/// A velocity sequence laid on the volume's voxels (docs/volume.md, docs/scenes.md "Velocity
/// sequences").
struct Sequence3Config {
    std::function<VolumeFrame(int64_t)> load;  ///< frame k; thread-safe, throws on bad input
    int64_t first = 0, last = 0;               ///< the sequence's frames, none missing
    double start = 0.0, rate = 24.0;           ///< frame u(t) = start + rate t, held to the ends
    sim::TimeInterpolation time = sim::TimeInterpolation::Linear;
    sim::Outside outside = sim::Outside::Zero;
    std::array<int, 3> size{};  ///< every frame's W, H, D (each >= 2)
    /// Volume point to grid index, axis by axis: index_c = scale[c] x_c + offset[c], scale != 0.
    std::array<double, 3> scale{1, 1, 1}, offset{0, 0, 0};
    double max_sample_speed = 0.0;  ///< max |v| over every frame's samples
    double span_s = 0.0;            ///< the lifetime (frames held: docs/scenes.md)
    bool read_ahead = true;
};
/// Trilinear in space, linear or cubic in time, with the exact divergence and curl of that
/// interpolant (for sqrt(J), design.md §1, and the vorticity orientation). Throws ValueError for a malformed config.
std::unique_ptr<Flow3> make_sequence_flow3(Sequence3Config config);
/// The largest |div v| of the trilinear interpolant of `frame` with index scales `scale` (exact:
/// on each cell div v is multilinear, so its extremes sit on the corners).
double max_interpolated_divergence3(const VolumeFrame& frame, const std::array<double, 3>& scale);

}  // namespace impulse::volume
