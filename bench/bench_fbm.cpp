// SPDX-License-Identifier: Apache-2.0
// impulse_bench_fbm: fractional Brownian surfaces (issue 16 item 7) — standard Fourier
// synthesis, Kaplan & Kuo's incremental Fourier synthesis and Stein's exact embedding, each at
// N = 1024, 4096, 8192, side by side: wall and CPU time of the spectra (FbmSynth's constructor,
// once per method/size/H) and of one realisation, the peak resident memory, and the
// incremental/standard ratio. Every row runs in its own child process (fork before any TBB or
// FFTW use in the parent), so its peak memory is that row's alone (wait4's ru_maxrss). See
// bench/README.md.

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/common.h"
#include "synth/synth.h"

namespace {

using namespace impulse;
using namespace impulse::bench;

struct Result {
    double build_ms = 0, realize_ms = 0, cpu_s = 0, peak_mib = 0;
    int fft = 0;
    bool ok = false;
};

// The row in a child: build, realize once (seed 1); times written back through a pipe.
Result run_row(const synth::FbmOptions& o) {
    int fd[2];
    if (pipe(fd) != 0) return {};
    const pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        Result r;
        const auto t0 = Clock::now();
        const synth::FbmSynth s(o);
        r.build_ms = ms_since(t0);
        const auto t1 = Clock::now();
        const synth::Surface f = s.realize(1);
        r.realize_ms = ms_since(t1);
        r.cpu_s = own_cpu_s();
        r.fft = s.fft_size();
        r.ok = f.data.size() == size_t(o.size) * o.size;
        if (write(fd[1], &r, sizeof r) != ssize_t(sizeof r)) _exit(2);
        _exit(0);
    }
    close(fd[1]);
    Result r;
    const bool got = read(fd[0], &r, sizeof r) == ssize_t(sizeof r);
    close(fd[0]);
    int status = 0;
    rusage ru{};
    wait4(pid, &status, 0, &ru);
    if (!got || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return {};
    r.peak_mib = double(ru.ru_maxrss) / 1024.0;  // kB on Linux
    return r;
}

}  // namespace

int main(int argc, char** argv) {
    std::vector<int> sizes = {1024, 4096, 8192};
    double H = 0.5;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--quick") sizes = {256, 1024};
        if (a == "--hurst" && i + 1 < argc) H = std::atof(argv[++i]);
    }
    std::printf("impulse_bench_fbm: H = %.2f, one realisation per row (seed 1), each row in its "
                "own process; load average %s\n\n",
                H, loadavg().c_str());
    std::printf("%6s  %-12s %6s  %10s  %10s  %10s  %8s  %9s  %s\n", "N", "method", "fft",
                "spectra ms", "field ms", "total ms", "cpu s", "peak MiB", "others");
    for (int N : sizes) {
        double total[3] = {0, 0, 0};
        int m = 0;
        for (auto method :
             {synth::FbmMethod::Fourier, synth::FbmMethod::Incremental, synth::FbmMethod::Exact}) {
            const synth::FbmOptions o{method, H, N, false};
            const double busy0 = machine_busy_s(), own0 = own_cpu_s();
            const auto t0 = Clock::now();
            std::fflush(stdout);  // the child must not inherit unwritten output
            const Result r = run_row(o);
            const double wall_s = ms_since(t0) / 1e3;
            // Other processes' CPU while the row ran, % of one core (the child's own CPU out).
            const double others =
                100.0 * (machine_busy_s() - busy0 - (own_cpu_s() - own0) - r.cpu_s) / wall_s;
            total[m++] = r.build_ms + r.realize_ms;
            if (!r.ok) {
                std::printf("%6d  %-12s  failed (memory?)\n", N, synth::to_string(method));
                continue;
            }
            std::printf("%6d  %-12s %6d  %10.0f  %10.0f  %10.0f  %8.2f  %9.0f  %5.0f%%%s\n", N,
                        synth::to_string(method), r.fft, r.build_ms, r.realize_ms,
                        r.build_ms + r.realize_ms, r.cpu_s, r.peak_mib, others,
                        others > 5 ? " !" : "");
        }
        std::printf("%6d  incremental / standard = %.2f, exact / standard = %.2f\n", N,
                    total[1] / total[0], total[2] / total[0]);
    }
    return 0;
}
