// SPDX-License-Identifier: Apache-2.0
// FbmSynth: the method switch, the input checks and the memory budget.

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "synth/detail/fbm.h"
#include "numeric/errors.h"

namespace impulse::synth {

FbmMethod parse_fbm_method(const std::string& name) {
    if (name == "fourier") return FbmMethod::Fourier;
    if (name == "incremental") return FbmMethod::Incremental;
    if (name == "exact") return FbmMethod::Exact;
    throw ValueError("method = \"" + name + "\": expected one of fourier, incremental, exact");
}

const char* to_string(FbmMethod method) {
    switch (method) {
        case FbmMethod::Fourier: return "fourier";
        case FbmMethod::Incremental: return "incremental";
        case FbmMethod::Exact: return "exact";
    }
    return "?";
}

double fbm_memory_bytes(const FbmOptions& o) {
    switch (o.method) {
        case FbmMethod::Fourier: return detail::fourier_bytes(o);
        case FbmMethod::Incremental: return detail::incremental_bytes(o.size);
        case FbmMethod::Exact: return detail::exact_bytes(o);
    }
    return 0.0;
}

double default_memory_budget() {
    return 0.5 * double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE));
}

namespace {
std::string number(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}

std::string gib(double bytes) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f GiB", bytes / double(1ull << 30));
    return b;
}
}  // namespace

void check_fbm(const FbmOptions& o, double budget_bytes) {
    if (!(o.hurst > 0.0 && o.hurst < 1.0))
        throw ValueError("hurst = " + number(o.hurst) + ": expected H in (0, 1)");
    if (o.size < 2 || o.size > 8192 || (o.size & (o.size - 1)) != 0)
        throw ValueError("size = " + std::to_string(o.size) +
                         ": expected a power of two from 2 to 8192");
    if (o.seamless && o.method != FbmMethod::Fourier)
        throw ValueError(std::string("seamless with method = ") + to_string(o.method) +
                         ": fBm is not periodic; only the fourier method tiles");
    const double need = fbm_memory_bytes(o);
    if (need > budget_bytes)
        throw BudgetError(std::string("size = ") + std::to_string(o.size) + ": method " +
                          to_string(o.method) + " needs about " + gib(need) +
                          ", over the memory budget of " + gib(budget_bytes));
}

FbmSynth::FbmSynth(const FbmOptions& o) {
    check_fbm(o, std::numeric_limits<double>::infinity());
    switch (o.method) {
        case FbmMethod::Fourier: m_impl = detail::make_fourier(o); break;
        case FbmMethod::Incremental: {
            const double H = o.hurst;
            m_impl = detail::make_incremental(o.size, [H](double r) { return std::pow(r, 2 * H); });
            break;
        }
        case FbmMethod::Exact: m_impl = detail::make_exact(o); break;
    }
}

FbmSynth::~FbmSynth() = default;

Surface FbmSynth::realize(uint64_t seed) const { return m_impl->realize(seed); }
int FbmSynth::fft_size() const { return m_impl->fft_size(); }

Surface fbm(const FbmOptions& options, uint64_t seed) { return FbmSynth(options).realize(seed); }

double fbm_tile_variance(double hurst, int n) {
    // (1/2) (1/n^4) sum over lags (dx, dy) of (n - |dx|)(n - |dy|) |d|^{2H}, by symmetry over
    // dx, dy >= 0 with weight 2 for each non-zero component.
    double sum = 0.0;
    for (int dy = 0; dy < n; ++dy) {
        const double wy = (dy == 0 ? 1.0 : 2.0) * (n - dy);
        double row = 0.0;
        for (int dx = 0; dx < n; ++dx) {
            if (dx == 0 && dy == 0) continue;
            const double wx = (dx == 0 ? 1.0 : 2.0) * (n - dx);
            row += wx * std::pow(double(dx) * dx + double(dy) * dy, hurst);
        }
        sum += wy * row;
    }
    const double n2 = double(n) * n;
    return 0.5 * sum / (n2 * n2);
}

Surface incremental_synthesis(int size, const std::function<double(double)>& structure,
                            uint64_t seed) {
    if (size < 2 || (size & (size - 1)) != 0)
        throw ValueError("size = " + std::to_string(size) + ": expected a power of two >= 2");
    return detail::make_incremental(size, structure)->realize(seed);
}

}  // namespace impulse::synth
