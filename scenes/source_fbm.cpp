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
#include "scenes/source_grid.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

class FbmSource final : public LayerSource {
public:
    FbmSource(const synth::FbmOptions& o, double size, uint64_t seed) {
        m_grid.n = o.size;
        m_grid.cell = size / o.size;
        m_grid.periodic = o.method == synth::FbmMethod::Fourier;
        m_grid.values = synth::fbm(o, seed).data;
        double sum = 0.0;  // the tile's mean, in a fixed order
        for (float v : m_grid.values) sum += v;
        const double mean = sum / double(m_grid.values.size());
        for (float& v : m_grid.values) v = static_cast<float>(v - mean);
        m_variance = m_grid.periodic ? synth::fourier_fbm_variance(o)
                                     : synth::fbm_tile_variance(o.hurst, o.size);
    }
    std::string_view kind() const override { return "fbm"; }
    void add(const numeric::View& v, double, numeric::Frame& out) const override { m_grid.add(v, out); }
    bool perspective() const override { return true; }
    void add_perspective(const PixelFootprints& px, double dx, double dy, double,
                         numeric::Frame& out) const override {
        m_pyramid.get(m_grid).add(px, dx, dy, out);
    }
    Theory theory(double) const override { return {0.0, m_variance}; }
    double correlation_length() const override { return 8.0 * m_grid.cell; }

private:
    SampleGrid m_grid;
    LazyPyramid m_pyramid;
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
