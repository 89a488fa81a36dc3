// SPDX-License-Identifier: Apache-2.0
#pragma once
// Timing, statistics and machine-load helpers shared by the benchmarks.

#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace impulse::bench {

using Clock = std::chrono::steady_clock;

/// Median, minimum and maximum of a set of samples, and how many there were.
struct Stats {
    double med = 0, min = 0, max = 0;
    size_t n = 0;
    Stats scaled(double f) const { return {med * f, min * f, max * f, n}; }
};

inline Stats summarise(std::vector<double> v) {
    if (v.empty()) return {};
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    const double med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    return {med, v.front(), v.back(), n};
}

inline double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// "12.3 [12.1-12.9]": median [min-max] with about three significant digits.
inline std::string cell(const Stats& s) {
    auto f = [](double v) {
        char b[32];
        std::snprintf(b, sizeof b, v < 10 ? "%.2f" : v < 100 ? "%.1f" : "%.0f", v);
        return std::string(b);
    };
    return f(s.med) + " [" + f(s.min) + "-" + f(s.max) + "]";
}

/// The three load averages from /proc/loadavg.
inline std::string loadavg() {
    std::ifstream in("/proc/loadavg");
    std::string a, b, c;
    if (!(in >> a >> b >> c)) return "unavailable";
    return a + " " + b + " " + c;
}

/// Busy CPU seconds of the whole machine from /proc/stat (user nice system irq softirq steal;
/// steal: the hypervisor gave the core to another guest), or -1 when unreadable.
inline double machine_busy_s() {
    std::ifstream in("/proc/stat");
    std::string cpu;
    double v[8] = {};
    if (!(in >> cpu) || cpu != "cpu") return -1;
    for (double& x : v)
        if (!(in >> x)) return -1;
    return (v[0] + v[1] + v[2] + v[5] + v[6] + v[7]) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// CPU milliseconds used by the calling thread: unlike wall time, not inflated when other
/// processes take the core away.
inline double thread_cpu_ms() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e3 * double(t.tv_sec) + 1e-6 * double(t.tv_nsec);
}

/// CPU seconds used by this process (all threads).
inline double own_cpu_s() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    auto s = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
    return s(u.ru_utime) + s(u.ru_stime);
}

}  // namespace impulse::bench
