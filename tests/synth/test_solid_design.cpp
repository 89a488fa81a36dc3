// SPDX-License-Identifier: Apache-2.0
// Kernels of solid noise designed from a 3-D spectrum or an isotropic 3-D correlation
// (kernels::DesignOptions::dims = 3, synth::solid_designed_kernel): Campbell's variance and the
// radial spectrum against the target's closed form, the measured variance against Campbell, the
// refusals (a negative 3-D spectrum, a correlation below the 3-D bound -0.218 R(0), 2-D models),
// and the 2-D spectrum of a slice (projection-slice) against the 3-D variance.

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "kernels/kernels.h"
#include "kernels/quadrature.h"
#include "numeric/errors.h"
#include "synth/synth.h"

using namespace impulse;
namespace K = impulse::kernels;

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kZ = 5.0;  // |z| beyond which a statistical check fails

/// Gaussian correlation e^{-r^2/l^2} of unit variance and its 3-D spectrum.
double gaussian_s3(double k, double l) { return std::pow(kPi, 1.5) * l * l * l * std::exp(-std::pow(kPi * l * k, 2)); }

synth::SolidParams designed_params(const K::DesignedKernel& d, double density) {
    synth::SolidParams p;
    p.kernel = synth::solid_designed_kernel(d.params, density);
    p.density = density;
    p.seed = 11;
    return p;
}

K::DesignOptions options3(double radius) {
    K::DesignOptions o;
    o.dims = 3;
    o.nyquist = 0.5;
    o.radius = radius;
    return o;
}

}  // namespace

TEST_CASE("solid design: a gaussian correlation's kernel has its variance and 3-D spectrum", "[synth][solid][design]") {
    // l = 6: S_3 at the pass band's edge 0.4 is e^-57 of its peak, so the roll-off removes
    // nothing; radius 24 = 4 l holds all but e^-32 of h ~ e^{-2 r^2 / l^2}. What is left is the
    // profile's interpolation (16 samples per 1/nyquist: relative error eps < 1e-3 of max h,
    // kernels/spectral.h), so int h^2 is within 2 eps and |H(k)|^2 within
    // 2 eps H(0) / H(k) = 2 eps sqrt(S(0) / S(k)) (h >= 0: |dH| <= eps int h).
    const double l = 6.0, eps = 1e-3;
    K::ModelParams m;
    m.model = K::SpectralModel::Gaussian;
    m.length = l;
    for (const bool acf : {false, true}) {
        const K::DesignedKernel d = acf ? K::kernel_from_autocorrelation(K::model_autocorrelation(m), options3(24.0))
                                        : K::kernel_from_spectrum(K::model_spectrum(m, 0.5, 3), options3(24.0));
        const synth::SolidNoise noise(designed_params(d, 16.0));
        INFO((acf ? "from the correlation" : "from the spectrum") << ": Campbell variance "
             << noise.theory().variance);
        CHECK(std::abs(noise.theory().variance - 1.0) <= 2 * eps);
        for (double k = 0.0; k <= 0.1; k += 0.005) {
            const double target = gaussian_s3(k, l), got = noise.radial_power_spectrum(k);
            if (target < 1e-3 * gaussian_s3(0, l)) break;
            const double tol = 2 * eps * std::sqrt(gaussian_s3(0, l) / target);
            INFO("k = " << k << ": S " << got << ", target " << target);
            CHECK(std::abs(got / target - 1.0) <= tol);
        }
    }
    // The 3-D design is what makes it pass: the same S designed as a 2-D kernel (dims = 2) and
    // used in 3-D misses the variance far beyond the tolerance.
    K::DesignOptions o2 = options3(24.0);
    o2.dims = 2;
    const synth::SolidNoise wrong(designed_params(K::kernel_from_spectrum(K::model_spectrum(m, 0.5, 3), o2), 16.0));
    INFO("designed in 2-D: variance " << wrong.theory().variance);
    CHECK(std::abs(wrong.theory().variance - 1.0) > 0.1);
}

TEST_CASE("solid design: a markov correlation's noise has Campbell's variance when measured", "[synth][solid][design]") {
    // The closed form: Var = int S_3 T^2 d^3k over the band (T the roll-off), here with
    // S_3 = 8 pi l^3 / (1 + (2 pi l k)^2)^2 (the 3-D transform of e^{-r/l}).
    const double l = 3.0;
    K::ModelParams m;
    m.model = K::SpectralModel::Markov;
    m.length = l;
    K::DesignOptions o = options3(0.0);
    o.energy = 0.999;
    const K::DesignedKernel d = K::kernel_from_autocorrelation(K::model_autocorrelation(m), o);
    const synth::SolidNoise noise(designed_params(d, 64.0));
    const double K0 = o.nyquist, kp = (1 - o.rolloff) * K0;
    const double band = K::detail::integrate(
        [&](double k) {
            const double u = 1 + std::pow(2 * kPi * l * k, 2);
            const double T = k <= kp ? 1.0 : 0.5 + 0.5 * std::cos(kPi * (k - kp) / (K0 - kp));
            return 4 * kPi * k * k * 8 * kPi * l * l * l / (u * u) * T * T;
        },
        0.0, K0, 64);
    // The kernel keeps energy_fraction of int A^2 = band (the window's loss).
    const double campbell = noise.theory().variance;
    INFO("band variance " << band << ", kept " << d.report.energy_fraction << ", Campbell " << campbell);
    CHECK(std::abs(campbell - band * d.report.energy_fraction) <= 2e-3 * band);
    CHECK(d.report.energy_fraction >= 0.998);
    // Measured at points 2R + 1 apart (independent): mean 0, variance Campbell's.
    const double R = noise.kernel().radius(), s = 2 * R + 1;
    std::vector<synth::SolidPoint> pts;
    for (int k = 0; k < 24; ++k)
        for (int j = 0; j < 24; ++j)
            for (int i = 0; i < 24; ++i) pts.push_back({i * s + 0.3, j * s + 0.1, k * s + 0.7, 0});
    std::vector<float> v;
    noise.evaluate(pts, v);
    double s1 = 0, s2 = 0, s4 = 0;
    for (float x : v) s1 += x;
    const double n = double(v.size()), mean = s1 / n;
    for (float x : v) s2 += (x - mean) * (x - mean), s4 += std::pow(x - mean, 4);
    const double var = s2 / (n - 1), se = std::sqrt((s4 / n - var * var) / n);
    INFO("measured variance " << var << " +- " << se << ", mean " << mean);
    CHECK(std::abs(mean) <= kZ * std::sqrt(var / n));
    CHECK(std::abs(var - campbell) <= kZ * se);
}

TEST_CASE("solid design: refusals", "[synth][solid][design]") {
    // A 3-D spectrum negative somewhere.
    const auto neg = K::expression_spectrum("exp(-k*k*100) * (1 - 40*k)");
    CHECK_THROWS_WITH(K::kernel_from_spectrum(neg, options3(0.0)), Catch::Contains("is negative"));
    // A correlation valid in 2-D but not in 3-D: J0(x) e^{-(r/60)^2} has the ring spectrum
    // (smoothed) in 2-D, but dips to -0.40 R(0), below the 3-D bound -0.218.
    K::Autocorrelation j0;
    j0.name = "J0";
    j0.function = [](double r) { return std::cyl_bessel_j(0.0, 0.8 * r) * std::exp(-std::pow(r / 60.0, 2)); };
    CHECK_NOTHROW(K::spectrum_of_autocorrelation(j0, 0.5, 2));
    CHECK_THROWS_WITH(K::spectrum_of_autocorrelation(j0, 0.5, 3), Catch::Contains("-0.218 R(0)") &&
                                                                       Catch::Contains("reaches -0.4 R(0)"));
    CHECK_THROWS_WITH(K::kernel_from_autocorrelation(j0, options3(0.0)), Catch::Contains("-0.218"));
    // Models defined by a 2-D spectrum and anisotropic spectra have no 3-D design here.
    K::ModelParams bp;
    bp.model = K::SpectralModel::Bandpass;
    CHECK_THROWS_WITH(K::model_spectrum(bp, 0.5, 3), Catch::Contains("defined in 2-D"));
    CHECK_THROWS_WITH(K::kernel_from_spectrum(K::expression_spectrum("exp(-k) * (2 + cos(theta))"), options3(0.0)),
                      Catch::Contains("isotropic"));
}

TEST_CASE("solid design: a slice's 2-D spectrum integrates to the 3-D variance", "[synth][solid][design]") {
    // int S_2 d^2k = C(0) = Var: the projection-slice theorem at lag 0. The quadratures
    // (S_3 tabulated 64 points per 1/R, cubic) are good to 1e-4.
    for (const bool designed : {false, true}) {
        synth::SolidParams p;
        p.kernel.radius = 5.0;
        p.density = 16.0;
        if (designed) {
            K::ModelParams m;
            m.model = K::SpectralModel::Gaussian;
            m.length = 4.0;
            p = designed_params(K::kernel_from_spectrum(K::model_spectrum(m, 0.5, 3), options3(0.0)), 16.0);
        }
        const synth::SolidNoise noise(p);
        const synth::SolidSliceSpectrum s2(noise);
        const double var2 = 2 * kPi * K::detail::integrate([&](double k) { return k * s2(k); }, 0.0, s2.cutoff(), 256);
        INFO((designed ? "designed" : "cosine") << ": int S_2 d^2k = " << var2 << ", variance " << noise.theory().variance);
        CHECK(std::abs(var2 / noise.theory().variance - 1.0) <= 1e-4);
    }
}
