// SPDX-License-Identifier: Apache-2.0
// The `marginal` key of a [[layer]] (docs/scenes.md): distribution shaping (Lewis 1986 §4) and
// the spectrum pre-correction by ITAM (kernels/shaping.h).

#include "scenes/detail/marginal.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "output/output.h"
#include "render/render.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {
namespace {

const auto kPositive = [](double v) { return v > 0.0; };

/// Parameter keys of each marginal type, in kernels::MarginalType order.
const std::vector<std::vector<std::string>> kTypeKeys = {
    {"a", "b"},         {"rate"}, {"mu", "scale"}, {"mu", "sigma"}, {"mu", "scale", "nu"},
    {"values", "image"}};

/// `cdf`: the impulse layer's own shot-noise law by default; a source layer's is Gaussian.
kernels::SourceCdf read_cdf(Reader& m, const LayerConfig& L) {
    const size_t fallback = static_cast<size_t>(L.source ? kernels::SourceCdf::Gaussian
                                                         : kernels::SourceCdf::ShotNoise);
    const auto cdf =
        static_cast<kernels::SourceCdf>(m.choice("cdf", kernels::kSourceCdfNames, fallback));
    if (L.source && cdf == kernels::SourceCdf::ShotNoise)
        m.fail(m.node("cdf"), "cdf",
               "\"shot_noise\" needs an impulse layer; a " + std::string(L.source->kind()) +
                   " layer's F_x is \"gaussian\" or \"empirical\"");
    return cdf;
}

/// The transfer at t = 0 (an empirical F_x is replaced by the Renderer's calibration): F_x the
/// unshaped layer's shot-noise law (its kernel's value law kept in L when the kernel is fixed),
/// or its closed-form mean and variance (Campbell's theorem). Throws ValueError.
std::shared_ptr<const kernels::MarginalTransform> build_transform(LayerConfig& L,
                                                                  const kernels::MarginalParams& P) {
    L.marginal.reset();
    L.kernel_values.reset();
    if (L.marginal_cdf == kernels::SourceCdf::ShotNoise) {
        if (L.kernel_keys.empty())
            L.kernel_values = std::make_shared<const kernels::KernelValueLaw>(
                kernels::kernel_value_law(kernels::Kernel(L.kernel)));
        return shot_noise_marginal(L, P, 0.0, L.kernel_values.get());
    }
    const Theory raw = layer_theory(L);
    return std::make_shared<const kernels::MarginalTransform>(P, raw.mean,
                                                              std::sqrt(raw.variance));
}

}  // namespace

namespace {

/// An empirical target's sample: values = [...] or the pixels of an image.
std::shared_ptr<std::vector<double>> read_empirical(Reader& m, const kernels::MarginalParams& P0,
                                                    const std::filesystem::path& base) {
    kernels::MarginalParams P = P0;
    const toml::node* vn = m.node("values");
    const toml::node* in = m.node("image");
    if ((vn != nullptr) == (in != nullptr))
        m.fail(vn ? vn : in, vn ? "values" : "image",
                "an empirical marginal needs exactly one of values = [numbers] or "
                "image = \"path\"");
    auto samples = std::make_shared<std::vector<double>>();
    if (vn) {
        const toml::array* a = vn->as_array();
        if (!a)
            m.fail(vn, "values", "expected an array of numbers, found " + type_name(*vn));
        for (const auto& e : *a) {
            if (!e.is_number())
                m.fail(&e, "values", "expected numbers, found " + type_name(e));
            samples->push_back(e.value<double>().value_or(0.0));
        }
    } else {
        const std::string rel = m.string("image", "");
        const std::filesystem::path p = resolve_path(in, rel, base);
        try {
            const render::Frame img = output::read_image(p.string());
            samples->assign(img.data.begin(), img.data.end());
        } catch (const Error& e) {
            m.fail(in, "image", std::string("cannot read: ") + e.what());
        }
    }
    P.samples = samples;
    try {
        kernels::validate(P);
    } catch (const ValueError& e) {
        m.fail(vn ? vn : in, vn ? "values" : "image", e.what());
    }
    return samples;
}

/// The target's parameters, keyframed unless `fixed_target` says why they cannot vary.
void read_target(Reader* m, LayerConfig& L, kernels::MarginalParams& P,
                 const std::string& fixed_target, const std::filesystem::path& base) {
    // A target parameter: keyframed (the Renderer rebuilds the transfer when it changes).
    using MP = kernels::MarginalParams;
    auto param = [&](const char* key, double MP::*member, double fallback,
                     const std::function<bool(double)>& ok, const char* expected) {
        const numeric::Keyframed v = m->keyframed(key, fallback, ok, expected);
        if (!v.is_constant() && !fixed_target.empty())
            m->fail(m->node(key), key, "cannot vary in time: " + fixed_target);
        P.*member = v.value(0.0);
        if (!v.is_constant()) L.marginal_keys.push_back({member, v});
    };
    switch (P.type) {
        case kernels::MarginalType::Uniform:
            param("a", &MP::a, 0.0, {}, "");
            param("b", &MP::b, 1.0, {}, "");
            break;
        case kernels::MarginalType::Exponential:
            param("rate", &MP::rate, 1.0, kPositive, "a rate > 0 (the mean is 1 / rate)");
            break;
        case kernels::MarginalType::Laplace:
            param("mu", &MP::mu, 0.0, {}, "");
            param("scale", &MP::scale, 1.0, kPositive, "a scale b > 0 in exp(-|y - mu| / b)");
            break;
        case kernels::MarginalType::Lognormal:
            param("mu", &MP::mu, 0.0, {}, "");
            param(
                "sigma", &MP::sigma, 1.0, [](double v) { return v > 0.0 && v <= 8.0; },
                "a standard deviation of log y in (0, 8]");
            break;
        case kernels::MarginalType::StudentT:
            param("mu", &MP::mu, 0.0, {}, "");
            param("scale", &MP::scale, 1.0, kPositive, "a scale > 0");
            param(
                "nu", &MP::nu, 4.0, [](double v) { return v > 2.0; },
                "degrees of freedom > 2 (a finite variance)");
            break;
        case kernels::MarginalType::Empirical:
            P.samples = read_empirical(*m, P, base);
            break;
    }
}

/// Keys of the other types are accepted with a warning, like the kernel's (read_kernel).
void warn_other_type_keys(Reader& m, kernels::MarginalType type) {
    const std::string type_str(kernels::to_string(type));
    for (size_t t = 0; t < kTypeKeys.size(); ++t)
        for (const auto& key : kTypeKeys[t]) {
            const auto& own = kTypeKeys[static_cast<size_t>(type)];
            if (std::find(own.begin(), own.end(), key) == own.end() && m.has(key))
                m.warn(key, "ignored for marginal type " + type_str);
        }
}

/// A uniform target: b > a at every time.
void check_uniform(Reader& m, const LayerConfig& L, const kernels::MarginalParams& P) {
    using MP = kernels::MarginalParams;
    // b > a at every time.
    std::vector<const numeric::Keyframed*> ks;
    for (const auto& k : L.marginal_keys) ks.push_back(&k.value);
    for (double t : key_check_times(ks)) {
        double a = P.a, b = P.b;
        for (const auto& k : L.marginal_keys) (k.field == &MP::a ? a : b) = k.value.value(t);
        if (!(b > a)) {
            std::ostringstream s;
            s << "expected b > a = " << a;
            if (!L.marginal_keys.empty()) s << " (at t = " << t << " s)";
            m.fail(m.node(m.has("b") ? "b" : "a"), m.has("b") ? "b" : "a", s.str());
        }
    }
}

/// Keys the shaping overrides, or that a transfer built once cannot follow.
void check_layer_keys(Reader& r, const LayerConfig& L, bool precorrect) {
    if (!L.mean.is_constant())
        r.fail(r.node("mean"), "mean",
               "cannot vary in time on a layer with a marginal: the target distribution sets its "
               "mean");
    if (!L.gain.is_constant())
        r.fail(r.node("gain"), "gain",
               "cannot vary in time on a layer with a marginal: the target distribution sets the "
               "scale (only the sign of gain matters)");
    if (L.marginal_cdf == kernels::SourceCdf::Empirical && !L.density.is_constant())
        r.fail(r.node("density"), "density",
               "cannot vary in time with marginal cdf = \"empirical\": F_x is measured once, on "
               "a render at frame 0");
    if ((L.marginal_cdf == kernels::SourceCdf::Empirical || precorrect) && !L.kernel_keys.empty())
        r.fail(r.node("kernel"), "kernel",
               std::string("cannot vary in time with ") +
                   (precorrect ? "marginal precorrect = true: the kernel is replaced once by the "
                                 "corrected one"
                               : "marginal cdf = \"empirical\": F_x is measured once, on a render "
                                 "at frame 0"));
    if (L.mean.value(0.0) != 0.0)
        r.warn("mean",
               "no effect on a layer with a marginal: the target distribution sets its mean");
    if (std::abs(L.gain.value(0.0)) != 1.0)
        r.warn("gain",
               "only its sign matters on a layer with a marginal: the target distribution "
               "sets the scale");
}

/// precorrect = true: the kernel replaced by the ITAM-corrected one (Lewis 1986 §4.1), and the
/// transfer rebuilt for it.
void apply_precorrection(Reader& m, LayerConfig& L, const kernels::MarginalParams& P) {
    if (L.source)
        m.fail(m.node("precorrect"), "precorrect",
                "needs an impulse layer's kernel to correct; a " + std::string(L.source->kind()) +
                    " layer's spectrum is its synthesizer's");
    try {
        const kernels::Precorrection pc =
            kernels::precorrect_spectrum(kernels::Kernel(L.kernel), *L.marginal);
        // The density keeps referring to the original kernel: process.intensity and cell_size are
        // left as prepare_layer set them (the corrected kernel is wider, with the same int h^2).
        L.kernel = pc.kernel;
        L.precorrection = std::make_shared<const kernels::PrecorrectionReport>(pc.report);
        L.marginal = build_transform(L, P);
        if (!pc.report.converged) m.warn("precorrect", pc.report.message);
    } catch (const ValueError& e) {
        m.fail(m.node("precorrect"), "precorrect", e.what());
    }
}

}  // namespace

void read_marginal(Reader& r, LayerConfig& L, const std::filesystem::path& base) {
    auto m = r.table("marginal");
    if (!m) return;
    std::string names;
    for (auto n : kernels::kMarginalTypeNames)
        names += (names.empty() ? "" : ", ") + std::string(n);
    if (!m->has("type")) m->fail(nullptr, "type", "a marginal needs a type: one of " + names);
    kernels::MarginalParams P;
    P.type = static_cast<kernels::MarginalType>(m->choice("type", kernels::kMarginalTypeNames, 0));
    // Read first: they decide whether the target may vary in time.
    const bool precorrect = m->boolean("precorrect", false);
    L.marginal_cdf = read_cdf(*m, L);
    const std::string fixed_target =
        precorrect ? "the kernel is pre-corrected once for the target (precorrect = true)"
        : L.marginal_cdf == kernels::SourceCdf::Empirical
            ? "the transfer is built once from the calibration render (cdf = \"empirical\")"
            : "";
    read_target(&*m, L, P, fixed_target, base);
    warn_other_type_keys(*m, P.type);
    if (P.type == kernels::MarginalType::Uniform) check_uniform(*m, L, P);
    m->finish();
    check_layer_keys(r, L, precorrect);
    try {
        L.marginal = build_transform(L, P);
    } catch (const ValueError& e) {
        m->fail(m->node("type"), "type", e.what());
    }
    if (precorrect) apply_precorrection(*m, L, P);
}

namespace {

kernels::AmplitudeLaw amplitude_law(sim::Amplitude a) {
    switch (a) {
        case sim::Amplitude::Uniform: return kernels::AmplitudeLaw::Uniform;
        case sim::Amplitude::Sign: return kernels::AmplitudeLaw::Sign;
        case sim::Amplitude::Normal: break;
        case sim::Amplitude::Exponential: break;  // refused with a marginal by the loader
    }
    return kernels::AmplitudeLaw::Normal;
}

/// The impulse weights' multipliers at layer time t: gain x carrier weight, times the envelope
/// w(a) at 256 ages a (midpoints) with the rate of births at t - a (thinned by density_scale,
/// loop-reduced as birth_weight does) for an animated layer.
std::vector<kernels::WeightNode> weight_nodes(const LayerConfig& L, double t) {
    const auto& p = L.process;
    const double g = L.gain.value(t) * L.carrier_weight(t);
    if (!(p.lifetime_s > 0)) return {{g, 1.0}};
    constexpr int kAges = 256;  // midpoints: exact for hann's E[w^2], E[w^4] (periodic, smooth)
    const double T = p.lifetime_s;
    std::vector<kernels::WeightNode> nodes;
    for (int i = 0; i < kAges; ++i) {
        const double a = (i + 0.5) * T / kAges;
        double tb = t - a;
        if (p.loop_s > 0) tb -= std::floor(tb / p.loop_s) * p.loop_s;
        const double s = p.density_scale ? p.density_scale(tb) : 1.0;
        nodes.push_back({g * sim::envelope_weight(p.envelope, a, T), s / kAges});
    }
    return nodes;
}

}  // namespace

std::shared_ptr<const kernels::MarginalTransform> shot_noise_marginal(
    const LayerConfig& layer, const kernels::MarginalParams& target, double t_s,
    const kernels::KernelValueLaw* values) {
    kernels::KernelValueLaw own;
    if (!values) {
        own = kernels::kernel_value_law(kernels::Kernel(layer.kernel_at(t_s)));
        values = &own;
    }
    auto cdf = std::make_shared<const kernels::ShotNoiseCdf>(
        layer.process.intensity, *values, amplitude_law(layer.process.amplitude),
        weight_nodes(layer, t_s));
    return std::make_shared<const kernels::MarginalTransform>(target, layer.mean.value(t_s),
                                                              std::move(cdf));
}

namespace {

/// F_x of a source layer measured on 1024^2 samples spaced an eighth of its correlation length.
std::shared_ptr<const kernels::MarginalTransform> calibrate_source_marginal(
    const LayerConfig& layer) {
    render::View view;
    view.width = view.height = 1024;
    view.scale = layer.source->correlation_length() / 8.0;
    render::Frame f;
    f.resize(view.width, view.height);
    layer.source->add(view, 0.0, f);
    const double gain = layer.gain.value(0.0), mean = layer.mean.value(0.0);
    for (auto& v : f.data) v = static_cast<float>(mean + gain * v);
    return std::make_shared<const kernels::MarginalTransform>(layer.marginal->target().params(),
                                                              f.data);
}

}  // namespace

std::shared_ptr<const kernels::MarginalTransform> calibrate_marginal(const LayerConfig& layer,
                                                                     const sim::Timing& timing) {
    // Empirical F_x refuses keyframed density, gain, mean and kernel: the constants hold.
    if (layer.source) return calibrate_source_marginal(layer);
    const double R = layer.kernel.radius;
    const double side = std::min(256.0 * R, std::sqrt(2e6 / layer.process.intensity));
    render::View view;
    view.width = view.height = 1024;
    view.scale = side / view.width;
    sim::LayerSimulator sim(layer.process, layer.flow, timing, R);
    sim::Impulses imp;
    sim.impulses_at(0, view.box(), imp);
    const double gain = layer.gain.value(0.0), mean = layer.mean.value(0.0);
    if (gain != 1.0)
        for (auto& w : imp.weight) w = static_cast<float>(w * gain);
    render::Frame f;
    f.resize(view.width, view.height);
    render::accumulate(kernels::Kernel(layer.kernel), imp, view, f);
    if (mean != 0.0)
        for (auto& v : f.data) v = static_cast<float>(v + mean);
    return std::make_shared<const kernels::MarginalTransform>(layer.marginal->target().params(),
                                                              f.data);
}

}  // namespace impulse::scenes::detail
