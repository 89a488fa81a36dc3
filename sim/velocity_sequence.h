// SPDX-License-Identifier: Apache-2.0
#pragma once
// Velocity sequences: a sampled flow that varies in time (sim/sequence.cpp, docs/scenes.md "A
// Blender cache"). Part of impulse::sim (sim/sim.h).

#include <array>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "sim/flow.h"

namespace impulse::sim {

/// How a sequence is read between its frames: linear over two frames, or Catmull-Rom cubic
/// over four.
enum class TimeInterpolation { Linear, Cubic };
inline constexpr std::array<std::string_view, 2> kTimeInterpolationNames = {"linear", "cubic"};
/// The field outside the sampled domain: zero, the value at the nearest point of the domain
/// (clamped coordinates, interpolated along the edge), or the nearest sample's value.
enum class Outside { Zero, Clamp, Nearest };
inline constexpr std::array<std::string_view, 3> kOutsideNames = {"zero", "clamp", "nearest"};

/// One frame of a velocity sequence on a plane: sample (i, j) at grid index (i, j), velocities
/// in texture units per second, row-major (vx[j * width + i]).
struct PlaneFrame {
    int width = 0, height = 0;
    std::vector<float> vx, vy;
};

/// Where a sequence's frames come from (scenes/ reads them from files). Thread-safe.
class FrameSource {
public:
    virtual ~FrameSource() = default;
    /// Frame n of the sequence. Throws Error (ValueError, IoError) with a one-line message.
    virtual PlaneFrame load(int64_t n) const = 0;
};

/// A velocity sequence laid on texture space.
struct SequenceConfig {
    std::shared_ptr<const FrameSource> source;
    int64_t first = 0, last = 0;  ///< the sequence's frame numbers, first <= last, none missing
    int width = 1, height = 1;    ///< every frame's grid size
    /// Scene time to sequence frame: u(t) = start + rate t (frames of the sequence a second);
    /// u is held to [first, last] (the first frame before it, the last after).
    double start = 0.0, rate = 24.0;
    /// Texture point to grid index: (i, j) = A (x, y) + b, A = {a00, a01, a10, a11} invertible.
    std::array<double, 4> to_index{1.0, 0.0, 0.0, 1.0};
    std::array<double, 2> index_offset{0.0, 0.0};
    TimeInterpolation time = TimeInterpolation::Linear;
    Outside outside = Outside::Zero;
    double max_sample_speed = 0.0;  ///< max |v| over every frame's samples (the speed bound)
    double span_s = 0.0;  ///< the layer's lifetime: the time span prepare_span covers, less a step
    bool read_ahead = true;  ///< load the frame after a span in the background
};
/// The sampled flow: bilinear in space, linear or cubic in time, with the divergence and curl
/// of that interpolant (exact: the d ln J/dt = div v of design.md §1 is the interpolated field's
/// own). Holds only the frames its last prepare_span needs (plus the one read ahead); a frame
/// asked for outside them is loaded on demand. Throws ValueError for a malformed config.
std::unique_ptr<Flow> make_sequence_flow(SequenceConfig config);
/// The largest |div v| of the bilinear interpolant of `frame` with texture-to-index map
/// `to_index` over the grid (exact: on each cell div v is affine in the cell's coordinates, so
/// its extremes sit on the cell's corners).
double max_interpolated_divergence(const PlaneFrame& frame, const std::array<double, 4>& to_index);

}  // namespace impulse::sim
