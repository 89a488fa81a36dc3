// SPDX-License-Identifier: Apache-2.0
#pragma once
// Frame evaluation (part of impulse::render): tiled sparse convolution of the live impulses
// with the kernel (Lewis 1986 eq. 2) and the naive per-pixel reference.

#include "kernels/kernels.h"
#include "numeric/errors.h"
#include "numeric/frame.h"
#include "sim/sim.h"

namespace impulse::render {

using numeric::Frame;
using numeric::View;

struct EvalOptions {
    int tile_size = 128;  ///< square tiles in pixels, >= 8; the result does not depend on it
    bool parallel = true;  ///< false: the serial path through the same code (debugging)
    bool use_avx2 = true;  ///< false: baseline SSE2 loops (bit-identical; for tests)
    bool use_avx512 = true;  ///< false: at most the AVX2 loops (bit-identical; for tests)
    /// > 0: a perspective frame (accumulate_perspective) whose impulses' pixel boxes add up to
    /// more than this is refused with render::PixelBudgetError before any pixel is evaluated.
    /// The impulse count alone does not bound the work: a footprint blurred isotropically
    /// (anisotropic = false) spreads a far impulse over a row of hundreds of pixels.
    double max_pixel_evaluations = 0.0;
};

/// Thrown by accumulate_perspective when EvalOptions::max_pixel_evaluations is exceeded.
class PixelBudgetError : public BudgetError {
public:
    PixelBudgetError(double needed, double budget);
    double needed, budget;
};

/// The kernel scales an impulse may carry (sim::Impulses::scale): four octaves either way.
inline constexpr float kMinKernelScale = 0.0625f, kMaxKernelScale = 16.0f;

/// Adds sum_k w_k h_{theta_k}(x - x_k) to `out` (sized to the view; not cleared) for every
/// pixel centre. Impulses with scales (impulses.scale not empty) draw h(x / s_k) / s_k instead:
/// the kernel s_k times larger with the same int h^2, s_k quantised into classes 1/8 octave
/// apart and each impulse split between its two bracketing classes with its int h^2 kept
/// (evaluate.cpp derives the weights); ValueError for a scale outside [kMinKernelScale,
/// kMaxKernelScale]. Without scales the arithmetic is that of the unscaled evaluator. Deterministic: each pixel sums its impulses in their canonical order, so the
/// bits do not depend on the thread count or the tile size. Uses AVX-512 or AVX2 where the CPU
/// has it (numeric::simd_path), with the same arithmetic (no FMA contraction) as the baseline
/// path. Throws ValueError naming
/// the first impulse whose position (in pixels, as a float), orientation or weight is not
/// finite; accumulate_region too.
void accumulate(const kernels::Kernel& kernel, const sim::Impulses& impulses, const View& view,
                Frame& out, const EvalOptions& options = {});

/// One scale class of impulses with scales: the class's scale s_k = 2^(k/8) and the parts of
/// the impulses it draws, in canonical order, with weights that include the split and 1/s_k;
/// drawn with the kernel h(x / s_k) (scaled_kernel), they add up to what accumulate draws.
struct ScaleClass {
    double scale = 1.0;
    sim::Impulses impulses;  ///< without scales
};
/// The classes of `impulses` (scales set), ascending (for evaluators that keep one kernel or
/// pyramid per class). Throws ValueError for a scale outside [kMinKernelScale,
/// kMaxKernelScale], naming `api`.
std::vector<ScaleClass> split_scale_classes(const kernels::Kernel& kernel,
                                            const sim::Impulses& impulses,
                                            const char* api = "render::split_scale_classes");
/// The smallest class scale 2^(k/8) >= s (the class whose kernel reaches furthest for scales up
/// to s), for s in [kMinKernelScale, kMaxKernelScale].
double scale_class_at_least(double s);
/// The parameters of h(x / s): lengths (radius, sigma) times s, frequencies (frequency, a Gabor
/// bandwidth) over s; a sampled kernel's samples span its radius and scale with it.
kernels::KernelParams scaled_kernel(const kernels::KernelParams& params, double s);

/// Evaluates only the pixel rectangle [x0, x0+w) x [y0, y0+h) of the view into `tile`
/// (w*h floats, added to). Equal bits to the same pixels of `accumulate` (tiling independence).
void accumulate_region(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                       const View& view, int x0, int y0, int w, int h, float* tile,
                       const EvalOptions& options = {});

/// The naive reference (Lewis 1989 §4.1, and how shading-language sparse convolution noise
/// works): for every pixel, regenerate the impulses of the 3x3 neighbouring cells from the
/// counter-based generator and evaluate the kernel exactly in double. Still processes only;
/// needs config.cell_size >= kernel radius. Adds to `out`.
void accumulate_naive(const kernels::Kernel& kernel, const sim::ProcessConfig& config,
                      const View& view, Frame& out);

}  // namespace impulse::render
