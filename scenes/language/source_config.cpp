// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "fbm" | "subdivision" | "solid": a layer drawn by another synthesizer on the
// layer-source seam (scenes/source.h, docs/scenes.md).

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>

#include "scenes/detail/loader.h"
#include "scenes/detail/marginal.h"
#include "scenes/detail/source.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {

namespace fs = std::filesystem;

namespace {

/// A source carried rigidly by a uniform velocity v(t): f(x, t) = g(x - d(t), t) with
/// d(t) = int_0^t v (the displacement of a particle of the flow, Lewis 1986 §3.1, in closed
/// form: numeric::Keyframed::integral). The statistics are those of g: a translation changes
/// neither the one-point moments nor the spectrum.
class DriftingSource final : public LayerSource {
public:
    DriftingSource(std::shared_ptr<const LayerSource> inner, numeric::Keyframed vx,
                   numeric::Keyframed vy)
        : m_inner(std::move(inner)), m_vx(std::move(vx)), m_vy(std::move(vy)) {}
    std::string_view kind() const override { return m_inner->kind(); }
    void add(const numeric::View& view, double t_s, numeric::Frame& out) const override {
        numeric::View moved = view;
        moved.x0 -= m_vx.integral(t_s);
        moved.y0 -= m_vy.integral(t_s);
        m_inner->add(moved, t_s, out);
    }
    bool perspective() const override { return m_inner->perspective(); }
    std::string no_perspective_reason() const override { return m_inner->no_perspective_reason(); }
    void add_perspective(const PixelFootprints& px, double dx, double dy, double t_s,
                         numeric::Frame& out) const override {
        m_inner->add_perspective(px, dx + m_vx.integral(t_s), dy + m_vy.integral(t_s), t_s, out);
    }
    Theory theory(double t_s) const override { return m_inner->theory(t_s); }
    double correlation_length() const override { return m_inner->correlation_length(); }
    double memory_bytes(double pixels, bool perspective) const override {
        return m_inner->memory_bytes(pixels, perspective);
    }
    std::optional<double> power_spectrum(double k_cycles) const override {
        return m_inner->power_spectrum(k_cycles);
    }
    std::optional<double> power_spectrum_2d(double kx, double ky) const override {
        return m_inner->power_spectrum_2d(kx, ky);
    }
    /// The inner source's on the lattice moved by -d(t_s): the drift changes the phase of a
    /// tile's samples against the pixels.
    std::optional<double> sampled_spectrum(double fx, double fy, const PixelLattice& lattice,
                                           double t_s) const override {
        PixelLattice moved = lattice;
        moved.x -= m_vx.integral(t_s);
        moved.y -= m_vy.integral(t_s);
        return m_inner->sampled_spectrum(fx, fy, moved, t_s);
    }
    bool anisotropic_spectrum() const override { return m_inner->anisotropic_spectrum(); }
    std::string no_spectrum_reason() const override { return m_inner->no_spectrum_reason(); }

private:
    std::shared_ptr<const LayerSource> m_inner;
    numeric::Keyframed m_vx, m_vy;
};

/// The source carried by the layer's [[layer.flow]] tables, all of type "uniform" (their
/// velocities summed); the source itself without any.
std::shared_ptr<const LayerSource> with_flow(Reader& r, const std::string& kind,
                                             std::shared_ptr<const LayerSource> source) {
    auto flows = r.tables("flow");
    if (flows.empty()) return source;
    numeric::Keyframed vx(0.0), vy(0.0);
    for (size_t k = 0; k < flows.size(); ++k) {
        Reader& f = flows[k];
        const std::string type = f.has("type") ? f.string("type", "") : "";
        if (type != "uniform")
            f.fail(f.node("type"), "type",
                   "a " + kind + " layer is carried rigidly: expected type = \"uniform\" (a "
                   "velocity = [vx, vy] or keyframed vx, vy), the only flow that moves a field "
                   "without deforming it");
        auto [fx, fy] = read_uniform_velocity(f);
        f.finish();
        if (flows.size() > 1 && !(fx.is_constant() && fy.is_constant() && vx.is_constant() &&
                                  vy.is_constant()))
            f.fail(nullptr, "vx", "a " + kind + " layer sums several uniform flows only when "
                                  "they are constant: give one flow with the keyframes");
        if (k == 0) {
            vx = fx, vy = fy;
        } else {
            vx = numeric::Keyframed(vx.value(0.0) + fx.value(0.0));
            vy = numeric::Keyframed(vy.value(0.0) + fy.value(0.0));
        }
    }
    return std::make_shared<const DriftingSource>(std::move(source), vx, vy);
}

/// MiB for a message: whole above 100, three significant digits below (a small budget's
/// fractions matter).
std::string mib_text(double mib) {
    std::ostringstream s;
    if (mib >= 100.0)
        s << std::lround(mib);
    else
        s << std::setprecision(3) << mib;
    return s.str();
}

}  // namespace

void TileBudget::check(Reader& t, std::string_view key, std::string_view what,
                       double need_mib) const {
    if (held_mib + need_mib <= limit_mib) return;
    std::string why =
        std::string(what) + " needs an estimated " + mib_text(need_mib) + " MiB, over ";
    if (held_mib > 0.0)
        why += "the " + mib_text(std::max(limit_mib - held_mib, 0.0)) +
               " MiB that limits.max_memory_mib = " + mib_text(limit_mib) +
               " leaves beside the earlier source layers' tiles (" + mib_text(held_mib) + " MiB)";
    else
        why += "limits.max_memory_mib = " + mib_text(limit_mib);
    t.fail(t.node(key), key, why + " (fewer samples, or raise the limit)");
}

/// A [[layer]] drawn by another synthesizer (source = "fbm", "subdivision", "solid"): its seed,
/// mean, gain, marginal and
/// composition; the impulse process's keys are refused (scenes/source.h).
void read_source_layer(Reader& r, size_t i, uint64_t global_seed, const fs::path& base,
                       const TileBudget& budget, double zoom, bool perspective,
                       detail::CompositionReader& compose, LayerConfig& L) {
    const std::string kind(detail::kLayerSourceNames[r.choice("source", detail::kLayerSourceNames, 0)]);
    for (std::string_view key : {"kernel", "density", "amplitude", "period", "lifetime", "envelope",
                                 "loop", "integrator", "substeps", "jacobian", "orientation",
                                 "region", "max_travel"})
        if (r.has(key))
            r.fail(r.node(key), key,
                   "a " + kind + " layer has no " + std::string(key) +
                       ": it belongs to the impulse process (source = \"impulses\")");
    L.process.layer = static_cast<uint32_t>(i);
    L.process.seed = mix_seed(global_seed, static_cast<uint64_t>(r.integer("seed", 1, 0, INT64_MAX)));
    L.mean = r.keyframed("mean", 0.0);
    L.gain = r.keyframed("gain", 1.0);
    if (kind == "fbm") {
        L.source = detail::read_fbm_source(r.table(kind), r, L.process.seed, budget);
    } else if (kind == "solid") {
        L.source = detail::read_solid_source(r.table(kind), L.process.seed, base, zoom,
                                             perspective);
    } else {
        std::optional<Reader> t = r.table(kind);
        if (!t)
            r.fail(r.node("source"), "source",
                   "a subdivision layer needs its [layer.subdivision] table with acf (markov, "
                   "gaussian, oscillatory_markov, ...) and the model's lengths");
        L.source = detail::read_subdivision_source(&*t, L.process.seed, base, budget);
    }
    L.source = with_flow(r, kind, std::move(L.source));
    detail::read_marginal(r, L, base);
    compose.read_layer(r, i, L);
    r.finish();
}

}  // namespace impulse::scenes::detail
