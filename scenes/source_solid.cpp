// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "solid": a 2-D slice z = z0 + velocity t through sparse-convolution solid
// noise (synth/solid.h; Lewis 1989 §4) as a layer source, so solid noise is composited, shaded
// and animated like other layers (animation by moving through the noise, L89 §5.3). With
// dims = 4 the slice also advances along the noise's fourth axis at `rate` units per second.
// A slice of an isotropic 3-D field has the field's one-point statistics: mean 0 and
// Campbell's variance lambda E[a^2] int h^2 d^3x, and (3-D) the 2-D spectrum
// S_2(k) = int S_3(k, k_z) dk_z, the projection of the volume's (docs/solid.md "Slices").

#include <cmath>
#include <numbers>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/loader_detail.h"
#include "scenes/source_detail.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

class SolidSource final : public LayerSource {
public:
    SolidSource(const synth::SolidParams& p, double z0, double velocity, double rate)
        : m_noise(p), m_z0(z0), m_velocity(velocity), m_rate(rate) {
        if (p.dims == 3) m_slice.emplace(m_noise);
    }
    std::string_view kind() const override { return "solid"; }
    void add(const numeric::View& v, double t_s, numeric::Frame& out) const override {
        std::vector<synth::SolidPoint> pts(size_t(v.width) * v.height);
        const double z = m_z0 + m_velocity * t_s, w = m_rate * t_s;
        for (int j = 0; j < v.height; ++j)
            for (int i = 0; i < v.width; ++i)
                pts[size_t(j) * v.width + i] = {v.x0 + (i + 0.5) * v.scale, v.y0 + (j + 0.5) * v.scale, z, w};
        std::vector<float> values;
        m_noise.evaluate(pts, values);
        for (size_t k = 0; k < values.size(); ++k) out.data[k] += values[k];
    }
    Theory theory(double) const override { return {0.0, m_noise.theory().variance}; }
    /// The points of a view and their values, made per frame by `add`.
    double memory_bytes(double pixels, bool) const override {
        return pixels * double(sizeof(synth::SolidPoint) + sizeof(float));
    }
    double correlation_length() const override { return m_noise.kernel().radius(); }
    /// The slice's 2-D spectrum (projection-slice); 4-D noise states its variance only.
    std::optional<double> power_spectrum(double k_cycles) const override {
        if (!m_slice) return std::nullopt;
        return (*m_slice)(k_cycles);
    }
    std::string no_spectrum_reason() const override {
        return m_slice ? "" : "4-D solid noise states its variance only (the slice spectrum is "
                              "derived for 3-D noise)";
    }

private:
    synth::SolidNoise m_noise;
    std::optional<synth::SolidSliceSpectrum> m_slice;
    double m_z0, m_velocity, m_rate;
};

/// A kernel designed from a 3-D spectrum or isotropic correlation (kernel = "spectrum" or
/// "autocorrelation"), scaled so the noise at `density` has that spectrum. Band-limited to
/// nyquist (default the pixel Nyquist frequency 0.5 zoom), so the slice does not alias.
kernels::KernelParams read_solid_design(Reader& t, bool acf, double density, double zoom,
                                        const std::filesystem::path& base) {
    namespace K = kernels;
    K::DesignOptions o;
    o.dims = 3;
    o.nyquist = 0.5 * zoom;
    o.window = static_cast<K::DesignWindow>(t.choice("window", K::kDesignWindowNames, 1));
    o.radius = t.number("radius", 0.0, kPositive, "a radius > 0 (texture units)");
    const K::DesignedKernel d = read_design(t, acf, base, o);
    // Campbell in 3-D: kappa_4 / kappa_2^2 = (E[a^4] / E[a^2]^2) / (lambda V_eff), 9/5 for
    // uniform amplitudes, V_eff = (int h^2)^2 / int h^4 over space.
    const double lambda = density / (4.0 / 3.0 * std::numbers::pi * std::pow(d.params.radius, 3));
    const double kurtosis = 1.8 / (lambda * d.report.effective_area);
    if (kurtosis > 1.0) {
        std::ostringstream s;
        s << std::setprecision(3) << "the designed kernel is peaked: at density " << density
          << " the noise's excess kurtosis is " << kurtosis << " and it looks speckled; density >= "
          << std::ceil(density * kurtosis / 0.3) << " brings it to 0.3";
        t.warn("density", s.str());
    }
    return synth::solid_designed_kernel(d.params, density);
}

}  // namespace

std::shared_ptr<const LayerSource> read_solid_source(std::optional<Reader> t, uint64_t seed,
                                                     const std::filesystem::path& base,
                                                     double zoom) {
    synth::SolidParams p;
    p.kernel.radius = 16.0;
    p.seed = seed;
    double z0 = 0.0, velocity = 0.0, rate = 0.0;
    if (t) {
        static constexpr std::array<std::string_view, 4> kKernels = {"cosine", "gaussian", "spectrum",
                                                                     "autocorrelation"};
        const size_t kernel = t->choice("kernel", kKernels, 0);
        p.density = t->number("density", 16.0, [](double d) { return d > 0.0 && d <= 1000.0; },
                              "impulses per kernel volume 4/3 pi R^3, in (0, 1000]");
        p.dims = static_cast<int>(t->integer("dims", 3, 3, 4));
        if (kernel >= 2) {
            if (p.dims != 3)
                t->fail(t->node("dims"), "dims",
                        "a kernel designed from a 3-D spectrum or correlation needs dims = 3");
            p.kernel = read_solid_design(*t, kernel == 3, p.density, zoom, base);
        } else {
            p.kernel.type = kernel == 0 ? kernels::KernelType::Cosine : kernels::KernelType::Gaussian;
            p.kernel.radius = t->number("radius", 16.0, [](double r) { return r >= 1e-3 && r <= 1e6; },
                                        "a kernel radius in [1e-3, 1e6] texture units");
            p.kernel.sigma = p.kernel.radius / 3.0;
            // Point samples of a kernel spanning few pixels alias (the slice is not band-limited).
            if (p.kernel.radius * zoom < 2.0)
                t->warn("radius", "radius = " + num(p.kernel.radius) + " texture units is " +
                                      num(p.kernel.radius * zoom) + " pixels at zoom " + num(zoom) +
                                      ", under 2: the slice aliases (its spectrum reaches past the "
                                      "pixel Nyquist frequency); raise radius or use kernel = "
                                      "\"spectrum\", band-limited to nyquist");
        }
        auto finite = [](double x) { return std::abs(x) <= 1e12; };
        z0 = t->number("z0", 0.0, finite, "a finite z in texture units, within +-1e12");
        velocity = t->number("velocity", 0.0, finite, "texture units per second along z, within +-1e12");
        rate = t->number("rate", 0.0, finite, "units per second along the fourth axis, within +-1e12");
        if (rate != 0.0 && p.dims != 4)
            t->fail(t->node("rate"), "rate", "rate moves along the fourth axis: set dims = 4");
        t->finish();
    }
    return std::make_shared<const SolidSource>(p, z0, velocity, rate);
}

}  // namespace impulse::scenes::detail
