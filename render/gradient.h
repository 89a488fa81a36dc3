// SPDX-License-Identifier: Apache-2.0
#pragma once
// Exact spatial derivatives of a frame (part of impulse::render): df/dx and df/dy at the pixel
// centres of an orthographic view, the sum of the impulses' kernel gradients (the derivative
// of Lewis 1986 eq. 2; docs/channels.md).

#include "render/evaluate.h"

namespace impulse::render {

/// Adds sum_k w_k dh/dx (x - x_k) and the same in y to `dx` and `dy` (each resized to the view
/// when empty, else the view's size; not cleared) at every pixel centre, in field units per
/// pixel, x to the right and y down the rows (texture y). The kernel, orientations and scales
/// are those `accumulate` draws (impulses with scales are split into the same classes), so
/// the result is the derivative of accumulate's field up to its float rounding and the
/// envelope polynomial's fit (1e-6 of e(0)). Evaluated in double at each pixel (no camera
/// filtering). Deterministic: each pixel sums its impulses in canonical order, whatever the
/// threads. Throws ValueError for non-finite impulses or a scale out of range.
void accumulate_gradient(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                         const View& view, Frame& dx, Frame& dy, const EvalOptions& options = {});

}  // namespace impulse::render
