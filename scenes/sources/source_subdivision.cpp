// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "subdivision": generalized stochastic subdivision (synth/subdivision.h;
// Lewis 1986 §2, Lewis 1987) as a layer source. A periodic field of N x N samples of any
// autocorrelation the synthesizer states (the named models, an expression, a table; isotropic
// or anisotropic) spans `size` texture units and tiles the plane. The autocorrelation's lengths
// are in texture units here: R is evaluated at lags scaled by the sample spacing, so the same
// scene gives the same texture at another `samples`, only finer. Sample (i, j) sits at the
// centre of cell (i, j), where a view at one cell per pixel puts its pixel centres: such a view
// reads the samples, whose variance is R(0); a magnified view reads the bilinear interpolant
// between them, whose variance is lower (docs/scenes.md).

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "kernels/spectral.h"
#include "numeric/errors.h"
#include "scenes/detail/source.h"
#include "scenes/detail/source_grid.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

/// The shortest lag along x or y (texture units) at which |R| falls to R(0) / e: how far the
/// field is correlated; the tile's side when it never does.
double correlation_length(const synth::Acf& acf, const SampleGrid& g) {
    const double r0 = acf.R(0.0, 0.0);
    for (int k = 1; k < g.n; ++k)
        if (std::abs(acf.R(k, 0.0)) < r0 / M_E || std::abs(acf.R(0.0, k)) < r0 / M_E)
            return k * g.cell;
    return g.n * g.cell;
}

class SubdivisionSource final : public LayerSource {
public:
    SubdivisionSource(const synth::Acf& acf, const synth::GssOptions& o, int n, double size) {
        m_grid.n = n;
        m_grid.cell = size / n;
        m_grid.offset = 0.5;
        m_grid.periodic = true;
        const synth::Field f = synth::synthesize(acf, o, 0, 0, n, n, true);
        m_grid.values.assign(f.values.begin(), f.values.end());
        // The tile keeps its own mean (a draw of the field's, 0 +- its sampling error), so its
        // samples keep the model's variance R(0); a perspective view fades to that mean, which
        // its near pixels average to, not to the layer's stated 0 (docs/perspective.md §8).
        double sum = 0.0;  // in a fixed order
        for (float v : m_grid.values) sum += v;
        m_grid.mean = sum / double(m_grid.values.size());
        m_variance = acf.R(0.0, 0.0);
        m_length = detail::correlation_length(acf, m_grid);
    }
    std::string_view kind() const override { return "subdivision"; }
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
    double correlation_length() const override { return m_length; }
    /// No spectrum: the construction's covariance departs from the specified model by more than
    /// the analysis resolves (in 2-D up to about 0.1 R(0) at short lags, and a variance of about
    /// 0.93 R(0), docs/subdivision.md), so the model's spectrum would report a disagreement that
    /// is the method's, not the frames'.
    std::string no_spectrum_reason() const override {
        return "a subdivision layer's covariance is the specified model's only approximately "
               "(docs/subdivision.md: up to about 0.1 R(0) apart at short lags in 2-D), so no "
               "spectrum is stated";
    }

private:
    SampleGrid m_grid;
    LazyPyramid m_pyramid;
    double m_variance = 0.0, m_length = 1.0;
};

/// A number as synth::make_acf parses it back, to the last bit.
std::string precise(double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
}

/// The model's parameters as synth::make_acf takes them (lengths converted from texture units
/// to samples by wrapping R below, so only dimensionless values and the table's path pass).
std::vector<synth::AcfParam> read_acf_params(Reader& t, const std::filesystem::path& base) {
    std::vector<synth::AcfParam> params;
    for (std::string_view key : {"variance", "length", "exponent", "nu", "omega", "aspect", "angle",
                                 "k0", "f0", "width", "slope", "k_low", "k_high", "nyquist"})
        if (t.has(key)) params.emplace_back(std::string(key), precise(t.number(key, 0.0)));
    if (t.has("separable")) params.emplace_back("separable", t.boolean("separable", false) ? "1" : "0");
    if (t.has("expr")) params.emplace_back("expr", t.string("expr", ""));
    if (t.has("file"))
        params.emplace_back("file", resolve_path(t.node("file"), t.string("file", ""), base).string());
    return params;
}

}  // namespace

std::shared_ptr<const LayerSource> read_subdivision_source(Reader* t, uint64_t seed,
                                                           const std::filesystem::path& base,
                                                           const TileBudget& budget) {
    const std::string model = t->string("acf", "");
    if (model.empty()) t->fail(t->node("acf"), "acf", "expected the autocorrelation's model name");
    std::vector<synth::AcfParam> params = read_acf_params(*t, base);
    const int64_t n = t->integer("samples", 256, 2, 8192);
    if ((n & (n - 1)) != 0)
        t->fail(t->node("samples"), "samples",
                "expected a power of two in [2, 8192] (the periodic field's side)");
    const double size = t->number("size", double(n), [](double s) { return s > 0.0 && s <= 1e9; },
                                  "the side of the tile in texture units, in (0, 1e9]");
    synth::GssOptions o;
    o.dims = 2;
    o.seed = seed;
    o.max_neighbors = int(t->integer("neighbors", 8, 2, 16));
    if (o.max_neighbors % 2)
        t->fail(t->node("neighbors"), "neighbors", "expected an even neighbourhood size 2N in [2, 16]");
    static constexpr std::array<std::string_view, 2> kDisplacements = {"correlated", "independent"};
    o.correlated = t->choice("displacement", kDisplacements, 0) == 0;
    t->finish();
    // Field values, the finest level's work arrays and the neighbourhood solves: about three
    // doubles per sample.
    budget.check(*t, "samples", "the field",
                 double(n) * double(n) * 3 * sizeof(double) / (1024.0 * 1024.0));
    const double cell = size / double(n);
    // A model defined by its spectrum is band-limited to the samples' Nyquist frequency in
    // texture units unless the scene says otherwise.
    const auto m = kernels::spectral_model_from_string(model);
    if (m && !kernels::defined_by_autocorrelation(*m) && !t->has("nyquist")) {
        params.emplace_back("nyquist", precise(0.5 / cell));
    }
    try {
        const synth::Acf texture = synth::make_acf(model, params);
        synth::Acf samples{[R = texture.R, cell](double x, double y) { return R(x * cell, y * cell); },
                           texture.name};
        return std::make_shared<const SubdivisionSource>(samples, o, int(n), size);
    } catch (const ValueError& e) {
        t->fail(t->node("acf"), "acf", e.what());
    }
}

}  // namespace impulse::scenes::detail
