// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulator: the live impulses of a layer at any frame (design.md §3). Part of impulse::sim
// (sim/sim.h).

#include <cstdint>
#include <memory>
#include <vector>

#include "numeric/box.h"
#include "sim/flow.h"
#include "sim/process.h"

namespace impulse::sim {

using numeric::Box;
using numeric::Region;

/// Frame timing: frame f is at time (start_frame + f) / fps seconds.
struct Timing {
    double fps = 30.0;
    int64_t start_frame = 0;
};

/// The live impulses of a layer at one frame, in canonical order (by time cell, spatial cell,
/// index), structure of arrays. weight = a * w(age) * sqrt(J); theta = rotation added to the
/// kernel's own orientation (radians). scale: empty (every kernel at its own size), or one
/// factor per impulse by which the renderer scales its kernel (a scene's scale field; the
/// simulator never sets it, see render::accumulate).
struct Impulses {
    std::vector<double> x, y;
    std::vector<float> weight, theta;
    std::vector<float> scale;
    size_t size() const { return x.size(); }
    void clear();
};

/// Impulses of one seeding cell before any motion (for consistency tests).
struct CellImpulses {
    std::vector<double> x, y, birth_s;
    std::vector<float> amplitude, theta0;
};
/// Impulses born in spatial cell (cx, cy) and time cell ct (ct = 0 for a still process) of a
/// process; a pure function of (config, cx, cy, ct).
void cell_impulses(const ProcessConfig& config, int64_t cx, int64_t cy, int64_t ct,
                   CellImpulses& out);

/// Expected number of impulses generated for `region` (before culling): the budget estimate.
double expected_impulses(const ProcessConfig& config, const Region& region);

/// A camera shutter for motion blur (docs/motion_blur.md): open over [t + open_s, t + close_s]
/// around the frame time t. Each live impulse is drawn as n copies at the centres of n equal
/// strata of that interval, weight 1/n each, n the smallest power of two (at most max_samples)
/// with the impulse's travel over the shutter / n <= max_step: an impulse that barely moves is
/// one copy.
struct Shutter {
    double open_s = 0.0, close_s = 0.0;  ///< offsets from the frame time, seconds, open <= close
    double max_step = 1.0;               ///< largest travel between copies, texture units, > 0
    int max_samples = 64;                ///< a power of two >= 1
    /// False for a shutter of zero length (an instant: the frame as without a shutter).
    bool open() const { return close_s > open_s; }
};

/// Produces the live impulses of one layer at any frame. Sequential calls (frame f then f+1)
/// reuse the previous state and step it; any other call integrates from birth. Both paths do the
/// same floating-point operations per particle, so results are bit-identical (design.md §3).
class LayerSimulator {
public:
    /// `flow` may be null (no motion). Throws ValueError if the flow's speed bound times the
    /// lifetime exceeds config.max_travel.
    LayerSimulator(ProcessConfig config, std::shared_ptr<Flow> flow, Timing timing,
                   double support_radius);
    ~LayerSimulator();
    LayerSimulator(LayerSimulator&&) noexcept;

    /// Impulses whose support can touch `view` (texture-space boxes) at frame `frame`. Only the
    /// seeding cells whose birth region meets a box are generated. A still process (no lifetime)
    /// writes its impulses straight into `out`, pieces of rows of cells in parallel, each in its
    /// place of the canonical order (the same values and order as cell_impulses cell by cell).
    void impulses_at(int64_t frame, const Region& view, Impulses& out);
    /// The same, motion-blurred over `shutter`: each live impulse's copies along its path
    /// (docs/motion_blur.md). A closed shutter gives impulses_at's impulses, bit for bit.
    void impulses_at(int64_t frame, const Region& view, const Shutter& shutter, Impulses& out);
    /// The birth region used for `view`: expanded by support radius + travel bound.
    Box birth_region(const Box& view) const;
    /// The birth regions of every box of `view`.
    Region birth_region(const Region& view) const;
    /// Travel bound (max speed * lifetime) for `view`, in texture units.
    double travel_bound(const Box& view) const;
    /// Bytes the flow's caches may hold for `view` (Flow::cache_bytes over the region
    /// impulses_at prepares the flow for); 0 for a still process or no flow.
    double flow_cache_bytes(const Region& view) const;
    /// Flow integration steps the first frame of `view` takes: each impulse held for its birth
    /// region (expected_impulses) is integrated from its birth, on average lifetime / 2 of
    /// fps * substeps steps a second, plus one frame; 0 for a still process or no flow. (Later
    /// frames move each impulse by one frame: `substeps` steps.)
    double first_frame_steps(const Region& view) const;
    const ProcessConfig& config() const;
    /// Forget the cached state (the next call integrates from birth).
    void reset();

private:
    struct State;
    std::unique_ptr<State> m_state;
};

}  // namespace impulse::sim
