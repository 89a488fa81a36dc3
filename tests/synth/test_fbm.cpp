// SPDX-License-Identifier: Apache-2.0
// Fractional Brownian surfaces (issue 16 item 6): the exact method's generalised Hurst exponent
// H(s) (Kaplan & Kuo eq. 21) within its sampling band of H, incremental synthesis within 0.05 of
// H while standard Fourier synthesis drifts beyond, and the per-pixel variance growing as
// |m|^{2H} from the origin (exact, incremental) or flat (standard) — their Figs. 1-3.
// The default runs use N = 256; the N = 512 runs are tagged [.slow].

#include <catch2/catch.hpp>

#include <tbb/global_control.h>

#include <cmath>
#include <cstring>

#include "analysis/analysis.h"
#include "synth/synth.h"
#include "numeric/errors.h"

using namespace impulse;
using synth::FbmMethod;

namespace {

constexpr int kRealizations = 64;
// |z| beyond which a check fails: two-sided 6e-5 per check, about 1e-3 over the ~20 checks of a
// run (family-wise, Bonferroni).
constexpr double kZ = 4.0;

analysis::Image to_image(synth::Surface&& f) { return {f.width, f.height, std::move(f.data)}; }

struct Pooled {
    analysis::StructureSummary structure;
    analysis::Image variance;
};

Pooled pooled(FbmMethod method, double H, int N, int max_s) {
    const synth::FbmSynth synth({method, H, N, false});
    analysis::StructureAccumulator acc(max_s);
    analysis::PixelVariance var;
    for (int r = 0; r < kRealizations; ++r) {
        const analysis::Image im = to_image(synth.realize(1000 + r));
        acc.add(im);
        var.add(im);
    }
    return {acc.summary(), var.variance()};
}

// Exact: |H^(s) - H| <= kZ stderr(s) at every s (the pooled estimate of an exact method has
// E f(d) = d^{2H} at every lag, so only sampling error is left).
void check_exact_band(const Pooled& p, double H, int max_s) {
    const auto& S = p.structure;
    REQUIRE(int(S.hurst.size()) >= max_s + 1);
    for (int s = 0; s <= max_s; ++s) {
        INFO("H = " << H << ", s = " << s << ": H(s) = " << S.hurst[s] << " +- "
                    << S.hurst_stderr[s]);
        CHECK(std::abs(S.hurst[s] - H) <= kZ * S.hurst_stderr[s]);
    }
}

// Incremental: the method's own H(s) within 0.05 of H: the estimate may exceed 0.05 by no more
// than its sampling error allows.
void check_within(const Pooled& p, double H, int max_s, double tol) {
    const auto& S = p.structure;
    for (int s = 0; s <= max_s; ++s) {
        INFO("H = " << H << ", s = " << s << ": H(s) = " << S.hurst[s] << " +- "
                    << S.hurst_stderr[s]);
        CHECK(std::abs(S.hurst[s] - H) <= tol + kZ * S.hurst_stderr[s]);
    }
}

// Log-log slope of the per-pixel variance against |m| over the dyadic rings 2^j <= |m| < 2^{j+1}
// of the quadrant (j >= 1), and its standard error: each ring mean of a variance over n
// realizations has a relative sd of at most sqrt(2 / (n - 1)) (fully correlated pixels; Gaussian
// field), taken as the sd of its log, rings independent.
struct Slope {
    double slope = 0, stderr_slope = 0;
};
Slope variance_slope(const analysis::Image& v) {
    std::vector<double> x, y;
    for (int j = 1; (1 << j) < v.width; ++j) {
        double sum = 0;
        int count = 0;
        for (int my = 0; my < v.height; ++my)
            for (int mx = 0; mx < v.width; ++mx) {
                const double r = std::hypot(mx, my);
                if (r >= (1 << j) && r < (2 << j)) sum += v.at(mx, my), ++count;
            }
        x.push_back(std::log(std::ldexp(1.5, j)));  // ring's middle radius
        y.push_back(std::log(sum / count));
    }
    double mx = 0, my = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) mx += x[i] / x.size(), my += y[i] / x.size();
    for (size_t i = 0; i < x.size(); ++i)
        sxx += (x[i] - mx) * (x[i] - mx), sxy += (x[i] - mx) * (y[i] - my);
    return {sxy / sxx, std::sqrt(2.0 / (kRealizations - 1)) / std::sqrt(sxx)};
}

void check_variance_growth(const Pooled& p, double expected_slope) {
    const Slope s = variance_slope(p.variance);
    INFO("variance slope " << s.slope << " +- " << s.stderr_slope << ", expected "
                           << expected_slope);
    CHECK(std::abs(s.slope - expected_slope) <= kZ * s.stderr_slope);
}

void run_item6(int N, int max_s) {
    for (double H : {0.2, 0.5, 0.8}) {
        const Pooled exact = pooled(FbmMethod::Exact, H, N, max_s);
        check_exact_band(exact, H, max_s);
        check_variance_growth(exact, 2 * H);
        const Pooled inc = pooled(FbmMethod::Incremental, H, N, max_s);
        check_within(inc, H, max_s, 0.05);
        check_variance_growth(inc, 2 * H);
    }
}

}  // namespace

TEST_CASE("fBm: exact and incremental H(s) and variance growth, N = 256", "[synth][stats]") {
    run_item6(256, 5);
}

TEST_CASE("fBm: exact and incremental H(s) and variance growth, N = 512", "[synth][stats][.slow]") {
    run_item6(512, 6);
}

TEST_CASE("fBm: standard Fourier synthesis drifts (Kaplan & Kuo Fig. 3)", "[synth][stats]") {
    const int N = 256, max_s = 5;
    for (double H : {0.2, 0.8}) {
        const Pooled std_ = pooled(FbmMethod::Fourier, H, N, max_s);
        const auto& S = std_.structure;
        // Its theoretical H(s), from the periodic covariance of eq. 14, leaves H +- 0.05 ...
        const std::vector<double> theory = analysis::generalized_hurst(
            synth::fourier_fbm_structure({FbmMethod::Fourier, H, N, false}, S.lags));
        double drift = 0;
        for (int s = 0; s <= max_s; ++s) drift = std::max(drift, std::abs(theory[s] - H));
        INFO("H = " << H << ": largest |H(s) - H| of the theory " << drift);
        CHECK(drift > 0.05);
        // ... the realizations follow that theory (the synthesis is what it claims) ...
        for (int s = 0; s <= max_s; ++s) {
            INFO("s = " << s << ": H(s) = " << S.hurst[s] << " +- " << S.hurst_stderr[s]
                        << ", theory " << theory[s]);
            CHECK(std::abs(S.hurst[s] - theory[s]) <= kZ * S.hurst_stderr[s] + 1e-3);
        }
        // ... so the check the exact method passes fails for it, and its variance is flat.
        int outside = 0;
        for (int s = 0; s <= max_s; ++s)
            outside += std::abs(S.hurst[s] - H) > 0.05 + kZ * S.hurst_stderr[s];
        CHECK(outside > 0);
        check_variance_growth(std_, 0.0);
    }
    // Kaplan & Kuo Fig. 3(c): at H = 0.2 the finest scale comes out too smooth, H(0) ~ 0.44.
    const std::vector<double> f = synth::fourier_fbm_structure(
        {FbmMethod::Fourier, 0.2, 256, false}, analysis::dyadic_lags(2));
    CHECK(analysis::generalized_hurst(f)[0] > 0.4);
}

TEST_CASE("fBm: sigma^2 = 1 and B(0, 0) = 0", "[synth]") {
    const int lag1[] = {1};
    for (FbmMethod m : {FbmMethod::Exact, FbmMethod::Incremental, FbmMethod::Fourier}) {
        const synth::FbmSynth synth({m, 0.5, 128, false});
        std::vector<double> f1;
        for (int r = 0; r < 16; ++r) {
            const analysis::Image im = to_image(synth.realize(7 + r));
            if (m != FbmMethod::Fourier) CHECK(im.at(0, 0) == 0.0f);
            f1.push_back(analysis::structure_function(im, lag1).f[0]);
        }
        // sigma^2 = E[(B(m + e) - B(m))^2] = 1 within kZ standard errors of the mean over the
        // realizations (the pixels of one realization are correlated: their spread is what counts).
        double mean = 0, var = 0;
        for (double v : f1) mean += v / f1.size();
        for (double v : f1) var += (v - mean) * (v - mean) / (f1.size() - 1);
        const double se = std::sqrt(var / f1.size());
        INFO(synth::to_string(m) << ": f(1) = " << mean << " +- " << se);
        CHECK(std::abs(mean - 1.0) < kZ * se);
    }
}

TEST_CASE("fBm: the same bits whatever the thread count", "[synth][determinism]") {
    for (FbmMethod m : {FbmMethod::Fourier, FbmMethod::Incremental, FbmMethod::Exact}) {
        const synth::FbmOptions o{m, 0.3, 128, false};
        const synth::Surface many = synth::fbm(o, 42);
        synth::Surface one;
        {
            tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
            one = synth::fbm(o, 42);
        }
        REQUIRE(one.data.size() == many.data.size());
        CHECK(std::memcmp(one.data.data(), many.data.data(), one.data.size() * 4) == 0);
        CHECK(synth::fbm(o, 43).data != many.data);
    }
}

TEST_CASE("fBm: seamless Fourier tiles", "[synth]") {
    const synth::Surface f = synth::fbm({FbmMethod::Fourier, 0.5, 128, true}, 3);
    // The step across the wrap is an ordinary lag-1 increment: mean square about sigma^2 = 1.
    double wrap = 0;
    for (int y = 0; y < 128; ++y) {
        const double d = f.at(0, y) - f.at(127, y);
        wrap += d * d / 128;
    }
    CHECK(wrap < 2.0);
    const synth::Surface cropped = synth::fbm({FbmMethod::Fourier, 0.5, 128, false}, 3);
    double wrap_c = 0;
    for (int y = 0; y < 128; ++y) {
        const double d = cropped.at(0, y) - cropped.at(127, y);
        wrap_c += d * d / 128;
    }
    CHECK(wrap_c > 10.0);  // about 127^{2H} = 127 for H = 0.5
}

TEST_CASE("fBm: bad input is refused", "[synth][errors]") {
    using Catch::Matchers::Contains;
    const double inf = 1e300;
    REQUIRE_THROWS_AS(synth::check_fbm({FbmMethod::Exact, 1.0, 64, false}, inf), ValueError);
    REQUIRE_THROWS_AS(synth::check_fbm({FbmMethod::Exact, 0.0, 64, false}, inf), ValueError);
    REQUIRE_THROWS_AS(synth::check_fbm({FbmMethod::Exact, 0.5, 100, false}, inf), ValueError);
    REQUIRE_THROWS_AS(synth::check_fbm({FbmMethod::Exact, 0.5, 16384, false}, inf), ValueError);
    REQUIRE_THROWS_AS(synth::check_fbm({FbmMethod::Exact, 0.5, 64, true}, inf), ValueError);
    REQUIRE_THROWS_WITH(synth::parse_fbm_method("midpoint"), Contains("fourier, incremental"));
    // Stein's embedding needs a 4N torus above H = 0.75.
    REQUIRE_THROWS_WITH(synth::check_fbm({FbmMethod::Exact, 0.8, 8192, false}, 4.0 * (1 << 30)),
                        Contains("GiB"));
    CHECK(synth::fbm_memory_bytes({FbmMethod::Exact, 0.8, 8192, false}) > 4.0 * (1 << 30));
    CHECK_NOTHROW(synth::check_fbm({FbmMethod::Incremental, 0.5, 8192, false}, 4.0 * (1 << 30)));
}

TEST_CASE("incremental synthesis of an arbitrary structure function (Kaplan & Kuo §VI)",
          "[synth][stats]") {
    // f~(r) = r^{0.6} up to 16 px, then growing as r^{1.4}: H(s) = 0.3 at the fine scales, 0.7
    // at the coarse ones (an "extended self-similar" surface).
    const auto ft = [](double r) {
        return r <= 16.0 ? std::pow(r, 0.6) : std::pow(16.0, 0.6) * std::pow(r / 16.0, 1.4);
    };
    analysis::StructureAccumulator acc(5);
    for (int r = 0; r < 32; ++r) acc.add(to_image(synth::incremental_synthesis(256, ft, 500 + r)));
    const auto S = acc.summary();
    for (int s : {0, 1, 2}) {
        INFO("s = " << s << ": H(s) = " << S.hurst[s] << " +- " << S.hurst_stderr[s]);
        CHECK(std::abs(S.hurst[s] - 0.3) <= 0.05 + kZ * S.hurst_stderr[s]);
    }
    for (int s : {4, 5}) {
        INFO("s = " << s << ": H(s) = " << S.hurst[s] << " +- " << S.hurst_stderr[s]);
        CHECK(std::abs(S.hurst[s] - 0.7) <= 0.05 + kZ * S.hurst_stderr[s]);
    }
}
