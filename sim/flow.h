// SPDX-License-Identifier: Apache-2.0
#pragma once
// Flows: velocity fields that carry the impulses, with their divergence and curl (design.md §1).
// Part of impulse::sim (sim/sim.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "numeric/box.h"
#include "numeric/keyframed.h"

namespace impulse::sim {

using numeric::Box;
using numeric::Keyframed;

/// A velocity field v(x, t) in texture units per second with its divergence and vorticity
/// (curl, counter-clockwise positive). Implementations accumulate (+=) into the outputs so
/// a sum of flows is a loop over its terms. Evaluation is deterministic and thread-safe once
/// `prepare` has run.
class Flow {
public:
    virtual ~Flow() = default;
    /// Add v, div v and curl v at n points (x[i], y[i]) at time t. `div` and `curl` may be
    /// null when the caller does not need them (the flow then skips their work); v is the same
    /// either way, bit for bit.
    virtual void add(double t_s, size_t n, const double* x, const double* y, double* vx,
                     double* vy, double* div, double* curl) const = 0;
    /// True when div v = 0 everywhere and at all times, so `add` would only add zeros to `div`
    /// (the simulator then does not integrate ln J: it stays exactly 0).
    virtual bool divergence_free() const { return false; }
    /// Upper bound of |v| over `region` and all time.
    virtual double max_speed(const Box& region) const = 0;
    /// Bounds {vx_min, vx_max, vy_min, vy_max} over `region` and all time (default: +-max_speed);
    /// the birth region extends upstream only as far as these allow (design.md §3).
    virtual std::array<double, 4> velocity_bounds(const Box& region) const {
        const double s = max_speed(region);
        return {-s, s, -s, s};
    }
    /// Called (single-threaded) before a frame is integrated over `region`; lets a flow build
    /// caches. Default: nothing.
    virtual void prepare(const Box& region) { (void)region; }
    /// Called (single-threaded) before a frame is integrated with the times of every step it
    /// may evaluate, [t0_s, t1_s]: lets a flow sampled in time load the frames it needs and drop
    /// the others. Default: nothing.
    virtual void prepare_span(double t0_s, double t1_s) { (void)t0_s, (void)t1_s; }
    /// Bytes prepare(region) may hold at most, for the memory budget (limits.max_memory_mib):
    /// checked at load, before any cache is built. Default: none.
    virtual double cache_bytes(const Box& region) const {
        (void)region;
        return 0.0;
    }
};

/// Sum of flow primitives (scene `[[layer.flow]]` list).
class FlowSum final : public Flow {
public:
    void push(std::unique_ptr<Flow> f) { m_terms.push_back(std::move(f)); }
    bool empty() const { return m_terms.empty(); }
    void add(double t_s, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double* curl) const override;
    bool divergence_free() const override;
    double max_speed(const Box& region) const override;
    std::array<double, 4> velocity_bounds(const Box& region) const override;
    void prepare(const Box& region) override;
    void prepare_span(double t0_s, double t1_s) override;
    double cache_bytes(const Box& region) const override;

private:
    std::vector<std::unique_ptr<Flow>> m_terms;
};

/// Uniform wind (vx, vy).
std::unique_ptr<Flow> make_uniform_flow(Keyframed vx, Keyframed vy);
/// Shear: velocity `rate * (p - c) . n_perp` along direction `angle`, where n_perp is the unit
/// normal to that direction; curl = -rate. Every parameter may vary in time.
std::unique_ptr<Flow> make_shear_flow(Keyframed rate, Keyframed cx, Keyframed cy,
                                      Keyframed angle_rad);
enum class VortexModel { LambOseen, Rankine };
inline constexpr std::array<std::string_view, 2> kVortexModelNames = {"lamb-oseen", "rankine"};
std::optional<VortexModel> vortex_model_from_string(std::string_view name);
/// Vortex of circulation `circulation` (units^2/s, positive counter-clockwise) and core radius
/// (> 0 at every key).
std::unique_ptr<Flow> make_vortex_flow(VortexModel model, Keyframed cx, Keyframed cy,
                                       Keyframed circulation, Keyframed core_radius);
/// Source (rate > 0) or sink (rate < 0): v = rate (x - c) g(r), g = exp(-r^2 / radius^2)
/// (radius = 0: g = 1, a uniform divergence 2 rate). div v = rate g (2 - 2 r^2 / radius^2).
/// A keyframed radius must be > 0 at every key (0 is a different field, not a limit of it).
std::unique_ptr<Flow> make_source_flow(Keyframed cx, Keyframed cy, Keyframed rate,
                                       Keyframed radius);
/// Divergence-free curl noise: v = (d psi/dy, -d psi/dx) of a sparse-convolution potential psi
/// with compact kernel (1 - r^2/s^2)^3 of radius `scale`; consistent (counter-based per cell)
/// and periodic when `period` is given (a multiple of the cell size is chosen). `speed` is the
/// RMS speed.
/// Throws ValueError for a scale outside [kMinCurlScale, kMaxCurlScale]; prepare() throws
/// ValueError when the lattice over its region would exceed 1e8 nodes.
std::unique_ptr<Flow> make_curl_noise_flow(uint64_t seed, double scale, Keyframed speed,
                                           std::optional<std::array<double, 2>> period);
inline constexpr double kMinCurlScale = 1e-3, kMaxCurlScale = 1e9;
/// A field sampled from a 2-channel grid (vx, vy in units per second), bilinear, clamped at the
/// edges; grid pixel (i, j) sits at texture point origin + (i + 0.5, j + 0.5) * spacing.
struct VectorGrid {
    int width = 0, height = 0;
    std::vector<float> vx, vy;
    double origin_x = 0, origin_y = 0, spacing = 1.0;
};
/// Throws ValueError for a malformed grid or a velocity that is not finite (naming its pixel).
std::unique_ptr<Flow> make_grid_flow(VectorGrid grid, Keyframed gain);

}  // namespace impulse::sim
