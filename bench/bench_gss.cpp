// SPDX-License-Identifier: Apache-2.0
// impulse_bench_gss: a 4097 x 4097 field by generalized stochastic subdivision (Lewis 1987) with
// 4 x 4 (2N = 4, the paper's usual size) and 8 x 8 neighbourhoods, side by side with one FFTW
// Fourier-filtering pass of the same size (white noise, forward FFT, times sqrt(S), inverse
// FFT; FFTW_ESTIMATE, one thread). Markov autocorrelation, length 32. See bench/README.md.
//
//   impulse_bench_gss [--size N] [--reps R]

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <string>
#include <vector>

#include "bench/common.h"
#include "numeric/fft.h"
#include "synth/synth.h"

using namespace impulse;
using bench::Clock;

namespace {

double time_gss(const synth::Acf& acf, int neighbors, bool correlated, int n, int reps,
                int threads) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
    synth::GssOptions o;
    o.dims = 2;
    o.max_neighbors = neighbors;
    o.tolerance = 0;  // always the largest neighbourhood: the cost the row names
    o.debias = 0;
    o.correlated = correlated;
    std::vector<double> t;
    double check = 0;
    for (int r = 0; r < reps; ++r) {
        o.seed = uint64_t(r);
        const auto t0 = Clock::now();
        const synth::Field f = synth::synthesize(acf, o, 0, 0, n, n);
        t.push_back(bench::ms_since(t0));
        check += f.values[f.values.size() / 2];
    }
    if (!std::isfinite(check)) std::printf("non-finite output\n");
    return bench::summarise(t).med;
}

/// One Fourier-filtering pass: the same normals, r2c, multiply by sqrt(S), c2r.
void time_fft(int n, int reps, double length, double& total_ms, double& fft_ms) {
    std::vector<double> tot, ffts;
    for (int r = 0; r < reps; ++r) {
        const auto t0 = Clock::now();
        numeric::RealFft2d fwd(n, n, numeric::FftPlans::Forward), inv(n, n, numeric::FftPlans::Inverse);
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x)
                fwd.real()[size_t(y) * n + x] = synth::node_normal(uint64_t(r), 0, x, y);
        const auto t1 = Clock::now();
        fwd.forward();
        double fft = bench::ms_since(t1);
        const int hc = fwd.half_cols();
        for (int y = 0; y < n; ++y) {
            const double ky = double(y <= n / 2 ? y : y - n) / n;
            for (int x = 0; x < hc; ++x) {
                const double k = std::hypot(double(x) / n, ky);
                const double u = 2 * std::numbers::pi * length * k;  // 2-D markov spectrum
                const double s = 2 * std::numbers::pi * length * length * std::pow(1 + u * u, -1.5);
                inv.spectrum()[size_t(y) * hc + x] =
                    fwd.spectrum()[size_t(y) * hc + x] * std::sqrt(s) / double(n);
            }
        }
        const auto t2 = Clock::now();
        inv.inverse();
        fft += bench::ms_since(t2);
        tot.push_back(bench::ms_since(t0));
        ffts.push_back(fft);
    }
    total_ms = bench::summarise(tot).med;
    fft_ms = bench::summarise(ffts).med;
}

}  // namespace

int main(int argc, char** argv) {
    int n = 4097, reps = 3;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--size")) n = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
    }
    const double length = 32;
    const synth::Acf acf = synth::make_acf("markov", {{"length", "32"}});
    std::printf("impulse_bench_gss: %dx%d, markov length %g, median of %d; load %s\n", n, n, length,
                reps, bench::loadavg().c_str());
    double fft_total = 0, fft_only = 0;
    time_fft(n, reps, length, fft_total, fft_only);
    std::printf("%-44s %10s %10s\n", "method", "ms", "vs FFT");
    std::printf("%-44s %10.0f %10s\n", "FFTW filtering pass (1 thread), total", fft_total, "1.00");
    std::printf("%-44s %10.0f %10.2f\n", "  of which the two FFTs", fft_only, fft_only / fft_total);
    for (bool corr : {false, true})
        for (int nb : {4, 8})
            for (int threads : {1, 2}) {
                const double ms = time_gss(acf, nb, corr, n, reps, threads);
                char name[80];
                std::snprintf(name, sizeof name, "GSS %dx%d, %s, %d thread%s", nb, nb,
                              corr ? "correlated" : "independent", threads, threads > 1 ? "s" : "");
                std::printf("%-44s %10.0f %10.2f\n", name, ms, ms / fft_total);
            }
    return 0;
}
