// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "fbm": a fractional Brownian surface (synth/fbm.h; Kaplan & Kuo 1996,
// Stein 2002) as a layer source. The grid of N x N samples, sigma^2 = 1 per sample step
// (Kaplan & Kuo eq. 2), spans `size` texture units; sample (i, j) sits at (i, j) * size / N
// and the field between samples is bilinear. The tile's own mean is subtracted, so the layer's
// mean is its `mean` key. Fourier synthesis gives a periodic, stationary field that tiles the
// plane; incremental and exact synthesis give true fBm (stationary increments), mirrored at the
// tile's edges so it stays continuous.

#include <cmath>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/source_detail.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

class FbmSource final : public LayerSource {
public:
    FbmSource(const synth::FbmOptions& o, double size, uint64_t seed)
        : m_n(o.size), m_cell(size / o.size), m_periodic(o.method == synth::FbmMethod::Fourier),
          m_grid(synth::fbm(o, seed).data) {
        double sum = 0.0;  // the tile's mean, in a fixed order
        for (float v : m_grid) sum += v;
        const double mean = sum / double(m_grid.size());
        for (float& v : m_grid) v = static_cast<float>(v - mean);
        m_variance = m_periodic ? synth::fourier_fbm_variance(o) : synth::fbm_tile_variance(o.hurst, m_n);
    }
    std::string_view kind() const override { return "fbm"; }
    void add(const numeric::View& v, double, numeric::Frame& out) const override {
        for (int j = 0; j < v.height; ++j) {
            const double y = (v.y0 + (j + 0.5) * v.scale) / m_cell;
            float* row = out.data.data() + size_t(j) * v.width;
            for (int i = 0; i < v.width; ++i)
                row[i] = static_cast<float>(row[i] + sample((v.x0 + (i + 0.5) * v.scale) / m_cell, y));
        }
    }
    Theory theory(double) const override { return {0.0, m_variance}; }
    double correlation_length() const override { return 8.0 * m_cell; }

private:
    /// Grid index k folded into [0, n): wrapped (periodic) or mirrored at the edges.
    int64_t fold(int64_t k) const {
        if (m_periodic) return ((k % m_n) + m_n) % m_n;
        const int64_t p = 2 * (int64_t(m_n) - 1);
        if (p == 0) return 0;
        k = ((k % p) + p) % p;
        return k < m_n ? k : p - k;
    }
    /// The bilinear interpolant at grid coordinates (u, v) (samples at integers).
    double sample(double u, double v) const {
        const double fu = std::floor(u), fv = std::floor(v), a = u - fu, b = v - fv;
        const int64_t i0 = fold(int64_t(fu)), i1 = fold(int64_t(fu) + 1);
        const int64_t j0 = fold(int64_t(fv)), j1 = fold(int64_t(fv) + 1);
        const float* r0 = m_grid.data() + size_t(j0) * m_n;
        const float* r1 = m_grid.data() + size_t(j1) * m_n;
        return (1 - b) * ((1 - a) * r0[i0] + a * r0[i1]) + b * ((1 - a) * r1[i0] + a * r1[i1]);
    }

    int m_n;
    double m_cell;
    bool m_periodic;
    std::vector<float> m_grid;
    double m_variance = 0.0;
};

}  // namespace

std::shared_ptr<const LayerSource> read_fbm_source(std::optional<Reader> t, uint64_t seed,
                                                   double max_memory_mib) {
    synth::FbmOptions o;
    o.size = 256;
    double size = 256.0;
    if (t) {
        static constexpr std::array<std::string_view, 3> kMethods = {"fourier", "incremental",
                                                                     "exact"};
        o.method = static_cast<synth::FbmMethod>(t->choice("method", kMethods, 1));
        o.hurst = t->number("hurst", 0.5, [](double h) { return h > 0.0 && h < 1.0; },
                            "a Hurst exponent H in (0, 1)");
        const int64_t n = t->integer("samples", 256, 2, 4096);
        if ((n & (n - 1)) != 0)
            t->fail(t->node("samples"), "samples", "expected a power of two in [2, 4096]");
        o.size = static_cast<int>(n);
        size = t->number("size", double(n), [](double s) { return s > 0.0 && s <= 1e9; },
                         "the side of the tile in texture units, in (0, 1e9]");
        t->finish();
    }
    o.seamless = o.method == synth::FbmMethod::Fourier;  // the periodic field itself tiles
    const double mib = synth::fbm_memory_bytes(o) / (1024.0 * 1024.0);
    if (mib > max_memory_mib && t)
        t->fail(t->node("samples"), "samples",
                "the surface needs an estimated " + std::to_string(std::lround(mib)) +
                    " MiB, over limits.max_memory_mib = " + std::to_string(std::lround(max_memory_mib)) +
                    " (fewer samples, or raise the limit)");
    try {
        return std::make_shared<const FbmSource>(o, size, seed);
    } catch (const ValueError& e) {
        if (t) t->fail(nullptr, "method", e.what());
        throw;
    }
}

}  // namespace impulse::scenes::detail
