// SPDX-License-Identifier: Apache-2.0
#pragma once
// Solid noise by sparse convolution (Lewis 1989 §4, eq. 7–8; docs/solid.md): a function of 3-D
// (or 4-D: x, y, z, t) space, evaluated only at the points a model asks for. Impulses of
// uniform amplitude in [-1, 1] sit at Poisson-distributed positions in cells of side R (the
// kernel radius), each cell's impulses drawn from the counter RNG keyed by (seed, component,
// cell): any point, in any batch, order or thread count, gets the same bits (L89 §2.1
// "internally consistent"). The kernel is a kernels::Kernel's radial shape looked up by the
// squared distance (its polynomial in q = r^2 / R^2: no square root, L89 §4.1).
//
// Statistics (Campbell's theorem, with lambda = density / V_R, V_R = 4/3 pi R^3 in 3-D,
// pi^2 / 2 R^4 in 4-D, E[a] = 0, E[a^2] = 1/3):
//     mean 0,  variance lambda E[a^2] int h^2 d^n x,  spectrum S(k) = lambda E[a^2] |H(k)|^2.
// Anisotropy: f(x) = g(M x) for a 3x3 metric M, g isotropic; the variance is unchanged and
// S_f(k) = S_g(M^-T k) / |det M|.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/kernel.h"

namespace impulse::synth {

/// A kernels::Kernel's radial shape in n = 3 or 4 dimensions: h(x) = e(|x|^2 / R^2), times
/// cos(2 pi f x_1 + phase) for a Gabor kernel (its carrier along the first axis). Cosine,
/// gaussian, gabor and radial sampled (designed) kernels; aspect and orientation must be the
/// defaults (anisotropy is SolidParams::metric). Immutable.
class SolidKernel {
public:
    /// Throws ValueError for a grid kernel, aspect != 1 or dims not 3 or 4.
    explicit SolidKernel(const kernels::KernelParams& params, int dims = 3);

    const kernels::Kernel& shape() const { return m_kernel; }
    int dims() const { return m_dims; }
    double radius() const { return m_kernel.radius(); }
    /// h at offset d (texture units), exact (double).
    double evaluate(const std::array<double, 4>& d) const;
    /// Volume of the support ball, 4/3 pi R^3 (3-D) or pi^2 / 2 R^4 (4-D): the "kernel volume"
    /// the density counts impulses in.
    double support_volume() const;
    /// int h d^n x and int h^2 d^n x over R^n (quadrature to ~1e-10 relative).
    double integral() const { return m_integral; }
    double integral_sq() const { return m_integral_sq; }
    /// |H(k)|^2 at the 3-D frequency k (cycles per unit), H(k) = int h e^{-2 pi i k.x} d^3x.
    /// 3-D kernels only.
    double power_spectrum(double kx, double ky, double kz) const;
    /// Average of |H|^2 over the sphere |k| = k (3-D only; exact for isotropic shapes).
    double radial_power_spectrum(double k) const;

private:
    double envelope_transform(double k) const;  ///< 3-D transform of e(|x|^2/R^2)

    kernels::Kernel m_kernel;
    int m_dims;
    double m_integral = 0.0, m_integral_sq = 0.0;
};

/// Parameters of sparse-convolution solid noise.
struct SolidParams {
    kernels::KernelParams kernel;  ///< radial shape and radius R (texture units)
    double density = 16.0;         ///< impulses per kernel volume V_R, in (0, 1000]
    uint64_t seed = 0;
    int dims = 3;                  ///< 3: f(x, y, z); 4: f(x, y, z, t), t in texture units
    /// Row-major 3x3 metric M: f(x) = g(M x). Identity: isotropic.
    std::array<double, 9> metric = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    /// Cells of side R per period along x, y, z, in [0, 2^40]: > 0 makes the noise periodic
    /// along that axis with period period_cells * R (its cells' impulses repeat, Lewis 1986
    /// §3.2's wrap-around); 0: not periodic. Identity metric only.
    std::array<int64_t, 3> period_cells = {0, 0, 0};
};

/// A point of the noise's domain (t ignored in 3-D).
struct SolidPoint {
    double x = 0, y = 0, z = 0, t = 0;
};

/// Second-order theory of a SolidParams (Campbell's theorem, L89 eq. 7 with §4's Poisson
/// process).
struct SolidTheory {
    double mean = 0.0;
    double variance = 0.0;
    double lambda = 0.0;             ///< impulses per unit volume (per unit^4 in 4-D)
    double amplitude_moment2 = 1.0 / 3.0;  ///< E[a^2] of the uniform amplitudes
};

/// The impulses that reach a plane z = const (and t = const in 4-D), as impulses of that plane:
/// the slice is sum_i a_i h(sqrt(|x - x_i|^2 + d2_i)) (docs/solid.md "Slices in perspective").
struct SliceImpulses {
    std::vector<double> x, y;  ///< position in the plane, texture units
    std::vector<float> a;      ///< amplitude, uniform in [-1, 1]
    std::vector<float> d2;     ///< squared distance from the plane (dz^2 + dt^2), units^2, < R^2
    size_t size() const { return a.size(); }
};

/// Sparse-convolution solid noise. Immutable after construction, thread-safe.
class SolidNoise {
public:
    /// Validates (ValueError naming the field: radius, density, dims, a singular metric).
    explicit SolidNoise(const SolidParams& params);

    const SolidParams& params() const { return m_params; }
    const SolidKernel& kernel() const { return m_kernel; }
    SolidTheory theory() const;
    /// S(k) = lambda E[a^2] |H(M^-T k)|^2 / |det M| at the 3-D frequency k (3-D noise).
    double power_spectrum(double kx, double ky, double kz) const;
    /// Radially averaged S at |k| (isotropic metric: exact; otherwise averaged over 2 x 64^2
    /// directions).
    double radial_power_spectrum(double k) const;

    /// The noise at one point (a batch of one).
    float evaluate(const SolidPoint& p, int component = 0) const;
    /// The noise at many points: values[i] = f(points[i]) for component `component` (0, 1 or 2
    /// are three independent noises: vector-valued noise, L89 §5.3). Cells are visited once per
    /// batch (their impulses generated once and shared by the points near them, L89 §4.1), the
    /// work is spread over TBB, and every value is bit-identical whatever the batch, its order
    /// or the thread count.
    void evaluate(const std::vector<SolidPoint>& points, std::vector<float>& values,
                  int component = 0) const;
    /// A dense W x H x D grid, sample (i, j, k) at origin + (i, j, k) * spacing (t = origin.t),
    /// x fastest; the same bits as evaluate() at those points. 3-D noise with a diagonal metric
    /// and a polynomial kernel splats each cell's impulses into bricks of its samples (no
    /// grouping); otherwise slabs of point batches.
    std::vector<float> grid(int width, int height, int depth, const SolidPoint& origin,
                            double spacing = 1.0, int component = 0) const;

    /// The impulses of the cells (cx, cy, cz[, ct]) (side R, texture units) of the given columns
    /// (cx, cy) that lie within R of the plane z (and t, 4-D), in the order of `columns`, then of
    /// cz (and ct) ascending, then of the draw: the impulses evaluate() sums, so a slice drawn
    /// from them has the same realisation. Identity metric only (ValueError otherwise).
    void slice_impulses(const std::vector<std::array<int64_t, 2>>& columns, double z, double t,
                        SliceImpulses& out, int component = 0) const;

    /// Bytes a batch of n points (or a grid of n samples) needs, for budgets.
    static double batch_bytes(double n);

private:
    SolidParams m_params;
    SolidKernel m_kernel;
    std::array<double, 9> m_warp;  ///< M / R: points to cell units
};

/// The 2-D power spectrum of a plane z = const through 3-D solid noise with the identity metric:
/// S_2(k) = int S(sqrt(k^2 + k_z^2)) dk_z (the projection-slice theorem: a slice's spectrum is
/// the projection of the volume's), k in cycles per unit; int S_2 d^2k is the noise's variance.
/// The 3-D radial spectrum is tabulated once (64 points per 1/R) out to where it has fallen
/// below 1e-12 of its peak, S_2 by Gauss–Legendre quadrature over k_z. Immutable.
class SolidSliceSpectrum {
public:
    /// ValueError for 4-D noise or a metric other than the identity.
    explicit SolidSliceSpectrum(const SolidNoise& noise);
    double operator()(double k) const;
    /// The frequency beyond which S (3-D) is taken as 0.
    double cutoff() const { return m_step * double(m_s3.size() - 3); }

private:
    double s3(double k) const;  ///< the tabulated 3-D radial spectrum, cubic interpolation
    double m_step = 0.0;
    std::vector<double> m_s3;
};

/// A kernel designed in 3-D (kernels::DesignOptions::dims = 3, so |H|^2 = S) divided by
/// sqrt(lambda E[a^2]), lambda = density / (4/3 pi R^3), E[a^2] = 1/3: sparse convolution with it
/// at `density` has the spectrum S itself and the variance int S d^3k. ValueError for a kernel
/// that is not a radial sampled one.
kernels::KernelParams solid_designed_kernel(const kernels::KernelParams& designed, double density);

}  // namespace impulse::synth
