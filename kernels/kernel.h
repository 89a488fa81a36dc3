// SPDX-License-Identifier: Apache-2.0
#pragma once
// The kernels h of the shaped Poisson point process (Lewis 1986 §3) with their exact
// second-order statistics, and a fast form for evaluation (part of impulse::kernels; included
// by kernels/kernels.h).
//
// Every kernel is an envelope e(q) of the normalised elliptical radius
//     q = (u^2 + (aspect * v)^2) / R^2,   (u, v) = offset rotated into the kernel's frame,
// zero for q >= 1, times an optional carrier cos(2 pi f u + phase) (Gabor, Lewis 1986 §3.2
// band-pass; Lagae et al. 2009). `aspect` >= 1 squeezes the kernel across its orientation.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace impulse::kernels {

/// Analytic kernels, and `Sampled`: a kernel given by samples (from a spectrum, an
/// autocorrelation, an exemplar image or a low-pass pyramid level).
enum class KernelType { Cosine, Gaussian, Gabor, Sampled };

/// Names accepted in scene files, in enum order.
inline constexpr std::array<std::string_view, 3> kKernelTypeNames = {"cosine", "gaussian",
                                                                      "gabor"};
/// Samples of a kernel. Radial: h(r) at r_i = i R / (n - 1), i = 0 .. n-1, interpolated with
/// a cubic (Catmull–Rom) in r. Grid: h at x_i = -R + i 2R / (n - 1) (same in y), row-major
/// values[j * n + i] = h(x_i, y_j), bilinear; both zero beyond the radius R (a grid is cut to
/// the disk: window it to zero there, or the cut is a jump). The grid's power spectrum is that
/// of the bilinear interpolant of the samples (the disk cut is neglected: exact for a grid
/// windowed to zero at R).
struct SampledKernel {
    bool radial = true;
    int n = 0;
    std::vector<double> values;
};

/// Name of a kernel type ("cosine", ...).
std::string_view to_string(KernelType type);
/// Kernel type from its name; nullopt when unknown.
std::optional<KernelType> kernel_type_from_string(std::string_view name);

/// Parameters of one kernel. Lengths are in texture units (pixels for the default camera).
struct KernelParams {
    KernelType type = KernelType::Cosine;
    double radius = 16.0;      ///< support radius R, > 0: h = 0 beyond it
    double sigma = 5.0;        ///< gaussian only: standard deviation, > 0
    double frequency = 0.0625; ///< gabor only: carrier frequency f, cycles per unit, >= 0
    double bandwidth = 0.0;    ///< gabor only: envelope exp(-pi a^2 r^2), a in 1/unit; 0 = derived
                               ///< from radius so the envelope is 1 % at R (a = 1.2107 / R)
    double phase = 0.0;        ///< gabor only: carrier phase, radians
    double orientation = 0.0;  ///< direction of the kernel's u axis, radians from +x (CCW)
    double aspect = 1.0;       ///< >= 1: ratio of the extent along u to the extent across it
    /// sampled only: the samples (radius above gives R); shared, immutable
    std::shared_ptr<const SampledKernel> sampled;
};

/// The largest and smallest support radius a kernel may have, texture units (below, its low-passed
/// levels underflow).
inline constexpr double kMaxKernelRadius = 1e6, kMinKernelRadius = 1e-6;

/// Neighbouring scale classes of a scale field are 1/8 octave apart (render::accumulate).
inline constexpr double kScaleClassRatio = 1.0905077326652577;  // 2^(1/8)

/// Throws impulse::ValueError naming the first invalid field ("radius = -1: must be > 0").
void validate(const KernelParams& params);

/// Chebyshev fit of an envelope e(q) on q in [0, 1], for fast evaluation in float with
/// Clenshaw's recurrence (Lewis 1989 §4.1: a kernel tabulated in r^2 avoids the square root).
/// The degree is chosen so the maximum error is below 1e-6 of e(0).
struct EnvelopePolynomial {
    std::vector<float> coefficients;  ///< c_0 .. c_n of sum c_j T_j(2q - 1)
    double max_error = 0.0;           ///< measured on a dense grid
    /// Evaluate in float (same arithmetic as the renderer's inner loop; q in [0, 1]).
    float evaluate(float q) const;
    /// The same polynomial in the monomial basis of q (m_0 + m_1 q + ...), evaluated by Horner
    /// with fused multiply-adds: half the work of Clenshaw. Filled only when that evaluation is
    /// as accurate as the Chebyshev one (true for low degrees, e.g. the cosine bump).
    std::vector<float> monomial;
    /// Horner-with-fma evaluation of `monomial` (the renderer's arithmetic).
    float evaluate_monomial(float q) const;
};

/// A kernel with its closed-form or quadrature statistics. Immutable, cheap to copy.
class Kernel {
public:
    /// Validates `params` (throws ValueError).
    explicit Kernel(const KernelParams& params);

    const KernelParams& params() const { return m_params; }
    KernelType type() const { return m_params.type; }
    double radius() const { return m_params.radius; }
    /// Gabor envelope parameter a actually used (derived when params.bandwidth == 0); 0 otherwise.
    double gabor_a() const { return m_gabor_a; }
    bool has_carrier() const { return m_params.type == KernelType::Gabor; }
    /// True when the kernel is a 2-D grid of samples (not radially symmetric).
    bool is_grid() const { return m_params.sampled && !m_params.sampled->radial; }

    /// Envelope e(q) at normalised squared radius q (exact, double); 0 for q >= 1.
    double envelope(double q) const;
    /// h at texture offset (dx, dy), kernel additionally rotated by `theta` radians (exact).
    double evaluate(double dx, double dy, double theta = 0.0) const;
    /// h and its gradient {h, dh/dx, dh/dy} at texture offset (dx, dy) (per texture unit), the
    /// kernel rotated by `theta` as in evaluate (kernels/gradient.cpp). Analytic for cosine,
    /// Gaussian and Gabor; for sampled kernels the exact gradient of the interpolant evaluate
    /// uses (the Catmull–Rom cubic's derivative, a combination of differences of the radial
    /// table; the bilinear grid's cell differences), zero outside the support.
    std::array<double, 3> value_gradient(double dx, double dy, double theta = 0.0) const;
    /// The same in the kernel's own frame: {h, dh/du, dh/dv} at (u, v), u along the kernel's
    /// orientation (for evaluators that rotate each impulse once).
    std::array<double, 3> frame_value_gradient(double u, double v) const;
    /// de/dq, the envelope's derivative in q (0 for q >= 1; q > 0 for sampled radial kernels).
    double envelope_derivative(double q) const;

    /// int h over the plane.
    double integral() const { return m_integral; }
    /// int h^2 over the plane (Campbell's theorem: variance = lambda E[a^2] int h^2).
    double integral_sq() const { return m_integral_sq; }
    /// int h^4 over the plane (fourth cumulant of the field: lambda E[a^4] int h^4).
    double integral_4() const { return m_integral_4; }
    /// Area of the support: pi R^2 / aspect (the "kernel area" of the scene's density).
    double support_area() const;

    /// Power spectrum |H(k)|^2 at frequency (kx, ky) in cycles per unit, H(k) = int h e^{-2 pi i k.x}.
    double power_spectrum(double kx, double ky) const;
    /// Angular average of |H|^2 over the circle |k| = k (what a radially averaged periodogram
    /// estimates for an isotropic orientation distribution).
    double radial_power_spectrum(double k) const;
    /// |H|^2 of the kernel turned by `rotation` radians on the n x n grid of frequencies
    /// k_i = -K + (i + 1/2) 2K / n (cycles per unit; the same in y), row-major [j * n + i]. The
    /// envelope's transform is tabulated once (2048 points, cubic interpolation: relative error
    /// ~(reach R / 2048)^4), so a grid costs n^2 look-ups (render's lattice rule).
    std::vector<double> power_spectrum_grid(double K, int n, double rotation = 0.0) const;
    /// The same for several turns of the kernel, the envelope's transform tabulated once for
    /// all (it does not depend on the turn): grids[t] for rotations[t].
    std::vector<std::vector<double>> power_spectrum_grids(double K, int n,
                                                          const std::vector<double>& rotations) const;
    /// Autocorrelation (h * h~)(tau) = int h(x) h(x + tau) dx, by quadrature (relative error
    /// about 1e-4 for kernels truncated with a jump, far smaller for the cosine kernel).
    double autocorrelation(double tx, double ty) const;

    /// rho = int h(x) h(x / r) dx / (r int h^2) with r = kScaleClassRatio = 2^(1/8): the
    /// correlation of the kernel scaled by s and by r s, each with amplitude 1/scale so both
    /// have int h^2 of their own (render's scale classes, docs/scenes.md "Kernel scale fields").
    /// By polar quadrature over the support; computed on first use, then cached (thread-safe,
    /// shared by copies).
    double scale_class_overlap() const;

    /// Fast envelope for the renderer.
    const EnvelopePolynomial& polynomial() const { return m_poly; }
    /// Envelope tabulated at q_i = i / (n - 1) (for envelopes the polynomial cannot fit to
    /// 1e-6, e.g. sampled radial kernels); empty when the polynomial is used.
    const std::vector<float>& envelope_table() const { return m_table; }
    /// Grid samples as floats (grid kernels only), row-major n x n over [-R, R]^2.
    const std::vector<float>& grid_values() const { return m_grid; }

private:
    double envelope_transform(double k) const;  ///< isotropic envelope's Hankel transform E(k)
    double grid_value(double u, double v) const;  ///< grid kernels: bilinear sample at (u, v)
    /// |H|^2 at (kx, ky) for orientation o, the envelope's transform given by `transform`.
    template <class Transform>
    double spectrum_with(double kx, double ky, double o, const Transform& transform) const;
    double grid_spectrum(double ku, double kv) const;  ///< grid kernels, kernel frame
    /// E(k) at k_j = (first + j) dk, j = 0 .. count - 1 (isotropic envelopes), all at once.
    std::vector<double> envelope_transform_table(double dk, int count, int first) const;

    KernelParams m_params;
    double m_gabor_a = 0.0;
    double m_integral = 0.0;
    double m_integral_sq = 0.0;
    double m_integral_4 = 0.0;
    EnvelopePolynomial m_poly;
    std::vector<float> m_table;
    double m_table_error = 0.0;
    std::vector<float> m_grid;
    struct LazyOverlap;  ///< scale_class_overlap, computed once
    std::shared_ptr<LazyOverlap> m_overlap;
};

/// A kernel's peak max|h| and its largest second directional derivative max|d^2 h / ds^2| over
/// the support (central differences of step R/128 on a 97 x 97 grid and 4 directions, inside
/// R - 2 steps): the motion blur's sub-step bound (docs/motion_blur.md).
struct KernelCurvature {
    double peak = 0.0, curvature = 0.0;
};
KernelCurvature kernel_curvature(const Kernel& k);

}  // namespace impulse::kernels
