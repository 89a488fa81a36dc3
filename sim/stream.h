// SPDX-License-Identifier: Apache-2.0
#pragma once
// A layer's field as a stream function: a divergence-free flow from a still process
// (sim/stream.cpp). Part of impulse::sim (sim/sim.h).

#include <functional>
#include <memory>

#include "numeric/keyframed.h"
#include "sim/flow.h"
#include "sim/process.h"

namespace impulse::sim {

using numeric::Keyframed;

/// A still process's field used as a stream function (sim/stream.cpp): the velocity of a layer
/// that flows along another layer's level lines. psi(x) = gain sum_k a_k h(x - x_k; theta_k)
/// with theta_k = the impulse's random angle for OrientationMode::Random, else 0.
struct StreamFunction {
    ProcessConfig process;  ///< a still process (lifetime 0) whose cell_size >= radius
    double gain = 1.0;      ///< != 0: its sign sets the sense of rotation, its size cancels
    double radius = 0.0;    ///< support radius of h, > 0
    /// h at offset (dx, dy) from an impulse rotated by theta radians; 0 beyond `radius`.
    std::function<double(double dx, double dy, double theta)> kernel;
    /// The kernel's semivariogram (1/2) int (h(x) - h(x + tau))^2 d^2x = C(0) - C(tau) at
    /// tau = (tx, ty), C the kernel's autocorrelation, averaged over the impulses' rotations (the
    /// field's covariance is lambda E[a^2] C). Differences of C set the gradient's variance, and
    /// computed this way they keep their relative accuracy at small lags.
    std::function<double(double tx, double ty)> semivariogram;
};
/// v = speed(t) sgn(gain) (d psi/dy, -d psi/dx) / sqrt(E|grad psi|^2): divergence-free, with
/// RMS speed `speed`, curl v = -lap psi scaled alike. psi is sampled at the nodes of a fixed
/// lattice (8 per seeding cell, whole multiples of the spacing) and interpolated with Catmull-Rom
/// bicubics, as the curl-noise flow does, so the flow is a pure function of (x, t) and exactly
/// divergence-free; E|grad psi|^2 is that of the interpolant, from the semivariogram.
std::unique_ptr<Flow> make_stream_flow(StreamFunction psi, Keyframed speed);
/// E|grad psi_I|^2 / gain^2 of make_stream_flow's interpolated stream function, averaged over
/// position (Campbell's theorem on the lattice; for tests and normalisation).
double stream_gradient_variance(const StreamFunction& psi);

}  // namespace impulse::sim
