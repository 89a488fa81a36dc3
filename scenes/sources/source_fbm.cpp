// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "fbm": a fractional Brownian surface (synth/fbm.h; Kaplan & Kuo 1996,
// Stein 2002) as a layer source. The grid of N x N samples, sigma^2 = 1 per sample step
// (Kaplan & Kuo eq. 2), spans `size` texture units; sample (i, j) sits at (i, j) * size / N
// and the field between samples is bilinear. The tile's own mean is subtracted, so the layer's
// mean is its `mean` key. Fourier synthesis gives a periodic, stationary field that tiles the
// plane; incremental and exact synthesis give true fBm (stationary increments), mirrored at the
// tile's edges so it stays continuous.

#include <cmath>
#include <mutex>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/detail/source.h"
#include "scenes/detail/source_grid.h"
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
        m_hurst = o.hurst;
    }
    std::string_view kind() const override { return "fbm"; }
    void add(const numeric::View& v, double, numeric::Frame& out) const override { m_grid.add(v, out); }
    bool perspective() const override { return true; }
    void add_perspective(const PixelFootprints& px, double dx, double dy, double,
                         numeric::Frame& out) const override {
        m_pyramid.get(m_grid).add(px, dx, dy, out);
    }
    Theory theory(double) const override { return {0.0, m_variance}; }
    double memory_bytes(double, bool perspective) const override {
        return m_grid.bytes() + (perspective ? GridPyramid::bytes(m_grid.n) : 0.0);
    }
    double correlation_length() const override { return 8.0 * m_grid.cell; }
    std::optional<double> power_spectrum(double k) const override {
        if (!m_grid.periodic) return std::nullopt;
        // Radial mean over a quarter turn (the spectrum has the square lattice's symmetry).
        const int n = 64;
        double sum = 0.0;
        for (int i = 0; i < n; ++i) {
            const double a = 0.5 * std::numbers::pi * (i + 0.5) / n;
            sum += spectrum(k * std::cos(a), k * std::sin(a));
        }
        return sum / n;
    }
    std::optional<double> power_spectrum_2d(double kx, double ky) const override {
        if (!m_grid.periodic) return std::nullopt;
        return spectrum(kx, ky);
    }
    /// At p = a / b pixels per sample (b <= kMaxCoherentDenominator) the images of each line
    /// are summed coherently at the lattice's phase (coherent_images); nullopt otherwise, where
    /// they are incoherent and the closed form sums spectrum()'s images as power.
    std::optional<double> sampled_spectrum(double fx, double fy, const PixelLattice& px,
                                           double) const override {
        if (!m_grid.periodic) return std::nullopt;
        const double p = m_grid.cell / px.scale;  // pixels per sample
        const std::optional<int> b = lattice_denominator(p);
        if (!b) return std::nullopt;
        // Pixel 0's centre in pixels from sample 0, modulo a pixel (a whole pixel turns every
        // image of a bin alike).
        const auto phase = [&](double x) {
            const double u = x / px.scale - p * m_grid.offset;
            return u - std::floor(u);
        };
        const auto ax = coherent_images(fx, p, *b, phase(px.x));
        const auto ay = coherent_images(fy, p, *b, phase(px.y));
        // Class c of images is line (nu + c) n p of the tile; its density in pixel units is its
        // variance times (n p)^2 (a line per frequency cell of a tile of n p pixels).
        const double np = m_grid.n * p;
        double s = 0.0;
        for (int cy = 0; cy < *b; ++cy)
            for (int cx = 0; cx < *b; ++cx)
                s += line_variance((fx + cx) * np, (fy + cy) * np) * std::norm(ax[size_t(cx)]) *
                     std::norm(ay[size_t(cy)]);
        return s * np * np;
    }
    bool anisotropic_spectrum() const override { return true; }
    std::string no_spectrum_reason() const override {
        return m_grid.periodic ? ""
                               : "an incremental or exact fbm layer is fBm in its tile (stationary "
                                 "increments, not a stationary field): it has no power spectrum "
                                 "and its variance depends on where a frame sits in the tile";
    }

private:
    /// sum |m|^{-(2H+2)} over the n x n lattice of the tile's frequencies (DC excluded), the
    /// normaliser of the Fourier method's line variances (Kaplan & Kuo eq. 14).
    static double line_sum(int n, double hurst) {
        double sum = 0.0;
        for (int y = -n / 2 + 1; y <= n / 2; ++y)
            for (int x = -n / 2 + 1; x <= n / 2; ++x)
                if (x != 0 || y != 0) sum += std::pow(double(x) * x + double(y) * y, -(hurst + 1.0));
        return sum;
    }
    /// The Fourier method's spectrum as the layer draws it
    /// (docs/scenes.md "Analysis of source layers"): line m of the tile (side L = n cell) has
    /// variance v_m = R(0) |m|^{-(2H+2)} / sum |m'|^{-(2H+2)}, the lattice folded into the
    /// samples' band; spread over its cell of the frequency plane that is a density v_m L^2
    /// (exact at the lines, which are the DFT bins of a frame spanning one tile). The bilinear read multiplies it by the tent's transfer sinc^4(kx c) sinc^4(ky c).
    double spectrum(double kx, double ky) const {
        const double L = m_grid.cell * m_grid.n;
        const double line = line_variance(kx * L, ky * L);
        const auto sinc = [](double x) {
            return x == 0.0 ? 1.0 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
        };
        const double t = sinc(kx * m_grid.cell) * sinc(ky * m_grid.cell);
        return line * L * L * std::pow(t, 4);
    }
    /// v_m of the line nearest (qx, qy) cycles per tile, folded into the samples' band (0 at DC).
    double line_variance(double qx, double qy) const {
        const double half = 0.5 * m_grid.n;
        const auto fold = [&](double q) { return q - double(m_grid.n) * std::round(q / m_grid.n); };
        qx = fold(qx), qy = fold(qy);
        const double q2 = qx * qx + qy * qy;
        if (q2 < 0.25 || std::abs(qx) > half || std::abs(qy) > half) return 0.0;  // no DC line
        // The normaliser only analysis needs: summed on first use, not when a scene loads.
        std::call_once(m_once, [&] { m_line_sum = line_sum(m_grid.n, m_hurst); });
        return m_variance * std::pow(q2, -(m_hurst + 1.0)) / m_line_sum;
    }

    SampleGrid m_grid;
    LazyPyramid m_pyramid;
    double m_variance = 0.0, m_hurst = 0.5;
    mutable std::once_flag m_once;
    mutable double m_line_sum = 1.0;
};

}  // namespace

std::shared_ptr<const LayerSource> read_fbm_source(std::optional<Reader> t, Reader& layer,
                                                   uint64_t seed, const TileBudget& budget) {
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
    if (t)
        budget.check(*t, "samples", "the surface", mib);
    else
        budget.check(layer, "source", "the default 256^2 surface", mib);
    try {
        return std::make_shared<const FbmSource>(o, size, seed);
    } catch (const ValueError& e) {
        if (t) t->fail(nullptr, "method", e.what());
        throw;
    }
}

}  // namespace impulse::scenes::detail
