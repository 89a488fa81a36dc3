// SPDX-License-Identifier: Apache-2.0
#include "synth/detail/periodic.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "sim/normal.h"
#include "numeric/rng.h"
#include "numeric/errors.h"
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

void symmetric_dft_2d(std::vector<double>& q, int h) {
    // REDFT00 of length h: Y_k = X_0 + (-1)^k X_{h-1} + 2 sum_{j=1}^{h-2} X_j cos(pi j k/(h-1)),
    // the DFT of the even extension of period n = 2 (h - 1) (eq. 15 with eqs. 12-13).
    const int dims[2] = {h, h};
    numeric::dct1(q.data(), 2, dims);
}

void symmetric_dft_1d(std::vector<double>& v) {
    const int dims[1] = {int(v.size())};
    numeric::dct1(v.data(), 1, dims);
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
    std::vector<double> x = numeric::inverse_real_1d(half.data(), n);
    x.resize(size_t(std::min(n, count)));
    return x;
}

void parallel_blocks(int count, int grain, const std::function<void(int, int)>& body) {
    const int blocks = (count + grain - 1) / grain;
    tbb::parallel_for(0, blocks, [&](int b) { body(b * grain, std::min(count, (b + 1) * grain)); });
}

PeriodicField::PeriodicField(int n, int rows) : m_fft(n, rows) {}

void PeriodicField::fill(const std::vector<float>& amp, uint64_t seed, uint32_t stream,
                         bool quarter) {
    const int n = this->n(), h = half();
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
