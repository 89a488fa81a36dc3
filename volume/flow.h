// SPDX-License-Identifier: Apache-2.0
#pragma once
// 3-D velocity fields for the volume particle system (part of impulse::volume).

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace impulse::volume {

/// An axis-aligned box in 3-D texture units (voxels).
struct Box3 {
    double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
    Box3 expanded(double m) const { return {x0 - m, y0 - m, z0 - m, x1 + m, y1 + m, z1 + m}; }
    double volume() const { return (x1 - x0) * (y1 - y0) * (z1 - z0); }
};

/// A velocity field v(x, t) in units per second with its divergence. `add` accumulates (+=)
/// into the outputs so a sum of flows is a loop over its terms; `div` may be null. Deterministic
/// and thread-safe.
class Flow3 {
public:
    virtual ~Flow3() = default;
    virtual void add(double t_s, size_t n, const double* x, const double* y, const double* z,
                     double* vx, double* vy, double* vz, double* div) const = 0;
    /// True when div v = 0 everywhere (ln J then stays exactly 0).
    virtual bool divergence_free() const { return false; }
    /// Upper bound of |v| over `region` at all times.
    virtual double max_speed(const Box3& region) const = 0;
    /// Called single-threaded before a frame is integrated over `region` (caches). Default:
    /// nothing. Results do not depend on it, only speed.
    virtual void prepare(const Box3& region) { (void)region; }
};

/// Sum of flows (a scene's [[volume.flow]] list).
class FlowSum3 final : public Flow3 {
public:
    void push(std::unique_ptr<Flow3> f) { m_terms.push_back(std::move(f)); }
    bool empty() const { return m_terms.empty(); }
    void add(double t_s, size_t n, const double* x, const double* y, const double* z, double* vx,
             double* vy, double* vz, double* div) const override;
    bool divergence_free() const override;
    double max_speed(const Box3& region) const override;
    void prepare(const Box3& region) override;

private:
    std::vector<std::unique_ptr<Flow3>> m_terms;
};

/// Uniform wind v (units per second).
std::unique_ptr<Flow3> make_uniform_flow3(const std::array<double, 3>& v);
/// Uniform divergence: v = r(t) (x - c), div v = 3 r(t) (per second), so J = exp(3 int r dt)
/// along a path; r(t) = rate + pulse sin(2 pi t / period) (pulse = 0: a steady source or sink;
/// period > 0 when pulse != 0).
std::unique_ptr<Flow3> make_divergent_flow3(const std::array<double, 3>& center, double rate,
                                            double pulse = 0.0, double period_s = 0.0);
/// Curl noise (Bridson et al. 2007): v = curl psi of a vector potential psi whose three
/// components are independent sparse-convolution solid noises with the compact kernel
/// (1 - r^2/s^2)^3 of radius `scale` (Poisson impulses, 4 per cell of side s, keyed by the counter
/// RNG from `seed`); divergence-free exactly (the curl is taken analytically). `speed` is the RMS
/// speed (Campbell's theorem on the potential's gradient). Throws ValueError for scale <= 0.
std::unique_ptr<Flow3> make_curl_flow3(uint64_t seed, double scale, double speed);

}  // namespace impulse::volume
