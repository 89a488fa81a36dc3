// SPDX-License-Identifier: Apache-2.0
// [layer.dispersion]: Gabor waves whose carriers move at the phase speed of deep-water waves,
// sqrt(g / k), band by band (long swell outruns short ripples), and whose envelopes move at
// the group speed; without dispersion every band moves at its flow's one speed.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <numbers>
#include <string>

#include "numeric/errors.h"
#include "numeric/fft.h"
#include "render/render.h"
#include "scenes/scenes.h"

using namespace impulse;

namespace {

constexpr int kWidth = 1024;
constexpr double kGravity = 98.1;  // texture units / s^2 (1 unit = 1 dm)
constexpr double kFps = 30.0;
// Carrier frequencies on whole FFT bins of a 1024-pixel row: swell, chop, ripples.
constexpr int kBins[3] = {16, 48, 128};

/// Three Gabor layers, carriers along x, at the frequencies of kBins; `motion` is appended to
/// each layer (a dispersion table or a flow). The domain is periodic with the frame's size, so
/// a row's FFT sees whole periods (no window, no content entering at the edges), and lifetimes
/// are long, so the Hann envelopes change by < 0.1 % between frames: a pure translation and
/// carrier advance turn each bin's coefficient by exactly -2 pi k c dt.
std::string wave_scene(const std::string& motion) {
    std::string text = "[output]\nsize = [1024, 256]\nframes = 40\nfps = 30\n";
    for (int b = 0; b < 3; ++b) {
        const double f = kBins[b] / double(kWidth);
        text += "[[layer]]\nseed = " + std::to_string(30 + b) + "\ndensity = 10.0\nlifetime = 100.0\n" +
                "period = [1024.0, 256.0]\n" +
                "[layer.kernel]\ntype = \"gabor\"\nradius = " + std::to_string(2.0 / f) +
                "\nfrequency = " + std::to_string(f) + "\n" + motion;
    }
    return text;
}

/// Phase speed (units per second) of the component at bin `bin` along x: the phase of the
/// cross-spectrum of consecutive frames, summed over rows and frame pairs 0..n, is
/// -2 pi (bin / N) c dt (a pattern moved by d has its transform times e^{-2 pi i k d}).
double phase_speed(scenes::Renderer& r, int bin, int pairs) {
    numeric::RealFft2d fft(1, kWidth, numeric::FftPlans::Forward);
    render::Frame a, b;
    std::complex<double> cross = 0.0;
    r.render(0, a);
    std::vector<std::complex<double>> prev(a.height), next(a.height);
    const auto row_bin = [&](const render::Frame& f, std::vector<std::complex<double>>& out) {
        for (int y = 0; y < f.height; ++y) {
            for (int x = 0; x < kWidth; ++x) fft.real()[x] = f.at(x, y);
            fft.forward();
            out[y] = fft.spectrum()[bin];
        }
    };
    row_bin(a, prev);
    for (int p = 1; p <= pairs; ++p) {
        r.render(p, b);
        row_bin(b, next);
        for (size_t y = 0; y < next.size(); ++y) cross += next[y] * std::conj(prev[y]);
        prev.swap(next);
    }
    const double k_cycles = bin / double(kWidth);
    return -std::arg(cross) / (2.0 * std::numbers::pi * k_cycles / kFps);
}

}  // namespace

TEST_CASE("dispersion: each band's carrier moves at the deep-water phase speed",
          "[scenes][waves][slow]") {
    scenes::Renderer r(scenes::load_scene_string(
        wave_scene("[layer.dispersion]\ngravity = " + std::to_string(kGravity) + "\n"), "waves.toml"));
    for (int b = 0; b < 3; ++b) {
        const double k = 2.0 * std::numbers::pi * kBins[b] / kWidth;  // radians per unit
        const double c_p = std::sqrt(kGravity / k);
        const scenes::WaveDispersion w = scenes::dispersion_relation(k, kGravity, 0.0);
        CHECK(w.group_speed == Approx(c_p / 2.0));
        // The sampling band: half a bin, over which the packet's phase speed
        // (omega0 + c_g (k' - k)) / k' moves by (c_p - c_g) dk / k = (c_p / 2) / (2 bin).
        const double band = 0.25 * c_p / kBins[b];
        const double c = phase_speed(r, kBins[b], 8);
        INFO("band " << b << ": k = " << k << " rad/unit, measured " << c << ", sqrt(g/k) = " << c_p
                     << " +- " << band);
        CHECK(std::abs(c - c_p) <= band);
    }
}

TEST_CASE("without dispersion every band moves at the flow's one speed and the law fails",
          "[scenes][waves][slow]") {
    // The swell's phase speed for everyone (the waves scene before dispersion): chop and
    // ripples move 1.8 and 2.8 times too fast.
    const double c_swell = std::sqrt(kGravity / (2.0 * std::numbers::pi * kBins[0] / kWidth));
    scenes::Renderer r(scenes::load_scene_string(
        wave_scene("[[layer.flow]]\ntype = \"uniform\"\nvelocity = [" + std::to_string(c_swell) + ", 0.0]\n"),
        "waves.toml"));
    int outside = 0;
    for (int b = 0; b < 3; ++b) {
        const double k = 2.0 * std::numbers::pi * kBins[b] / kWidth;
        const double c_p = std::sqrt(kGravity / k);
        const double c = phase_speed(r, kBins[b], 8);
        CHECK(c == Approx(c_swell).epsilon(0.01));
        outside += std::abs(c - c_p) > 0.25 * c_p / kBins[b];
    }
    CHECK(outside == 2);  // chop and ripples
}

TEST_CASE("dispersion is refused where it has no meaning", "[scenes][waves]") {
    CHECK_THROWS_WITH(
        scenes::load_scene_string("[[layer]]\nlifetime = 1.0\n[layer.dispersion]\n", "w.toml"),
        Catch::Contains("w.toml:") && Catch::Contains("dispersion") && Catch::Contains("gabor"));
    CHECK_THROWS_WITH(scenes::load_scene_string("[[layer]]\nlifetime = 1.0\n[layer.kernel]\ntype = \"gabor\"\n"
                                                "[layer.dispersion]\ngravity = -1\n",
                                                "w.toml"),
                      Catch::Contains("w.toml:6:") && Catch::Contains("gravity = -1"));
    // Finite depth slows long waves: omega^2 = g k tanh(k h).
    const scenes::WaveDispersion shallow = scenes::dispersion_relation(0.1, 9.81, 1.0);
    CHECK(shallow.omega == Approx(std::sqrt(9.81 * 0.1 * std::tanh(0.1))));
    CHECK(shallow.group_speed == Approx(shallow.omega / 0.1).epsilon(0.01));  // shallow: c_g -> c_p
}
