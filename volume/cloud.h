// SPDX-License-Identifier: Apache-2.0
#pragma once
// Cloud density from octaves of 3-D processes (part of impulse::volume, docs/volume.md).

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "kernels/kernel.h"
#include "sim/sim.h"
#include "synth/solid.h"
#include "volume/flow.h"
#include "volume/process.h"

namespace impulse::volume {

/// How the noise f becomes cloud density: d = max(0, gain (f / sd - threshold - 4 (1 - p)))
/// with p(z) a height profile that is 1 between `base` and `top` (fractions of the grid's
/// height), falling smoothly to 0 over `softness` outside: flat-bottomed cumulus.
struct CloudShape {
    bool enabled = true;      ///< false: d = f (the raw field, for statistics)
    double threshold = 0.6;   ///< in standard deviations of f
    double gain = 1.0;        ///< density per standard deviation above the threshold, > 0
    double base = 0.25, top = 0.8;  ///< height profile, fractions of the height, base < top
    double softness = 0.15;   ///< profile ramp width, fraction of the height, > 0
};

/// A cloud volume scene's content.
struct CloudConfig {
    uint64_t seed = 1;
    std::array<int, 3> size = {128, 128, 128};  ///< grid W x H x D, voxel (i, j, k) centred at (i + 1/2, j + 1/2, k + 1/2)
    kernels::KernelParams kernel;  ///< first octave's radial shape and radius R (voxels)
    /// The kernel stretched along its own axis: h(x) = k(|S^-1 R^T x|), S = diag(aspect, 1, 1)
    /// (aspect R along the axis, R across it), in (0, 16]; 1: the radial kernel.
    double aspect = 1.0;
    /// How each impulse's axis turns (Process3::orientation; docs/volume.md "Orientation").
    sim::OrientationMode orientation = sim::OrientationMode::Fixed;
    double density = 8.0;          ///< expected live impulses per kernel volume 4/3 pi R^3, > 0
    int octaves = 3;               ///< octave o: radius R / lacunarity^o, amplitude gain^o, 1..6
    double lacunarity = 2.0;       ///< > 1
    double gain = 0.5;             ///< amplitude ratio between octaves, in (0, 1]
    sim::Amplitude amplitude = sim::Amplitude::Normal;
    double lifetime_s = 2.0;       ///< T > 0
    sim::Envelope envelope = sim::Envelope::Hann;
    bool jacobian = true;
    double fps = 24.0;
    int substeps = 1;
    std::shared_ptr<Flow3> flow;  ///< null: still in space (impulses still fade in and out)
    CloudShape shape;
};

/// Second-order theory of the unshaped field f (Campbell's theorem per octave, summed: the
/// octaves are independent). Per octave: lambda E[a^2] (int w^2 dt / T) int h^2 d^3x, where
/// int h^2 d^3x = det S int k^2 d^3x = aspect int k^2 d^3x for any rotation.
struct CloudTheory {
    double variance = 0.0;
    std::vector<double> octave_variance;
};

/// A dense float grid (x fastest) with its size.
struct DensityGrid {
    std::array<int, 3> size{};
    std::vector<float> values;
};

/// Renders frames of a cloud volume. Frames in increasing order reuse the particles (faster);
/// any order gives the same bits, for any thread count.
class CloudVolume {
public:
    /// Throws ValueError naming the field for an invalid configuration.
    explicit CloudVolume(CloudConfig config);
    ~CloudVolume();
    CloudVolume(CloudVolume&&) noexcept;

    const CloudConfig& config() const;
    CloudTheory theory() const;
    /// The unshaped field f at frame `frame` (sum of the octaves' kernels, in voxels).
    DensityGrid field(int64_t frame);
    /// The cloud density: shape(field(frame)).
    DensityGrid density(int64_t frame);
    /// Live impulses (all octaves) at the last frame rendered.
    size_t last_impulse_count() const;
    /// Expected live impulses over all octaves in the birth regions (a budget estimate).
    double expected_impulses() const;

private:
    struct State;
    std::unique_ptr<State> m_state;
};

/// Adds sum_k weight_k h(x - x_k) into `grid` (voxel (i, j, k) at (i + 1/2, j + 1/2, k + 1/2)),
/// the grid cut into 16^3 bricks, each brick summing its impulses in their order: the same bits
/// for any thread count. Kernels with a carrier (gabor) are refused by CloudVolume. aspect = 1:
/// h(d) = k(|d|) (the axes are not read); else h(d) = k(|S^-1 R^T d|) with S = diag(aspect, 1,
/// 1) and R e_x the impulse's axis (x where the impulses carry none).
void splat(const synth::SolidKernel& kernel, const Impulses3& impulses, DensityGrid& grid,
           double aspect = 1.0);

}  // namespace impulse::volume
