// SPDX-License-Identifier: Apache-2.0
#pragma once
// Band-limited kernel pyramid (included by kernels/kernels.h; part of impulse::kernels).
//
// Lewis 1986 §3.1: "if the size of the kernel is small compared to the depth in a perspective
// view ... the noise can be accurately and efficiently anti-aliased by selecting appropriate
// precomputed bandlimited versions of the kernel as a function of depth". Level l is the kernel
// low-passed by a Gaussian pixel filter of standard deviation sigma_l = sigma_0 2^(l/2) (half
// octaves): h_l = h * g_l, H_l(k) = H(k) exp(-2 pi^2 sigma_l^2 |k|^2), support R + 4 sigma_l.
// Because the filter is isotropic, a rotated kernel's level is the rotated level, so one
// pyramid serves every particle orientation.
//
// Level 0 is the kernel itself: sigma_0 is chosen as the largest scale whose filtering changes
// the kernel by at most 1 % rms (||h - h * g_0|| <= 0.01 ||h||), so the kernel stands for every
// footprint below sigma_0 and scenes that never zoom out render exactly as without a pyramid.

#include <cstdint>
#include <vector>

#include "kernels/kernel.h"

namespace impulse::kernels {

struct PyramidParams {
    /// sigma_0 in texture units; 0 derives it from the kernel (1 % rms change, see above).
    double sigma0 = 0.0;
    /// rms change allowed between the kernel and its sigma_0 low-pass, when derived; (0, 0.5].
    double level0_tolerance = 0.01;
    /// Levels are added until the remaining standard deviation sqrt(int h_l^2 / int h^2)
    /// falls below this, `max_levels` is reached, or the next level's support would exceed
    /// kMaxKernelRadius (a large kernel and a small fraction); (0, 1). Beyond the top level
    /// sd_fraction extrapolates.
    double min_sd_fraction = 1e-3;
    int max_levels = 48;  ///< >= 2
};

/// The kernel low-passed by an isotropic Gaussian of standard deviation `sigma` (> 0, texture
/// units), as a Sampled kernel of radius R + 4 sigma: a radial profile when `base` is radially
/// symmetric (cosine, gaussian or a sampled profile with aspect 1), computed in the spatial
/// domain with the angular integral in closed form,
///     h_s(r) = int_0^R h(p) p / s^2 exp(-(r - p)^2 / (2 s^2)) I0e(r p / s^2) dp,
/// (the inverse Hankel transform of H(k) exp(-2 pi^2 s^2 k^2), without the slow spectral tail
/// of a kernel truncated at R); a 2-D grid in the kernel's own frame otherwise (gabor, aspect
/// != 1, grids), by FFT. The result keeps the base's orientation; its aspect is 1 (the
/// squeeze is in the samples). Deterministic.
Kernel low_pass(const Kernel& base, double sigma);

/// Whether the kernel is radially symmetric (its pyramid levels are radial profiles).
bool is_radial(const Kernel& kernel);

/// Precomputed tables of a radial level for the perspective evaluator (floats, immutable).
struct RadialLevelTables {
    /// h_l at q_i = i / (n - 1), q = r^2 / R_l^2 (linear interpolation in q).
    std::vector<float> table;
    /// Line profiles across a kernel blurred along one axis (Abel projection): at
    /// t_i = i / (n - 1), v = R_l sqrt(t): mass P(v) = int h_l(sqrt(s^2 + v^2)) ds, variance
    /// q(v) = int s^2 h_l ds / P(v) (texture units^2) and fourth cumulant
    /// k4(v) = int s^4 h_l ds / P(v) - 3 q(v)^2 (texture units^4) of the chord h_l(., v).
    std::vector<float> line_mass, line_var, line_k4;
    /// True when h_l >= 0 everywhere (the line form applies: see render/perspective.h).
    bool nonnegative = false;
    /// h_l blurred along one axis (the perspective near field's footprint filter: the level for
    /// the footprint's minor axis, convolved along its major axis with a 1-D Gaussian), for
    /// the extra variances var_k = k axial_var_max / (slices - 1), k = 0 .. slices - 1: on the
    /// quarter plane (the result is even in both axes), axial[(k nv + j) nu + i] at
    /// v_j = R_l j / (nv - 1) across and u_i = axial_extent[k] i / (nu - 1) along, bilinear.
    /// The extent R_l + 3 sqrt(var_k) truncates the Gaussian at 3 sd; the last column and row
    /// are 0, so coordinates clamped to the table read 0 outside.
    std::vector<float> axial, axial_extent;
    int axial_nu = 0, axial_nv = 0;
    double axial_var_max = 0.0;  ///< texture units^2
};

/// Line profiles of a level across one direction (non-radial pyramids, for the perspective
/// far field): with s along the direction e (at angle gamma in the kernel's frame) and v across
/// it (e turned a quarter counter-clockwise), at v_i = R_l (2 i / (n - 1) - 1): the chord's mass
/// P(v) = int h_l ds, its mean, variance and fourth cumulant in s (texture units). Chords inside
/// the disc of radius R_l only (grid levels are cut to it).
struct DirectionalLineTables {
    std::vector<float> mass, mean, var, k4;
};

class KernelPyramid {
public:
    /// Builds every level (validates params: throws ValueError).
    explicit KernelPyramid(const Kernel& base, const PyramidParams& params = {});

    const Kernel& base() const { return m_levels.front(); }
    /// Number of levels, L + 1 >= 2.
    int levels() const { return static_cast<int>(m_levels.size()); }
    /// sigma_l = sigma_0 2^(l/2) (level 0 is the kernel itself and stands for sigma <= sigma_0).
    double sigma(int l) const { return m_sigma[size_t(l)]; }
    /// Level l as a kernel (level 0: the base kernel; others Sampled).
    const Kernel& level(int l) const { return m_levels[size_t(l)]; }
    /// Support radius of level l (R + 4 sigma_l; R for level 0).
    double radius(int l) const { return m_levels[size_t(l)].radius(); }
    /// int h_l^2 over the plane.
    double variance(int l) const { return m_levels[size_t(l)].integral_sq(); }
    bool radial() const { return m_radial; }

    /// Remaining standard deviation of the kernel low-passed at `sigma`, relative to the
    /// unfiltered kernel: sqrt(int h_s^2 / int h^2). 1 at sigma <= sigma_0, log-log
    /// interpolated between levels, extrapolated as sigma_L / sigma beyond the top (the decay
    /// of a kernel with non-zero integral; band-pass kernels decay faster, so this is
    /// conservative).
    double sd_fraction(double sigma) const;

    /// The two levels bracketing `sigma` and the weight of the upper one: h_s is approximated
    /// by (1 - weight) h_lo + weight h_hi, the weight linear in log sigma so a continuous zoom
    /// never pops. `blend` false: the nearest level in log sigma (weight 0 or 1).
    struct Blend {
        int lo = 0, hi = 0;
        double weight = 0.0;
    };
    Blend select(double sigma, bool blend = true) const;

    /// Spacing of probes along a line that a level can smooth without visible ripple:
    /// 2 sqrt(sigma_0^2 + sigma_l^2) (level 0: 2 sigma_0); the comb's first alias is then
    /// attenuated by exp(-pi^2 / 2) = 0.7 %.
    double probe_spacing(int l) const;

    /// Tables of level l (radial pyramids only).
    const RadialLevelTables& tables(int l) const { return m_tables[size_t(l)]; }
    /// Grid samples (n x n over [-R_l, R_l]^2 in the kernel frame, row-major) of level l, for
    /// non-radial pyramids; level 0 is the kernel sampled on a grid.
    const std::vector<float>& grid(int l) const { return m_grids[size_t(l)]; }
    int grid_n(int l) const { return m_grid_n[size_t(l)]; }

    /// Non-radial pyramids: directions tabulated per level (0 for radial pyramids), equally
    /// spaced over direction_period() (pi when every level is point-symmetric, else 2 pi).
    int direction_bins() const { return m_direction_bins; }
    double direction_period() const { return m_direction_period; }
    /// The line profiles of level l across direction bin b (gamma = b period / bins).
    const DirectionalLineTables& direction_tables(int l, int b) const {
        return m_directional[size_t(l) * size_t(m_direction_bins) + size_t(b)];
    }
    /// Whether level l is >= 0 everywhere (to within 1e-4 of its peak).
    bool nonnegative(int l) const { return m_nonnegative[size_t(l)]; }
    /// A number no other pyramid built by this process has (copies share it: they hold the same
    /// levels). Lets a renderer tell that what it derived from a pyramid is still valid.
    uint64_t serial() const { return m_serial; }

private:
    uint64_t m_serial = 0;
    bool m_radial = false;
    std::vector<Kernel> m_levels;
    std::vector<double> m_sigma, m_sd;
    std::vector<RadialLevelTables> m_tables;
    std::vector<std::vector<float>> m_grids;
    std::vector<int> m_grid_n;
    int m_direction_bins = 0;
    double m_direction_period = 0.0;
    std::vector<DirectionalLineTables> m_directional;
    std::vector<uint8_t> m_nonnegative;
};

}  // namespace impulse::kernels
