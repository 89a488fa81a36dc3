// SPDX-License-Identifier: Apache-2.0
// The cloud scenes' physical spectrum (issue 20): 1-D transects of a raw rendered frame of
// `drift` follow k^-5/3 over 1.5 decades (Davis et al. 1997: cloud radiance transects), within
// +-0.2 in the log-log slope; without the octave weights they do not.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <vector>

#include "numeric/fft.h"
#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;

namespace {

/// Least-squares slope of log P against log k over log-spaced bins of the row periodogram of
/// rows [y0, y1) of `f`: each row's mean removed, Hann-windowed, |FFT|^2 averaged over the
/// rows, then averaged in 16 bins equally spaced in log k over [k_lo, k_hi] (cycles per pixel).
double transect_slope(const render::Frame& f, int y0, int y1, double k_lo, double k_hi) {
    const int n = f.width;
    numeric::RealFft2d fft(1, n, numeric::FftPlans::Forward);
    std::vector<double> power(n / 2 + 1, 0.0);
    for (int y = y0; y < y1; ++y) {
        double mean = 0.0;
        for (int x = 0; x < n; ++x) mean += f.at(x, y);
        mean /= n;
        for (int x = 0; x < n; ++x) {
            const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * x / n);
            fft.real()[x] = (f.at(x, y) - mean) * hann;
        }
        fft.forward();
        for (int k = 0; k <= n / 2; ++k) power[k] += std::norm(fft.spectrum()[k]);
    }
    constexpr int kBins = 16;
    std::vector<double> sum(kBins, 0.0), count(kBins, 0.0);
    const double span = std::log(k_hi / k_lo);
    for (int k = 1; k <= n / 2; ++k) {
        const int b = static_cast<int>(std::floor(std::log(double(k) / n / k_lo) / span * kBins));
        if (b < 0 || b >= kBins) continue;
        sum[b] += power[k], count[b] += 1.0;
    }
    double sx = 0, sy = 0, sxx = 0, sxy = 0, m = 0;
    for (int b = 0; b < kBins; ++b) {
        if (count[b] == 0.0) continue;
        const double x = std::log(k_lo) + span * (b + 0.5) / kBins, yv = std::log(sum[b] / count[b]);
        sx += x, sy += yv, sxx += x * x, sxy += x * yv, m += 1.0;
    }
    return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

struct SlopeEstimate {
    double mean = 0.0, standard_error = 0.0;
};

/// Transect slopes of `drift` (with `overrides`) over k in [1/900, 1/28.5] cycles per pixel
/// (1.5 decades), per block of 256 rows of a 4096 x 768 window, frames 0, 120 and 239.
SlopeEstimate drift_slope(std::vector<std::string> overrides) {
    overrides.push_back("output.size=[4096, 768]");  // a wider window at the scene's own scale
    scenes::Renderer r(scenes::load_scene(scenes::resolve_scene("drift"), overrides));
    std::vector<double> slopes;
    for (int64_t frame : {0, 120, 239}) {
        render::Frame f;
        r.render(frame, f);
        for (int y0 = 0; y0 + 256 <= f.height; y0 += 256)
            slopes.push_back(transect_slope(f, y0, y0 + 256, 1.0 / 900.0, 1.0 / 28.5));
    }
    SlopeEstimate e;
    for (double s : slopes) e.mean += s;
    e.mean /= double(slopes.size());
    double var = 0.0;
    for (double s : slopes) var += (s - e.mean) * (s - e.mean);
    e.standard_error = std::sqrt(var / double(slopes.size() - 1) / double(slopes.size()));
    return e;
}

}  // namespace

TEST_CASE("drift's raw frames have k^-5/3 transects over 1.5 decades",
          "[scenes][gallery][stats][slow]") {
    // Nine blocks (three frames x three 256-row blocks); blocks of one frame share the largest
    // impulses (sigma 120), so the standard error from their spread is a lower bound: the
    // check asks for it to be a quarter of the +-0.2 band at most, so the band is not noise.
    const SlopeEstimate e = drift_slope({});
    INFO("slope " << e.mean << " +- " << e.standard_error << " (standard error)");
    CHECK(e.standard_error < 0.05);
    CHECK(std::abs(e.mean + 5.0 / 3.0) <= 0.2);
    // The mechanism: equal octave gains (the weights gain_j ~ sigma_j^(1/3) switched off) give
    // sum_j sigma_j exp(-4 pi^2 sigma_j^2 k^2) ~ k^-1: outside the band.
    const SlopeEstimate flat = drift_slope({"layer.0.gain=1", "layer.1.gain=1", "layer.2.gain=1",
                                            "layer.3.gain=1", "layer.4.gain=1"});
    INFO("equal gains: slope " << flat.mean << " +- " << flat.standard_error);
    CHECK(std::abs(flat.mean + 5.0 / 3.0) > 0.2);
}

namespace {

/// Transect slope of drift at 1920x1080 over [0.002, 0.066] cycles per pixel, in four blocks of
/// 270 rows of frames 0, 90 and 180 (three looks 3 s apart, longer than every octave's lifetime
/// but the cells' 6 s): the blocks' mean and its standard error. One frame's four blocks gave a
/// standard error of 0.077, too wide for the +-0.2 band's 95 % interval to hold any estimate but
/// one within 0.05 of -5/3.
SlopeEstimate drift_frame0_slope(std::vector<std::string> overrides) {
    scenes::Renderer r(scenes::load_scene(scenes::resolve_scene("drift"), overrides));
    render::Frame f;
    std::vector<double> slopes;
    for (int64_t frame : {0, 90, 180}) {
        r.render(frame, f);
        for (int y0 = 0; y0 + 270 <= f.height; y0 += 270)
            slopes.push_back(transect_slope(f, y0, y0 + 270, 0.002, 0.066));
    }
    SlopeEstimate e;
    double var = 0.0;
    for (double s : slopes) e.mean += s / double(slopes.size());
    for (double s : slopes) var += (s - e.mean) * (s - e.mean) / double(slopes.size() - 1);
    e.standard_error = std::sqrt(var / double(slopes.size()));
    return e;
}

}  // namespace

TEST_CASE("drift's raw frame 0 has a k^-5/3 transect up to 0.066 cycles per pixel",
          "[scenes][gallery][stats][slow]") {
    // Issue 35: a new user measures frame 0 at the scene's 1920x1080 over 0.002-0.066 cycles per
    // pixel (1.5 decades reaching the finest octaves). The finest octave (sigma 3.07) rolls off
    // as exp(-4 pi^2 sigma^2 k^2) inside that band: -1.81 in theory, -1.76 +- 0.045 measured here
    // over three frames (the issue's -1.93 came from one frame and another estimator). The
    // slope's 95 % interval (two standard errors of the blocks' mean) must lie within
    // -5/3 +- 0.2.
    const SlopeEstimate e = drift_frame0_slope({});
    INFO("slope " << e.mean << " +- " << e.standard_error << " (standard error)");
    CHECK(std::abs(e.mean + 5.0 / 3.0) + 2.0 * e.standard_error <= 0.2);
    // The mechanism: the octaves' weights gain_j ~ sigma_j^(1/3). With equal gains the small
    // octaves carry too much: the slope leaves the band.
    const SlopeEstimate equal = drift_frame0_slope(
        {"layer.1.gain=1", "layer.2.gain=1", "layer.3.gain=1", "layer.4.gain=1"});
    INFO("equal gains: slope " << equal.mean << " +- " << equal.standard_error);
    CHECK(std::abs(equal.mean + 5.0 / 3.0) + 2.0 * equal.standard_error > 0.2);
}
