// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "solid": a 2-D slice z = z0 + velocity t through sparse-convolution solid
// noise (synth/solid.h; Lewis 1989 §4) as a layer source, so solid noise is composited, shaded
// and animated like other layers (animation by moving through the noise, L89 §5.3). With
// dims = 4 the slice also advances along the noise's fourth axis at `rate` units per second.
// A slice of an isotropic 3-D field has the field's one-point statistics: mean 0 and
// Campbell's variance lambda E[a^2] int h^2 d^3x (docs/solid.md "Slices").

#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/source_detail.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

class SolidSource final : public LayerSource {
public:
    SolidSource(const synth::SolidParams& p, double z0, double velocity, double rate)
        : m_noise(p), m_z0(z0), m_velocity(velocity), m_rate(rate) {}
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
    double correlation_length() const override { return m_noise.kernel().radius(); }

private:
    synth::SolidNoise m_noise;
    double m_z0, m_velocity, m_rate;
};

}  // namespace

std::shared_ptr<const LayerSource> read_solid_source(std::optional<Reader> t, uint64_t seed) {
    synth::SolidParams p;
    p.kernel.radius = 16.0;
    p.seed = seed;
    double z0 = 0.0, velocity = 0.0, rate = 0.0;
    if (t) {
        static constexpr std::array<std::string_view, 2> kKernels = {"cosine", "gaussian"};
        p.kernel.type = t->choice("kernel", kKernels, 0) == 0 ? kernels::KernelType::Cosine
                                                              : kernels::KernelType::Gaussian;
        p.kernel.radius = t->number("radius", 16.0, [](double r) { return r >= 1e-3 && r <= 1e6; },
                                    "a kernel radius in [1e-3, 1e6] texture units");
        p.kernel.sigma = p.kernel.radius / 3.0;
        p.density = t->number("density", 16.0, [](double d) { return d > 0.0 && d <= 1000.0; },
                              "impulses per kernel volume 4/3 pi R^3, in (0, 1000]");
        p.dims = static_cast<int>(t->integer("dims", 3, 3, 4));
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
