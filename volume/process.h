// SPDX-License-Identifier: Apache-2.0
#pragma once
// One 3-D shaped Poisson point process as a particle system (part of impulse::volume): the 2-D
// simulator's model (design.md §1, §3) in a box of 3-D space.

#include <cstdint>
#include <memory>
#include <vector>

#include "sim/sim.h"
#include "volume/flow.h"

namespace impulse::volume {

/// Everything that defines one process's impulses.
struct Process3 {
    uint64_t seed = 1;
    uint32_t layer = 0;            ///< part of the generator key (an octave's index)
    double intensity = 1e-3;       ///< lambda: expected live impulses per unit volume, > 0
    sim::Amplitude amplitude = sim::Amplitude::Normal;
    double cell_size = 16.0;       ///< seeding cell edge (units), > 0
    double lifetime_s = 2.0;       ///< T > 0: particles live [birth, birth + T)
    sim::Envelope envelope = sim::Envelope::Hann;
    bool jacobian = true;          ///< scale amplitudes by sqrt(J) (design.md §1)
    double fps = 24.0;             ///< frame f is at time f / fps
    int substeps = 1;              ///< Heun (RK2) steps per frame on the global time grid, >= 1
    /// How each impulse's kernel axis R e_x turns (docs/volume.md "Orientation"): Fixed (along
    /// x), Random (uniform on the sphere, from the impulse's identity), Flow (along v at the
    /// impulse at the frame time; x where v = 0), Vorticity (dR/dt = [omega/2]_x R from the
    /// identity at birth, on the position's Heun steps). Field is not a volume mode.
    sim::OrientationMode orientation = sim::OrientationMode::Fixed;
};

/// The live impulses at one frame in canonical order (time cell, z, y, x cell, index):
/// weight = a w(age) sqrt(J); the kernel axis (a unit vector) unless the orientation is Fixed
/// (then ax, ay, az are empty: the axis is x); the age at the frame in seconds.
struct Impulses3 {
    std::vector<double> x, y, z;
    std::vector<float> weight;
    std::vector<float> ax, ay, az;
    std::vector<double> age_s;
    size_t size() const { return x.size(); }
};

/// Produces the live impulses of a process at any frame. A later frame reuses the previous
/// frame's particles and steps them on; any other call integrates from birth; every particle
/// takes the same steps of the global grid either way, so both give the same bits (design.md §3).
class Simulator3 {
public:
    /// `flow` may be null (no motion). `support_radius`: how far an impulse reaches (culling).
    Simulator3(Process3 process, std::shared_ptr<Flow3> flow, double support_radius);
    ~Simulator3();
    Simulator3(Simulator3&&) noexcept;

    /// Impulses whose support can touch `view` at frame `frame`.
    void impulses_at(int64_t frame, const Box3& view, Impulses3& out);
    /// The box births are generated in for `view`: the view expanded by the support radius and
    /// by how far the flow can carry a particle in one lifetime.
    Box3 birth_region(const Box3& view) const;
    const Process3& process() const;

private:
    struct State;
    std::unique_ptr<State> m_state;
};

}  // namespace impulse::volume
