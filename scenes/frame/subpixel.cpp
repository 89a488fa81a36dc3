// SPDX-License-Identifier: Apache-2.0
// Filtering after shading (docs/shading.md): the part of the field a frame's pixel filter
// removes, as a standard deviation per row, so the shading can average the ramp over it
// (output::Shading::subpixel_sd). A filtered pixel holds f_G = G * f at its centre; the shading
// of the supersampled reference is the mean of shade(f(x)) over the filter, and with x drawn
// from G, f(x) - f_G has mean 0 and variance
//     var_sub = E|f(x) - f_G|^2 = var f - var f_G = int S(k) (1 - |G(k)|^2) dk
// (E_x Cov(f(x), f_G) = var f_G), docs/shading.md "The sub-pixel sd".

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "scenes/detail/camera.h"

namespace impulse::scenes::detail {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kGrid = 256;  ///< the spectrum's grid, kGrid^2 frequencies
constexpr int kBins = 256;  ///< radial bins of |k|

/// A layer's power spectrum binned by |k| (the filter is isotropic, so only |k| matters, and
/// binning makes a filter's effect a sum over kBins): squared bin centres and energies.
struct RadialEnergy {
    std::vector<double> k2, energy;
    double total = 0.0;
    /// int S |G_s|^2 / int S for the isotropic Gaussian G_s of sd s (texture units):
    /// |G_s(k)|^2 = exp(-4 pi^2 s^2 |k|^2).
    double kept(double s) const {
        if (!(total > 0.0)) return 1.0;
        double sum = 0.0;
        for (size_t b = 0; b < k2.size(); ++b) sum += energy[b] * std::exp(-4.0 * kPi * kPi * s * s * k2[b]);
        return sum / total;
    }
};

/// The spectrum of `kernel` on a kGrid^2 grid reaching K = 16 aspect / R cycles per unit: the
/// minor axis's extent is R / aspect, and a kernel's spectrum is negligible beyond ~8 / extent
/// (a Gaussian of R = 3.1 sd: exp(-4 pi^2 6.7) there); the grid step aspect / (8 R) resolves
/// the spectrum's structure of width ~1 / (2 R).
RadialEnergy radial_energy(const kernels::Kernel& kernel) {
    const kernels::KernelParams& p = kernel.params();
    const double K = 16.0 * std::max(1.0, p.aspect) / p.radius;
    const std::vector<double> grid = kernel.power_spectrum_grid(K, kGrid);
    RadialEnergy r;
    r.k2.resize(kBins), r.energy.assign(kBins, 0.0);
    const double kmax = K * std::sqrt(2.0), width = kmax / kBins;
    for (int b = 0; b < kBins; ++b) r.k2[size_t(b)] = ((b + 0.5) * width) * ((b + 0.5) * width);
    for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
            const double kx = -K + (i + 0.5) * 2.0 * K / kGrid, ky = -K + (j + 0.5) * 2.0 * K / kGrid;
            const int b = std::min(kBins - 1, int(std::hypot(kx, ky) / width));
            r.energy[size_t(b)] += grid[size_t(j) * kGrid + i];
        }
    for (double e : r.energy) r.total += e;
    return r;
}

/// Whether the frame's field is a plain sum of stationary impulse layers without shaping, warps,
/// scale fields, birth regions, dispersion, motion blur or a transform: the sum whose sub-pixel
/// variance is the sum of the layers' (independent layers), the same everywhere in a row. (A
/// birth region's field is not stationary: its variance, and so its sub-pixel part, follows the
/// region; the closed-form variance is the unthinned one.)
bool plain_sum(const Scene& scene) {
    if (scene.layers.empty() || scene.transform.type != output::FieldTransform::Type::None ||
        scene.camera.shutter > 0.0 || !is_sum_of_layers(scene))
        return false;
    for (const LayerConfig& l : scene.layers)
        if (l.source || l.marginal || l.scale || l.process.region || l.carrier_rate != 0.0) return false;
    return true;
}

}  // namespace

std::vector<float> subpixel_sd(const Scene& scene, double t_s) {
    const CameraConfig& cam = scene.camera;
    const bool perspective = cam.type == CameraConfig::Type::Perspective;
    const bool filtered = perspective ? cam.antialias != CameraConfig::AntiAliasMode::Off : cam.antialiased();
    if (!scene.shading.filter_after || !filtered || !plain_sum(scene))
        return {};
    std::vector<kernels::Kernel> kernels;
    std::vector<double> variance;
    for (const LayerConfig& l : scene.layers) {
        kernels.emplace_back(l.kernel_at(l.layer_time(t_s)));
        variance.push_back(layer_theory(l, t_s).variance);
    }
    const int W = scene.output.width, H = scene.output.height;
    if (!perspective) {
        // One footprint: each kernel low-passed by the pixel filter as the pyramid does
        // (kernels::low_pass), kept = int h_s^2 / int h^2.
        const double s = cam.filter / cam.zoom.value(t_s);
        double v = 0.0;
        for (size_t i = 0; i < kernels.size(); ++i) {
            const double kept = kernels::low_pass(kernels[i], s).integral_sq() / kernels[i].integral_sq();
            v += variance[i] * std::max(0.0, 1.0 - kept);
        }
        return {float(std::sqrt(v))};
    }
    // Perspective: a footprint per row, so each kernel's spectrum binned once (grid kernels,
    // whose spectrum is a transform per frequency, are not: no remedy for them yet).
    std::vector<RadialEnergy> spectra;
    for (const kernels::Kernel& k : kernels) {
        if (k.is_grid()) return {};
        spectra.push_back(radial_energy(k));
    }
    // Per row, the footprint at the centre column (docs/perspective.md §1); rows whose centre
    // ray misses the plane (beyond the horizon, the sea's rows) get 0.
    const render::PerspectiveView view(cam.perspective(W, H, t_s));
    std::vector<std::array<double, 2>> footprint(size_t(H), {0.0, 0.0});
    double s_lo = 0.0, s_hi = 0.0;
    for (int j = 0; j < H; ++j) {
        double x = 0, y = 0;
        if (!view.texture_point(0.5 * W, j + 0.5, x, y)) continue;
        const auto f = view.footprint(x, y);
        if (!(std::isfinite(f.s_major) && f.s_major > 0.0 && std::isfinite(f.s_minor) && f.s_minor > 0.0))
            continue;
        footprint[size_t(j)] = {cam.filter * f.s_major, cam.filter * f.s_minor};
        s_lo = s_lo > 0.0 ? std::min(s_lo, footprint[size_t(j)][1]) : footprint[size_t(j)][1];
        s_hi = std::max(s_hi, footprint[size_t(j)][0]);
    }
    if (!(s_lo > 0.0)) return std::vector<float>(size_t(H), 0.0f);
    // kept(s) per layer at sds 2^(1/16) apart over the rows' range, linear in log s between
    // (kept is smooth in log s: the error is ~(ln 2 / 16)^2 / 8 of its second derivative,
    // under 1e-4): a few hundred sums of the bins instead of two per row and layer.
    const int count = 2 + int(std::ceil(16.0 * std::log2(s_hi / s_lo)));
    std::vector<std::vector<double>> kept(spectra.size(), std::vector<double>(size_t(count)));
    for (size_t i = 0; i < spectra.size(); ++i)
        for (int k = 0; k < count; ++k) kept[i][size_t(k)] = spectra[i].kept(s_lo * std::exp2(k / 16.0));
    const auto kept_at = [&](size_t i, double s) {
        const double u = std::clamp(16.0 * std::log2(s / s_lo), 0.0, double(count - 1));
        const int k = std::min(count - 2, int(u));
        return kept[i][size_t(k)] + (u - k) * (kept[i][size_t(k) + 1] - kept[i][size_t(k)]);
    };
    // var_sub at a footprint of sds (s_major, s_minor) texture units: per layer var (1 - kept);
    // an anisotropic footprint's kept fraction taken as the geometric mean of the two isotropic
    // ones (exact for an isotropic Gaussian kernel, whose spectrum factors along the axes).
    std::vector<float> rows(size_t(H), 0.0f);
    for (int j = 0; j < H; ++j) {
        const auto [s_major, s_minor] = footprint[size_t(j)];
        if (!(s_major > 0.0)) continue;
        double v = 0.0;
        for (size_t i = 0; i < spectra.size(); ++i)
            v += variance[i] * std::max(0.0, 1.0 - std::sqrt(kept_at(i, s_major) * kept_at(i, s_minor)));
        rows[size_t(j)] = float(std::sqrt(v));
    }
    return rows;
}

}  // namespace impulse::scenes::detail
