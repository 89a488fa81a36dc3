// SPDX-License-Identifier: Apache-2.0
#pragma once
// The point process of one layer: everything that defines its impulses (ProcessConfig). Part of
// impulse::sim (sim/sim.h).

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>

#include "numeric/keyframed.h"
#include "sim/amplitude.h"
#include "sim/birth_region.h"
#include "sim/orientation.h"

namespace impulse::sim {

using numeric::Keyframed;

enum class Integrator { RK2, RK4 };
inline constexpr std::array<std::string_view, 2> kIntegratorNames = {"rk2", "rk4"};
std::optional<Integrator> integrator_from_string(std::string_view name);

/// How a particle's kernel rotation theta evolves. `Fixed`: 0 (the kernel's own orientation);
/// `Random`: an angle uniform in [0, 2 pi) drawn at birth, kept for life; `Flow`: the direction
/// of v at the particle at the frame time; `Vorticity`: integrated along the path from 0 at
/// birth, d theta/dt = omega/2 (design.md §1). `Field`: from ProcessConfig::orientation_field
/// (set by a table in scene files, hence not among the names below).
enum class OrientationMode { Fixed, Random, Flow, Vorticity, Field };
inline constexpr std::array<std::string_view, 4> kOrientationModeNames = {"fixed", "random", "flow",
                                                                          "vorticity"};
std::optional<OrientationMode> orientation_mode_from_string(std::string_view name);

/// Everything that defines a layer's impulses. Validated by the scene loader.
struct ProcessConfig {
    uint64_t seed = 1;           ///< user seed
    uint32_t layer = 0;          ///< layer index (part of the generator key)
    double intensity = 0.02;     ///< lambda: expected live impulses per unit area, > 0
    Amplitude amplitude = Amplitude::Normal;
    double cell_size = 16.0;     ///< spatial cell edge used for seeding, > 0
    /// Periodic domain (tileable output, Lewis 1986 §3.2): cell keys wrap with this period.
    std::optional<std::array<double, 2>> period;

    double lifetime_s = 0.0;     ///< 0: a still process (no births in time, no motion)
    Envelope envelope = Envelope::Hann;
    double loop_s = 0.0;         ///< > 0: births periodic in time with this period
    Integrator integrator = Integrator::RK2;
    int substeps = 2;            ///< integration steps per frame, >= 1
    bool jacobian = true;        ///< scale amplitudes by sqrt(J) (design.md §1)
    OrientationMode orientation = OrientationMode::Fixed;
    double max_travel = 4096.0;  ///< refuse flows that carry particles further in one lifetime
    /// OrientationMode::Field: theta(x, t) at each particle's position at the frame time.
    std::shared_ptr<const OrientationField> orientation_field;
    /// OrientationMode::Field: plus a random angle per particle, uniform in [-jitter, jitter)
    /// radians: the uniform is drawn at birth (from the particle's identity), the spread
    /// jitter(t) is evaluated at the frame time (loop-wrapped like the flow).
    Keyframed orientation_jitter = 0.0;
    /// A time-varying birth rate by thinning (Lewis-Shedler): births are generated at the
    /// maximum rate `intensity` and one born at time t_b (loop-reduced in a looped process) is
    /// kept iff a uniform of its own identity is below density_scale(t_b), a value in [0, 1].
    /// The live intensity at t is then (intensity / T) int_0^T density_scale(t - a) da, and the
    /// variance carries density_scale(t - a) w(a)^2 under the integral (Campbell's theorem).
    /// Empty: a constant rate (no thinning; the impulses of a constant-rate process).
    /// Must be a pure function of t; only for processes with lifetime_s > 0.
    std::function<double(double)> density_scale;
    /// Births confined to a region (null: everywhere): a birth at (x, y) is kept iff a uniform
    /// drawn from its identity (seed, layer, cell, index, on a stream of its own) is <= p(x, y)
    /// at its birth position; then it moves with the flow as usual.
    std::shared_ptr<const BirthRegion> region;
};

}  // namespace impulse::sim
