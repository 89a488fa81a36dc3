// SPDX-License-Identifier: Apache-2.0
#pragma once
// The closed-form second-order theory of a scene's layers: Campbell's theorem (design.md §1),
// the motion-blurred field, the sea's dispersion. Part of impulse::scenes (scenes/scenes.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scenes/scene.h"

namespace impulse::scenes {

/// At frame time t_s: for a source layer mean(t) + gain(t) mean_s and gain(t)^2 var_s from the
/// source's theory; for an impulse layer mean(t) and gain(t)^2 E[a^2] int h_t^2 (lambda / T) int_0^T s(t - a)
/// w(a)^2 da, s the birth thinning (process.density_scale; 1 when the rate is constant), so
/// a keyframed density acts through the births of the last lifetime. A shaped layer has its
/// target's moments at t.
Theory layer_theory(const LayerConfig& layer, double t_s = 0.0);
/// Higher moments of an impulse layer before shaping (Campbell's cumulants, design.md §1):
/// `effective_impulses` = lambda (int h^2)^2 / int h^4 x E[w^2]^2 / E[w^4], the live impulses
/// that overlap at a point (the "10 or more" of Lewis 1989 §4.1: a peaked kernel's effective
/// area is much smaller than its truncation disc), and the field's excess kurtosis
/// (E[a^4] / E[a^2]^2) / effective_impulses: 3 pi / density for a still cosine layer with normal
/// amplitudes. Zero for source layers.
struct LayerMoments {
    double effective_impulses = 0.0;
    double excess_kurtosis = 0.0;
};
LayerMoments layer_moments(const LayerConfig& layer, double t_s = 0.0);
/// The composed result's mean and variance at frame time t_s: the visible layers blended in
/// order, each independent of the others (exact for add and multiply; max, min and over with an
/// alpha range in the Gaussian approximation, see docs/scenes.md "Composition"). Sums add means
/// and variances.
Theory scene_theory(const Scene& scene, double t_s = 0.0);
/// The same with the camera's motion blur (docs/motion_blur.md "Theory"): each impulse layer's
/// variance times motion_blur_variance_factor. The display mapping keeps scene_theory, so a
/// shutter does not change a frame's exposure.
Theory blurred_scene_theory(const Scene& scene, double t_s = 0.0);

/// Motion blur's effect on an impulse layer's second-order statistics (docs/motion_blur.md
/// "Theory"): every kernel replaced by its mean along a straight path b = v shutter / fps, v the
/// flow's velocity at the shutter's middle at 64 points over the frame's view (a uniform flow:
/// one path; others by this quadrature over the flow). The envelope's and sqrt(J)'s change over
/// the shutter are neglected.
struct MotionBlur {
    std::vector<std::array<double, 2>> paths;  ///< distinct b_p in texture units; empty: no blur
    std::vector<double> weight;                ///< each path's share of the points (sum 1)
    /// |H_b|^2 / |H|^2 = mean_p sinc^2(pi k . b_p), k in cycles per texture unit.
    double spectrum_factor(double kx, double ky) const;
    /// spectrum_factor's angular mean over |k| = rho.
    double radial_factor(double rho) const;
    /// Var_b / Var = mean_p 2 int_0^1 (1 - s) C(s b_p) ds / C(0), C the autocorrelation of `k`.
    double variance_factor(const kernels::Kernel& k) const;
};
/// Layer `layer`'s motion blur at frame time t_s (no paths without [camera] shutter, for a
/// source layer, a still one or one without flow).
MotionBlur layer_motion_blur(const Scene& scene, size_t layer, double t_s = 0.0);
/// layer_motion_blur's variance_factor for the layer's kernel at t_s (1 without blur).
double motion_blur_variance_factor(const Scene& scene, size_t layer, double t_s = 0.0);

/// True when the frame is the plain sum of layers (every layer visible, added at opacity 1,
/// unwarped; source layers only where they state a spectrum, LayerSource::no_spectrum_reason):
/// what the spectral theory of `impulse analyze` covers.
bool is_sum_of_layers(const Scene& scene);

/// Linear water waves of wavenumber k (radians per unit) under `gravity` over `depth` (<= 0:
/// deep water): omega^2 = g k tanh(k h), group speed d omega / dk.
struct WaveDispersion {
    double omega = 0.0;        ///< radians per second
    double group_speed = 0.0;  ///< texture units per second
};
WaveDispersion dispersion_relation(double k, double gravity, double depth);

}  // namespace impulse::scenes
