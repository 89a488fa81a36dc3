// SPDX-License-Identifier: Apache-2.0
// The `marginal` key of a [[layer]] (docs/scenes.md): distribution shaping (Lewis 1986 §4) and
// the spectrum pre-correction by ITAM (kernels/shaping.h).

#include "scenes/marginal.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "render/render.h"
#include "util/errors.h"

namespace impulse::scenes::detail {
namespace {

const auto kPositive = [](double v) { return v > 0.0; };

/// Parameter keys of each marginal type, in kernels::MarginalType order.
const std::vector<std::vector<std::string>> kTypeKeys = {
    {"a", "b"},         {"rate"}, {"mu", "scale"}, {"mu", "sigma"}, {"mu", "scale", "nu"},
    {"values", "image"}};

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
    const std::string type_str(kernels::to_string(P.type));
    switch (P.type) {
        case kernels::MarginalType::Uniform:
            P.a = m->number("a", 0.0);
            P.b = m->number("b", 1.0);
            if (!(P.b > P.a)) {
                std::ostringstream s;
                s << "expected b > a = " << P.a;
                m->fail(m->node(m->has("b") ? "b" : "a"), m->has("b") ? "b" : "a", s.str());
            }
            break;
        case kernels::MarginalType::Exponential:
            P.rate = m->number("rate", 1.0, kPositive, "a rate > 0 (the mean is 1 / rate)");
            break;
        case kernels::MarginalType::Laplace:
            P.mu = m->number("mu", 0.0);
            P.scale = m->number("scale", 1.0, kPositive, "a scale b > 0 in exp(-|y - mu| / b)");
            break;
        case kernels::MarginalType::Lognormal:
            P.mu = m->number("mu", 0.0);
            P.sigma = m->number(
                "sigma", 1.0, [](double v) { return v > 0.0 && v <= 8.0; },
                "a standard deviation of log y in (0, 8]");
            break;
        case kernels::MarginalType::StudentT:
            P.mu = m->number("mu", 0.0);
            P.scale = m->number("scale", 1.0, kPositive, "a scale > 0");
            P.nu = m->number(
                "nu", 4.0, [](double v) { return v > 2.0; },
                "degrees of freedom > 2 (a finite variance)");
            break;
        case kernels::MarginalType::Empirical: {
            const toml::node* vn = m->node("values");
            const toml::node* in = m->node("image");
            if ((vn != nullptr) == (in != nullptr))
                m->fail(vn ? vn : in, vn ? "values" : "image",
                        "an empirical marginal needs exactly one of values = [numbers] or "
                        "image = \"path\"");
            auto samples = std::make_shared<std::vector<double>>();
            if (vn) {
                const toml::array* a = vn->as_array();
                if (!a)
                    m->fail(vn, "values", "expected an array of numbers, found " + type_name(*vn));
                for (const auto& e : *a) {
                    if (!e.is_number())
                        m->fail(&e, "values", "expected numbers, found " + type_name(e));
                    samples->push_back(e.value<double>().value_or(0.0));
                }
            } else {
                const std::string rel = m->string("image", "");
                const std::filesystem::path p = std::filesystem::path(rel).is_absolute()
                                                    ? std::filesystem::path(rel)
                                                    : base / rel;
                try {
                    const render::Frame img = render::read_image(p.string());
                    samples->assign(img.data.begin(), img.data.end());
                } catch (const Error& e) {
                    m->fail(in, "image", std::string("cannot read: ") + e.what());
                }
            }
            P.samples = samples;
            try {
                kernels::validate(P);
            } catch (const ValueError& e) {
                m->fail(vn ? vn : in, vn ? "values" : "image", e.what());
            }
            break;
        }
    }
    // Keys of the other types are accepted with a warning, like the kernel's (read_kernel).
    for (size_t t = 0; t < kTypeKeys.size(); ++t)
        for (const auto& key : kTypeKeys[t]) {
            const auto& own = kTypeKeys[static_cast<size_t>(P.type)];
            if (std::find(own.begin(), own.end(), key) == own.end() && m->has(key))
                m->warn(key, "ignored for marginal type " + type_str);
        }
    const bool precorrect = m->boolean("precorrect", false);
    L.marginal_cdf = static_cast<kernels::SourceCdf>(m->choice("cdf", kernels::kSourceCdfNames, 0));
    m->finish();
    if (L.mean != 0.0)
        r.warn("mean",
               "no effect on a layer with a marginal: the target distribution sets its mean");
    if (std::abs(L.gain) != 1.0)
        r.warn("gain",
               "only its sign matters on a layer with a marginal: the target distribution "
               "sets the scale");

    // F_x: the unshaped layer's closed-form mean and variance (Campbell's theorem).
    auto build = [&]() {
        L.marginal.reset();
        const Theory raw = layer_theory(L);
        return std::make_shared<const kernels::MarginalTransform>(P, raw.mean,
                                                                  std::sqrt(raw.variance));
    };
    try {
        L.marginal = build();
    } catch (const ValueError& e) {
        m->fail(m->node("type"), "type", e.what());
    }
    if (!precorrect) return;
    try {
        const kernels::Precorrection pc =
            kernels::precorrect_spectrum(kernels::Kernel(L.kernel), *L.marginal);
        // The density keeps referring to the original kernel: process.intensity and cell_size are
        // left as prepare_layer set them (the corrected kernel is wider, with the same int h^2).
        L.kernel = pc.kernel;
        L.precorrection = std::make_shared<const kernels::PrecorrectionReport>(pc.report);
        L.marginal = build();
        if (!pc.report.converged) m->warn("precorrect", pc.report.message);
    } catch (const ValueError& e) {
        m->fail(m->node("precorrect"), "precorrect", e.what());
    }
}

std::shared_ptr<const kernels::MarginalTransform> calibrate_marginal(const LayerConfig& layer,
                                                                     const sim::Timing& timing) {
    const double R = layer.kernel.radius;
    const double side = std::min(256.0 * R, std::sqrt(2e6 / layer.process.intensity));
    render::View view;
    view.width = view.height = 1024;
    view.scale = side / view.width;
    sim::LayerSimulator sim(layer.process, layer.flow, timing, R);
    sim::Impulses imp;
    sim.impulses_at(0, view.box(), imp);
    if (layer.gain != 1.0)
        for (auto& w : imp.weight) w = static_cast<float>(w * layer.gain);
    render::Frame f;
    f.resize(view.width, view.height);
    render::accumulate(kernels::Kernel(layer.kernel), imp, view, f);
    if (layer.mean != 0.0)
        for (auto& v : f.data) v = static_cast<float>(v + layer.mean);
    return std::make_shared<const kernels::MarginalTransform>(layer.marginal->target().params(),
                                                              f.data);
}

}  // namespace impulse::scenes::detail
