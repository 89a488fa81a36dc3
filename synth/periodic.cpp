// SPDX-License-Identifier: Apache-2.0
#include "synth/periodic.h"

#include <fftw3.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <string>

#include "sim/normal.h"
#include "numeric/rng.h"
#include "numeric/errors.h"
#include "numeric/fft.h"
#include "numeric/fft.h"

namespace impulse::synth::detail {

int fast_size(int n) {
    for (int m = n + (n & 1);; m += 2) {
        int r = m;
        for (int p : {2, 3, 5, 7})
            while (r % p == 0) r /= p;
        if (r == 1) return m;
    }
}

namespace {

// FFTW threads of every transform here: a constant, not the machine's core count, so the plan
// (FFTW_ESTIMATE) and hence the bits are the same on every machine and under any --threads.
// Set and reset under the planner lock, so other libraries' plans stay serial.
constexpr int kFftThreads = 4;

// Runs `plan` with the planner lock held and FFTW threads set to kFftThreads (float and double
// planners alike).
template <class Plan>
auto with_threads(Plan plan) {
    std::lock_guard<std::mutex> lock(numeric::fftw_planner_mutex());
    static const bool threads = fftwf_init_threads() != 0 && fftw_init_threads() != 0;
    if (threads) fftwf_plan_with_nthreads(kFftThreads), fftw_plan_with_nthreads(kFftThreads);
    auto p = plan();
    if (threads) fftwf_plan_with_nthreads(1), fftw_plan_with_nthreads(1);
    return p;
}

// Plans and runs one in-place FFTW r2r (REDFT00 per axis) transform of `dims` sizes.
void redft00(double* data, int rank, const int* dims) {
    const fftw_r2r_kind kinds[2] = {FFTW_REDFT00, FFTW_REDFT00};
    const fftw_plan plan =
        with_threads([&] { return fftw_plan_r2r(rank, dims, data, data, kinds, FFTW_ESTIMATE); });
    if (plan == nullptr) throw Error("fftw: cannot plan a DCT-I of " + std::to_string(dims[0]));
    fftw_execute(plan);
    std::lock_guard<std::mutex> lock(numeric::fftw_planner_mutex());
    fftw_destroy_plan(plan);
}

}  // namespace

void symmetric_dft_2d(std::vector<double>& q, int h) {
    // REDFT00 of length h: Y_k = X_0 + (-1)^k X_{h-1} + 2 sum_{j=1}^{h-2} X_j cos(pi j k/(h-1)),
    // the DFT of the even extension of period n = 2 (h - 1) (eq. 15 with eqs. 12-13).
    const int dims[2] = {h, h};
    redft00(q.data(), 2, dims);
}

void symmetric_dft_1d(std::vector<double>& v) {
    const int dims[1] = {int(v.size())};
    redft00(v.data(), 1, dims);
}

std::complex<double> complex_normal(uint64_t seed, uint32_t stream, int64_t a, int64_t b,
                                    bool real_only) {
    const numeric::CounterRng rng(seed, stream);
    const auto u = rng.uniforms(a, b, 0, 0);
    const double re = sim::detail::normal_from_uniforms(u[0], u[1]);
    if (real_only) return {re, 0.0};
    const double im = sim::detail::normal_from_uniforms(u[2], u[3]);
    return {re * M_SQRT1_2, im * M_SQRT1_2};
}

std::vector<double> inverse_real_1d(const std::vector<std::complex<double>>& half, int n,
                                    int count) {
    // FFTW's own buffers: the same alignment every call, hence the same plan and bits.
    fftw_complex* in = fftw_alloc_complex(half.size());
    double* out = fftw_alloc_real(size_t(n));
    std::copy(half.begin(), half.end(), reinterpret_cast<std::complex<double>*>(in));
    fftw_plan plan;
    {
        std::lock_guard<std::mutex> lock(numeric::fftw_planner_mutex());
        plan = fftw_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE);
    }
    if (plan != nullptr) fftw_execute(plan);
    std::vector<double> x(out, out + std::min(n, count));
    {
        std::lock_guard<std::mutex> lock(numeric::fftw_planner_mutex());
        if (plan != nullptr) fftw_destroy_plan(plan);
    }
    fftw_free(in);
    fftw_free(out);
    if (plan == nullptr) throw Error("fftw: cannot plan a 1-D transform of " + std::to_string(n));
    return x;
}

void parallel_blocks(int count, int grain, const std::function<void(int, int)>& body) {
    const int blocks = (count + grain - 1) / grain;
    tbb::parallel_for(0, blocks, [&](int b) { body(b * grain, std::min(count, (b + 1) * grain)); });
}

namespace {

// The two passes of the 2-D inverse: along y (every column k_x, stride n/2 + 1) and along x
// (only the first `rows` rows, each n/2 + 1 complex in, n real out in place).
std::pair<fftwf_plan, fftwf_plan> plan_field(int n, int rows, fftwf_complex* spec) {
    return with_threads([&] {
        const int h = n / 2 + 1;
        fftwf_plan y = fftwf_plan_many_dft(1, &n, h, spec, nullptr, h, 1, spec, nullptr, h, 1,
                                           FFTW_BACKWARD, FFTW_ESTIMATE);
        float* real = reinterpret_cast<float*>(spec);
        fftwf_plan x = fftwf_plan_many_dft_c2r(1, &n, rows, spec, nullptr, 1, h, real, nullptr,
                                               1, 2 * h, FFTW_ESTIMATE);
        return std::pair{y, x};
    });
}

}  // namespace

PeriodicField::PeriodicField(int n, int rows) : m_n(n) {
    const size_t count = size_t(n) * half();
    auto* spec = fftwf_alloc_complex(count);
    if (spec == nullptr)
        throw Error("fftw: cannot allocate a " + std::to_string(n) + "x" + std::to_string(n) +
                    " float field (" + std::to_string(bytes(n) / double(1 << 30)) + " GiB)");
    // fftwf_complex is float[2], layout-compatible with std::complex<float> (FFTW manual §4.1.1).
    m_spec = reinterpret_cast<std::complex<float>*>(spec);
    m_real = reinterpret_cast<float*>(spec);
    const auto [y, x] = plan_field(n, std::clamp(rows, 1, n), spec);
    m_plan_y = y, m_plan_x = x;
    if (y == nullptr || x == nullptr) {
        release();
        throw Error("fftw: cannot plan a " + std::to_string(n) + "x" + std::to_string(n) +
                    " inverse transform");
    }
}

PeriodicField::~PeriodicField() { release(); }

void PeriodicField::release() {
    {
        std::lock_guard<std::mutex> lock(numeric::fftw_planner_mutex());
        if (m_plan_y) fftwf_destroy_plan(static_cast<fftwf_plan>(m_plan_y));
        if (m_plan_x) fftwf_destroy_plan(static_cast<fftwf_plan>(m_plan_x));
    }
    m_plan_y = m_plan_x = nullptr;
    fftwf_free(reinterpret_cast<fftwf_complex*>(m_spec));
    m_spec = nullptr;
}

void PeriodicField::inverse() {
    fftwf_execute(static_cast<fftwf_plan>(m_plan_y));
    fftwf_execute(static_cast<fftwf_plan>(m_plan_x));
}

void PeriodicField::fill(const std::vector<float>& amp, uint64_t seed, uint32_t stream,
                         bool quarter) {
    const int n = m_n, h = half();
    const numeric::CounterRng rng(seed, stream);
    parallel_blocks(n, 16, [&](int ky0, int ky1) {
        numeric::DrawBatch draws;
        sim::detail::NormalBatch normals;
        std::vector<float> z(2 * size_t(h));
        for (int ky = ky0; ky < ky1; ++ky) {
            const int kyf = std::min(ky, n - ky);  // folded index: amp and the mirrored draw
            draws.clear();
            normals.clear();
            // Columns k_x = 0 and n/2 are their own mirror: z(k_x, n - k_y) = conj z(k_x, k_y),
            // so both rows draw the counter of the folded k_y.
            for (int kx = 0; kx < h; ++kx)
                draws.add(kx, (kx == 0 || kx == h - 1) ? kyf : ky, 0, 0);
            draws.run(rng);
            for (int kx = 0; kx < h; ++kx) {
                normals.add(draws.u01(size_t(kx), 0), draws.u01(size_t(kx), 1));
                normals.add(draws.u01(size_t(kx), 2), draws.u01(size_t(kx), 3));
            }
            normals.run(z.data());
            const float* a = amp.data() + size_t(quarter ? kyf : ky) * h;
            std::complex<float>* x = row(ky);
            for (int kx = 0; kx < h; ++kx) {
                const float s = a[kx] * float(M_SQRT1_2);
                x[kx] = {s * z[2 * kx], s * z[2 * kx + 1]};
            }
            for (int kx : {0, h - 1}) {
                if (ky == 0 || 2 * ky == n)
                    x[kx] = {a[kx] * z[2 * kx], 0.0f};  // self-conjugate: real N(0, amp^2)
                else if (ky > kyf)
                    x[kx] = std::conj(x[kx]);  // upper half of a self-mirrored column
            }
        }
    });
}

std::vector<float> periodic_crop(int n, const std::vector<float>& amp, uint64_t seed, int size,
                                 bool quarter) {
    PeriodicField field(n, size);
    field.fill(amp, seed, kStreamField, quarter);
    field.inverse();
    std::vector<float> out(size_t(size) * size);
    parallel_blocks(size, 64, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y)
            for (int x = 0; x < size; ++x) out[size_t(y) * size + x] = field.at(x, y);
    });
    return out;
}

}  // namespace impulse::synth::detail
