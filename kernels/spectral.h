// SPDX-License-Identifier: Apache-2.0
#pragma once
// Spectral design of kernels (included by kernels/kernels.h; part of impulse::kernels).
//
// A shaped point process with kernel h has the spectrum lambda E[a^2] |H(k)|^2 (Lewis 1986 §3
// eq. 1: the autocorrelation is h * h~, its transform |H|^2). So a target spectral density S
// is reached with the zero-phase kernel h = F^-1[sqrt(S)], an autocorrelation R through its
// spectrum S = F[R] (Wiener–Khinchine; S must be >= 0, i.e. R non-negative definite, Lewis
// 1986 §2), and an exemplar texture with a windowed sample of itself (Lewis 1986 §3, §3.2).
//
// Conventions: k is a spatial frequency in cycles per texture unit, H(k) = int h e^{-2 pi i k.x}
// d^2x, so int S d^2k = R(0) is the variance; theta = atan2(ky, kx) is the angle of the
// frequency vector. Every function here is deterministic (no randomness, fixed summation order).

#include <array>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "kernels/kernel.h"

namespace impulse::kernels {

// ---------------------------------------------------------------------------------------------
// Expressions

/// A parsed arithmetic expression of named variables: numbers (1, 2.5, 1e-3), the variables
/// given at parse time, the constants pi and e, + - * / ^ (right-associative, binds tighter
/// than unary minus: -2^2 = -4), parentheses, and the functions exp log sqrt abs sin cos tan
/// (one argument) and pow min max (two). Immutable and cheap to copy; evaluation is
/// thread-safe.
class Expression {
public:
    /// Parses `text`. Throws impulse::ValueError
    /// `expression "TEXT": at column N: expected ...` (N is 1-based).
    Expression(std::string_view text, std::vector<std::string> variables);
    /// Value for `values` given in the order of the variables passed at parse time.
    double evaluate(std::span<const double> values) const;
    /// Whether the expression mentions `variable`.
    bool uses(std::string_view variable) const;
    const std::string& text() const { return m_text; }

    /// One instruction of the compiled postfix program (internal).
    struct Op {
        int code = 0;        ///< operation (see expression.cpp)
        int index = 0;       ///< variable index or function id
        double value = 0.0;  ///< constant
    };

private:
    std::string m_text;
    std::vector<std::string> m_variables;
    std::vector<Op> m_program;
    std::vector<bool> m_used;
};

// ---------------------------------------------------------------------------------------------
// Spectrum and autocorrelation sources

/// Named second-order models. Defined by their autocorrelation R(r) (the spectrum is its 2-D
/// transform): markov, gaussian, markaussian, matern, and Lewis's oscillatory noises
/// oscillatory_markov e^{-r/l} cos(omega r) (Lewis 1987 Table 1, Fig. 2: the "oscillatory
/// Markovian (Lorentzian)" noise, whose 1-D spectrum is a pair of Lorentzian lines at
/// +-omega) and oscillatory_gaussian cos(omega r) e^{-r^2/l^2} (Lewis 1986 Fig. 1). Defined by
/// their spectrum S(k): lorentzian (despite its name the 2-D spectrum of markov, kept for the
/// scenes that use it), bandpass, power. All are isotropic and scaled so int S d^2k = R(0) =
/// variance.
enum class SpectralModel {
    Markov, Gaussian, Markaussian, Matern, Lorentzian, Bandpass, Power,
    OscillatoryMarkov, OscillatoryGaussian
};
/// Names in enum order ("exponential" is also accepted for markov).
inline constexpr std::array<std::string_view, 9> kSpectralModelNames = {
    "markov",   "gaussian", "markaussian",       "matern",
    "lorentzian", "bandpass", "power", "oscillatory_markov", "oscillatory_gaussian"};

/// Parameters of a named model (lengths in texture units, frequencies in cycles per unit).
struct ModelParams {
    SpectralModel model = SpectralModel::Markov;
    double variance = 1.0;  ///< R(0) = int S d^2k, > 0
    double length = 8.0;    ///< l, > 0: markov exp(-r/l), gaussian exp(-r^2/l^2),
                            ///< markaussian exp(-(r/l)^exponent), matern length, the
                            ///< oscillatory models' envelope
    double omega = 0.5;     ///< oscillatory models: cos(omega r), radians per unit, >= 0
    double exponent = 1.4;  ///< markaussian exponent in (0, 2] (1.4: Lewis 1987 "Markaussian")
    double nu = 1.5;        ///< matern smoothness nu > 0 (0.5 is markov)
    double k0 = 0.02;       ///< lorentzian corner: S ~ (1 + (k/k0)^2)^(-3/2), > 0
    double f0 = 0.1;        ///< bandpass: ring centre frequency, >= 0
    double width = 0.02;    ///< bandpass: Gaussian ring standard deviation, > 0
    double slope = 3.0;     ///< power: S ~ k^-slope above k_low, > 0
    double k_low = 0.01;    ///< power: below k_low the spectrum flattens, > 0
    double k_high = 0.0;    ///< power: above k_high it falls as exp(-(k/k_high)^2); 0 = none
                            ///< (then slope must be > 2 for a finite variance)
};

/// Model from its name; nullopt when unknown ("exponential" maps to Markov).
std::optional<SpectralModel> spectral_model_from_string(std::string_view name);
/// True for models defined by their autocorrelation (markov, gaussian, markaussian, matern and
/// the two oscillatory ones).
bool defined_by_autocorrelation(SpectralModel model);
/// Throws ValueError naming the first invalid parameter of the model.
void validate(const ModelParams& params);

/// A spectral density S(k, theta) >= 0, value^2 per (cycle/unit)^2.
struct Spectrum {
    std::function<double(double k, double theta)> density;
    bool isotropic = true;  ///< S does not depend on theta
    std::string name;       ///< for messages: "markov", "expression \"...\"", "table.csv"
};

/// An isotropic autocorrelation R(r) (r in texture units).
struct Autocorrelation {
    std::function<double(double r)> function;
    std::string name;
};

/// The spectrum of a named model: closed form (markov, gaussian, matern, lorentzian, bandpass,
/// power) or, for markaussian, the numerical Hankel transform of R tabulated on [0, k_max]
/// (zero beyond: pass the design's nyquist). Validates (ValueError). dims = 3: the model's 3-D
/// spectrum (int S d^3k = R(0)) for the models defined by an autocorrelation (markov
/// 8 pi l^3 / (1 + (2 pi l k)^2)^2, gaussian pi^1.5 l^3 exp(-(pi l k)^2), matern, the others
/// numerically); ValueError for those defined by a 2-D spectrum (lorentzian, bandpass, power).
Spectrum model_spectrum(const ModelParams& params, double k_max = 0.5, int dims = 2);
/// The autocorrelation of a model defined by one (markov, gaussian, markaussian, matern,
/// oscillatory_markov, oscillatory_gaussian);
/// ValueError for the spectrum-defined ones.
Autocorrelation model_autocorrelation(const ModelParams& params);
/// S from an expression of k (cycles per unit) and theta (radians). ValueError on syntax.
Spectrum expression_spectrum(std::string_view text);
/// R from an expression of r (texture units). ValueError on syntax.
Autocorrelation expression_autocorrelation(std::string_view text);
/// S from CSV text: rows "k,S" (an optional non-numeric header line, blank lines and lines
/// starting with # are skipped); k >= 0 strictly increasing, S finite; at least two rows.
/// Linear interpolation; S(k) = S(k_first) below the first row and 0 beyond the last.
/// ValueError "NAME:LINE: ..." naming the line.
Spectrum table_spectrum_text(std::string_view text, const std::string& name);
/// Same, read from a file (IoError when it cannot be read).
Spectrum table_spectrum(const std::string& path);
/// R from CSV text: rows "r,R" with the grammar of table_spectrum_text (R(r) = R(r_first)
/// below the first row, 0 beyond the last; R(-r) = R(r)). ValueError "NAME:LINE: ...".
Autocorrelation table_autocorrelation_text(std::string_view text, const std::string& name);
/// Same, read from a file (IoError when it cannot be read).
Autocorrelation table_autocorrelation(const std::string& path);

/// Spectrum of an autocorrelation by the Wiener–Khinchine relation,
/// S(k) = 2 pi int_0^inf R(r) J0(2 pi k r) r dr, tabulated on [0, k_max] and interpolated.
/// R is integrated to the radius beyond which |R| < 1e-9 R(0) (at most 4096 units: ValueError
/// otherwise). Refuses (ValueError "autocorrelation is not non-negative definite: S(0.12) =
/// -0.034, ...") when S < -1e-6 max S anywhere in [0, k_max] (the threshold is far above the
/// quadrature's noise, ~1e-9 max S, and far below any real negative lobe).
/// dims = 3: the 3-D spectrum S(k) = (2 / k) int_0^inf R(r) sin(2 pi k r) r dr (the Hankel
/// transform of order 1/2); the refusal then says that an isotropic 3-D correlation may dip to
/// about -0.218 R(0) (the minimum of sin x / x), not below, and how low this one goes.
Spectrum spectrum_of_autocorrelation(const Autocorrelation& acf, double k_max, int dims = 2);
/// The autocorrelation of an isotropic spectrum band-limited to |k| <= k_max, by the inverse
/// Wiener–Khinchine relation R(r) = 2 pi int_0^k_max S(k) J0(2 pi k r) k dk (Gauss–Legendre
/// panels over [0, k_max], two per period of J0 at r, at least 64). Each distinct |r| is
/// integrated once and remembered (thread-safe): the consumers (stochastic subdivision) ask for
/// the same lags many times. Beyond 4096 units (the reach of every design here) R is taken as 0:
/// a band-limited spectrum's J0 tail there is ~1e-5 R(0) and would cost 2 k_max r panels a lag.
/// ValueError for an anisotropic S or when R(0) is not finite and
/// > 0 (a spectrum with no energy below k_max).
Autocorrelation autocorrelation_of_spectrum(const Spectrum& spectrum, double k_max);

// ---------------------------------------------------------------------------------------------
// Kernels from a spectrum or an autocorrelation

/// Taper applied to the kernel near its radius R.
enum class DesignWindow { None, Hann, Gaussian };
inline constexpr std::array<std::string_view, 3> kDesignWindowNames = {"none", "hann", "gaussian"};

struct DesignOptions {
    /// k_max, cycles per unit, > 0: the spectrum is designed on |k| <= nyquist. 0.5 is the pixel
    /// Nyquist frequency at zoom 1 (use 0.5 * zoom for a camera with zoom pixels per unit).
    double nyquist = 0.5;
    /// sqrt(S) is rolled off to 0 with a raised cosine over the top `rolloff` fraction of
    /// [0, nyquist] (no aliasing, no ringing from a hard band edge); in [0, 0.9].
    double rolloff = 0.2;
    /// Radius choice: keep this fraction of the energy int h^2 inside the radius, in (0, 1).
    double energy = 0.99;
    /// > 0: use this support radius instead of the energy rule (texture units).
    double radius = 0.0;
    /// none: cut at R; hann: raised-cosine taper over the outer 20 % of R; gaussian:
    /// exp(-(r - 0.8 R)^2 / (2 (0.2 R / 3)^2)) over the outer 20 %. With the energy rule
    /// the taper starts at the energy radius (R = energy radius / 0.8).
    DesignWindow window = DesignWindow::Hann;
    /// Refuse kernels needing a larger radius (texture units).
    double max_radius = 1024.0;
    /// > 0: refuse (BudgetError) an angle-dependent design whose working arrays would take more
    /// bytes (grid_design_bytes(N) for its N x N FFT grid; a scene's limits.max_memory_mib).
    /// 0: no bound beyond the largest grid.
    double max_bytes = 0.0;
    /// 2: a kernel of the plane, S a 2-D density (int S d^2k = R(0)). 3: a radial kernel of
    /// space for solid noise (synth/solid.h), S a 3-D density (int S d^3k = R(0)), designed by the
    /// 3-D radial transform h(r) = (2 / r) int_0^nyquist sqrt(S) T sin(2 pi k r) k dk; the
    /// report's effective_area is then a volume (int h^2)^2 / int h^4 over space, its
    /// energy_fraction and spectrum errors 3-D integrals. Isotropic spectra only.
    int dims = 2;
};

/// What the design achieved.
struct DesignReport {
    double radius = 0.0;           ///< chosen support radius R
    double energy_fraction = 0.0;  ///< int (w h)^2 / int h^2 of the untruncated band-limited kernel
    /// Relative L2 difference || |H|^2 - S || / || S || over |k| <= nyquist, H the final
    /// (windowed, truncated, sampled) kernel's transform: includes the roll-off.
    double spectrum_error = 0.0;
    /// max | |H|^2 / S - 1 | over the pass band |k| <= passband where S >= 1 % of max S: the
    /// per-frequency allowance a statistical test should add.
    double passband_error = 0.0;
    double passband = 0.0;  ///< (1 - rolloff) nyquist
    /// Isotropic kernels: max |renderer envelope - exact profile| / max |h| (the renderer's
    /// polynomial or q-table; it coarsens near r = 0 for large radii). 0 for grids.
    double render_error = 0.0;
    /// (int h^2)^2 / int h^4, units^2: the area over which the kernel's energy is spread. A
    /// zero-phase kernel from a slowly decaying spectrum (markov, power) is peaked, with an
    /// effective area far below pi R^2, and the field's excess kurtosis is
    /// (E[a^4] / E[a^2]^2) / (lambda * effective_area): raise the density to keep it Gaussian.
    double effective_area = 0.0;
    int samples = 0;    ///< radial samples, or grid samples per axis
    bool grid = false;  ///< a 2-D grid (angle-dependent spectrum)
    /// Isotropic kernels: |H(k)|^2 of the final kernel at k = i nyquist / 256, i = 0 .. 256 (the
    /// per-frequency truncation error is achieved / S - 1; for plots and tests). Empty for grids.
    std::vector<double> achieved;
};

struct DesignedKernel {
    KernelParams params;  ///< type Sampled
    DesignReport report;
};

/// Throws ValueError naming the first invalid option.
void validate(const DesignOptions& options);

/// Peak bytes an angle-dependent design holds on an N x N grid: two real FFTs (the inverse that
/// makes the kernel, the forward that reports its spectrum; N^2 reals and N (N/2 + 1) complex
/// values each, 16 N^2 bytes), the half-plane target (4 N^2), the kernel h (8 N^2) and, on the
/// first grid, the pass-band samples checked for negative S (about 3 N^2): 47 N^2.
double grid_design_bytes(int N);

/// Kernel whose |H|^2 is S (Lewis 1986 §3): h = F^-1[sqrt(S) T(k)], T the roll-off. Isotropic S:
/// radial profile by the inverse Hankel transform h(r) = 2 pi int_0^nyquist sqrt(S) T J0(2 pi
/// k r) k dk (Gauss–Legendre, 16 samples per 1/nyquist), then windowed and truncated. Angle-
/// dependent S: 2-D grid by an inverse FFT of sqrt((S(k) + S(-k))/2) T at spacing 1/(4 nyquist),
/// pre-divided by the bilinear interpolant's transform sinc^2 (so |H|^2 = S for the grid the
/// renderer interpolates), centred, windowed and cropped. Refuses S < -1e-6 max S or a non-finite
/// S (ValueError naming k), and kernels needing more than max_radius.
DesignedKernel kernel_from_spectrum(const Spectrum& spectrum, const DesignOptions& options = {});
/// kernel_from_spectrum(spectrum_of_autocorrelation(acf, options.nyquist, options.dims), options).
DesignedKernel kernel_from_autocorrelation(const Autocorrelation& acf,
                                           const DesignOptions& options = {});

// ---------------------------------------------------------------------------------------------
// Kernels from an exemplar image (Lewis 1986 §3, §3.2)

struct ExemplarOptions {
    /// Kernel radius in exemplar pixels (= texture units); 0: the largest centred square that
    /// fits the image. The sample is a (2 ceil(radius) + 1)^2 centred crop.
    double radius = 0.0;
    /// Radial window over the crop: hann 1/2 + 1/2 cos(pi r / R); gaussian exp(-r^2 / (2 (R/3)^2));
    /// none: the disc r <= R only.
    DesignWindow window = DesignWindow::Hann;
    /// The layer's density (impulses per kernel area pi R^2) and E[a^2] of its amplitudes: the
    /// kernel is scaled so lambda E[a^2] int h^2 equals the exemplar's variance.
    double density = 16.0;
    double amplitude_second_moment = 1.0;
};

struct ExemplarReport {
    double radius = 0.0;    ///< support radius R (exemplar pixels)
    int crop = 0;           ///< side of the centred crop, 2R + 1
    double mean = 0.0;      ///< of the whole exemplar (what the synthesis leaves out: set the
                            ///< layer's mean to it to match the exemplar's grey level)
    double variance = 0.0;  ///< of the whole exemplar (population), what the field reproduces
    double scale = 0.0;     ///< factor applied to the windowed sample
};

struct ExemplarKernel {
    KernelParams params;  ///< type Sampled, a grid at half-pixel spacing (4R + 1 samples)
    ExemplarReport report;
};

/// A grid kernel from a single-channel exemplar (w x h floats, row-major, top row first) whose
/// |H|^2 estimates the exemplar's spectrum: a centred crop, mean removed (the crop's mean),
/// windowed, resampled at half-pixel spacing by FFT interpolation with the bilinear interpolant's
/// sinc^2 pre-divided (so the renderer's bilinear lookup keeps the spectrum up to the pixel
/// Nyquist frequency), scaled by ExemplarOptions::density. The phase is the sample's own, as in
/// Lewis's resynthesis; coherent-phase textures (brick) keep their spectrum, not their look.
/// Throws ValueError for an image smaller than 8x8, non-finite or constant pixels, or a radius
/// whose crop does not fit the image.
ExemplarKernel kernel_from_exemplar(const float* pixels, int width, int height,
                                    const ExemplarOptions& options = {});

/// Rec. 709 luminance of interleaved pixels with `channels` >= 3 channels (R, G, B first);
/// with 1 or 2 channels, the first channel. For one kernel per channel, pass each channel.
std::vector<float> luminance(const float* pixels, int width, int height, int channels);

}  // namespace impulse::kernels
