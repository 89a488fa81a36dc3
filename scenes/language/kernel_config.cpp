// SPDX-License-Identifier: Apache-2.0
// [layer.kernel]: the analytic kernels and those designed from a spectrum, an autocorrelation or
// an exemplar image (docs/scenes.md "[layer.kernel]", "Designed kernels").

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>

#include "output/output.h"
#include "scenes/detail/loader.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {

namespace fs = std::filesystem;

namespace {

/// Kernel types of scene files: the analytic ones (kernels::kKernelTypeNames, in enum order),
/// then the designed ones (docs/scenes.md "Designed kernels").
const std::array<std::string_view, 6> kSceneKernelTypes = {
    "cosine", "gaussian", "gabor", "spectrum", "autocorrelation", "exemplar"};

/// The parameters of `model` (source == "model"): the ones the model uses, warning about the
/// others (also without a model).
kernels::ModelParams read_model_params(Reader& r, bool acf, const std::string& source,
                                       const toml::node* sn) {
    namespace K = kernels;
    // Model parameters: read the ones the model uses, warn about the others.
    const std::array<const char*, 11> model_keys = {"variance", "length", "exponent", "nu",
                                                    "k0",       "f0",     "width",    "slope",
                                                    "k_low",    "k_high", "omega"};
    K::ModelParams mp;
    std::vector<const char*> used;
    if (source == "model") {
        const std::string name = r.string("model", "");
        const auto m = K::spectral_model_from_string(name);
        if (!m) {
            std::string list;
            for (auto n : K::kSpectralModelNames)
                list += (list.empty() ? "" : ", ") + std::string(n);
            r.fail(sn, "model", "expected one of " + list + " (exponential = markov)");
        }
        if (acf && !K::defined_by_autocorrelation(*m))
            r.fail(sn, "model",
                   "defined by its spectrum: expected one of markov, gaussian, markaussian, "
                   "matern, oscillatory_markov, oscillatory_gaussian for an autocorrelation "
                   "kernel (or use type = \"spectrum\")");
        mp.model = *m;
        used.push_back("variance");
        switch (mp.model) {
            case K::SpectralModel::Markov:
            case K::SpectralModel::Gaussian:
                used.push_back("length");
                break;
            case K::SpectralModel::Markaussian:
                used.insert(used.end(), {"length", "exponent"});
                break;
            case K::SpectralModel::Matern:
                used.insert(used.end(), {"length", "nu"});
                break;
            case K::SpectralModel::OscillatoryMarkov:
            case K::SpectralModel::OscillatoryGaussian:
                used.insert(used.end(), {"length", "omega"});
                break;
            case K::SpectralModel::Lorentzian:
                used.push_back("k0");
                break;
            case K::SpectralModel::Bandpass:
                used.insert(used.end(), {"f0", "width"});
                break;
            case K::SpectralModel::Power:
                used.insert(used.end(), {"slope", "k_low", "k_high"});
                break;
        }
        auto uses = [&](std::string_view key) {
            return std::find(used.begin(), used.end(), key) != used.end();
        };
        if (uses("variance"))
            mp.variance = r.number("variance", mp.variance, kPositive, "a variance > 0 (R(0))");
        if (uses("length"))
            mp.length = r.number("length", mp.length, kPositive,
                                 "a correlation length > 0 (texture units)");
        if (uses("exponent"))
            mp.exponent = r.number(
                "exponent", mp.exponent, [](double v) { return v > 0 && v <= 2; },
                "an exponent in (0, 2] (exp(-(r/l)^a) is an autocorrelation only there)");
        if (uses("nu"))
            mp.nu = r.number(
                "nu", mp.nu, [](double v) { return v > 0 && v <= 50; },
                "a smoothness in (0, 50]");
        if (uses("omega"))
            mp.omega = r.number("omega", mp.omega, kNonNegative,
                                "an angular frequency >= 0 (radians per unit)");
        if (uses("k0"))
            mp.k0 =
                r.number("k0", mp.k0, kPositive, "a corner frequency > 0 (cycles per unit)");
        if (uses("f0"))
            mp.f0 = r.number("f0", mp.f0, kNonNegative,
                             "a centre frequency >= 0 (cycles per unit)");
        if (uses("width"))
            mp.width =
                r.number("width", mp.width, kPositive, "a ring width > 0 (cycles per unit)");
        if (uses("slope"))
            mp.slope = r.number("slope", mp.slope, kPositive, "a slope > 0 (S ~ k^-slope)");
        if (uses("k_low"))
            mp.k_low =
                r.number("k_low", mp.k_low, kPositive, "a low cut-off > 0 (cycles per unit)");
        if (uses("k_high"))
            mp.k_high =
                r.number("k_high", mp.k_high, kNonNegative, "a high cut-off >= 0 (0: none)");
        try {
            K::validate(mp);
        } catch (const ValueError& e) {  // a combination (power: slope <= 2 without k_high)
            r.fail(r.node("slope"), "slope", e.what());
        }
    }
    for (const char* g : model_keys)
        if (std::find(used.begin(), used.end(), std::string_view(g)) == used.end() && r.has(g))
            r.warn(g, source == "model" ? "ignored for model " + r.string("model", "")
                                        : std::string("ignored without a model"));
    return mp;
}

}  // namespace

/// The design keys of a `spectrum` or `autocorrelation` kernel in table `r` (energy, nyquist,
/// rolloff, max_radius; one of model, expression, table and the model's parameters) and the
/// design in o.dims dimensions; o.radius and o.window are the caller's (radius read from `r`).
/// Library errors are reported at the key whose value caused them.
kernels::DesignedKernel read_design(Reader& r, bool acf, const fs::path& base,
                                    kernels::DesignOptions o) {
    namespace K = kernels;
    auto detail_of = [](const std::exception& e, const std::string& quoted) {
        // Drop a repeated 'expression "...": ' or 'expression "..." ' (the key shows the value).
        const std::string m = e.what();
        if (quoted.empty() || m.rfind(quoted, 0) != 0) return m;
        size_t i = quoted.size();
        if (m.compare(i, 2, ": ") == 0)
            i += 2;
        else if (m.compare(i, 1, " ") == 0)
            i += 1;
        return m.substr(i);
    };
    auto path_of = [&](const toml::node* n, const std::string& rel) {
        return detail::resolve_path(n, rel, base);
    };
    const toml::node* radius_node = r.node("radius");
    const double radius = o.radius;
    const toml::node* energy_node = r.node("energy");
    o.energy = r.number(
        "energy", o.energy, [](double v) { return v > 0 && v < 1; },
        "a fraction in (0, 1) of the kernel energy to keep, e.g. 0.99");
    if (energy_node && radius_node)
        r.fail(energy_node, "energy",
               "give energy or radius, not both (radius fixes the size)");
    o.nyquist = r.number("nyquist", o.nyquist, kPositive,
                         "a frequency > 0 (cycles per unit; 0.5 = pixel Nyquist at zoom 1)");
    o.rolloff = r.number(
        "rolloff", o.rolloff, [](double v) { return v >= 0 && v <= 0.9; },
        "a fraction in [0, 0.9] of nyquist");
    o.max_radius =
        r.number("max_radius", o.max_radius, kPositive, "a radius > 0 (texture units)");
    if (radius > o.max_radius)
        r.fail(radius_node, "radius",
               "expected <= max_radius = " + std::to_string(o.max_radius));

    // Exactly one source.
    std::vector<std::string> given;
    for (const char* g : {"model", "expression", "table"})
        if (r.has(g)) given.push_back(g);
    if (given.size() > 1)
        r.fail(r.node(given[1]), given[1],
               "give one of model, expression" + std::string(acf ? "" : ", table") +
                   ", not both " + given[0] + " and " + given[1]);
    if (given.empty())
        r.fail(nullptr, "model",
               acf ? "missing: a kernel of type autocorrelation needs model = "
                     "\"markov\" (or ...) or expression = \"...\" of r"
                   : "missing: a kernel of type spectrum needs model = \"markov\" "
                     "(or ...), expression = \"...\" of k and theta, or table = "
                     "\"path.csv\"");
    const std::string source = given[0];
    const toml::node* sn = r.node(source);

    const K::ModelParams mp = read_model_params(r, acf, source, sn);
    if (acf && source == "table")
        r.fail(sn, "table",
               "a table gives a spectrum: use type = \"spectrum\" (or an expression of r)");

    K::DesignedKernel d;
    try {
        if (acf) {
            const K::Autocorrelation a =
                source == "model" ? K::model_autocorrelation(mp)
                                  : K::expression_autocorrelation(r.string("expression", ""));
            d = K::kernel_from_autocorrelation(a, o);
        } else {
            K::Spectrum sp;
            if (source == "model")
                sp = K::model_spectrum(mp, o.nyquist, o.dims);
            else if (source == "expression")
                sp = K::expression_spectrum(r.string("expression", ""));
            else
                sp = K::table_spectrum(path_of(sn, r.string("table", "")).string());
            d = K::kernel_from_spectrum(sp, o);
        }
    } catch (const Error& e) {
        const std::string prefix =
            source == "expression" ? "expression \"" + r.string("expression", "") + "\"" : "";
        if (dynamic_cast<const BudgetError*>(&e))
            r.fail(sn, source,
                   detail_of(e, prefix) +
                       " (limits.max_memory_mib; lower nyquist or energy, or raise the limit)");
        // Radius problems belong to the radius or energy key when one was given.
        const std::string what = e.what();
        if (what.find("radius") != std::string::npos && (radius_node || energy_node))
            r.fail(radius_node ? radius_node : energy_node, radius_node ? "radius" : "energy",
                   detail_of(e, prefix));
        r.fail(sn, source, detail_of(e, prefix));
    }
    return d;
}

namespace {

/// A designed kernel: `spectrum`, `autocorrelation` or `exemplar` (kernels/spectral.h). Library
/// errors (ValueError, IoError) are reported at the key whose value caused them.
kernels::KernelParams read_designed_kernel(Reader& r, std::string_view type, Reader& layer,
                                           const fs::path& base, std::vector<KernelKey>& keys,
                                           double max_memory_mib) {
    namespace K = kernels;
    const std::string tname(type);
    auto path_of = [&](const toml::node* n, const std::string& rel) {
        return detail::resolve_path(n, rel, base);
    };
    r.set_structural_reason(
        "a designed kernel is computed once, when the scene loads (up to a second per design); "
        "orientation and aspect can vary");
    const auto window = static_cast<K::DesignWindow>(r.choice("window", K::kDesignWindowNames, 1));
    const toml::node* radius_node = r.node("radius");
    const double radius = r.number("radius", 0.0, kPositive, "a radius > 0 (texture units)");
    const numeric::Keyframed orientation = r.keyframed("orientation", 0.0);
    const numeric::Keyframed aspect = r.keyframed(
        "aspect", 1.0, [](double v) { return v >= 1.0; }, "a ratio >= 1");
    // The design is normalised at the largest density over time (docs/scenes.md "Keyframes").
    auto layer_density = [&] {
        return layer
            .keyframed("density", 16.0, kPositive, "a density > 0 (impulses per kernel area)")
            .max();
    };
    for (const char* g : {"sigma", "frequency", "bandwidth", "phase"})
        if (r.has(g)) r.warn(g, "ignored for kernel type " + tname);

    K::KernelParams k;
    if (type == "exemplar") {
        const toml::node* pn = r.node("path");
        const std::string rel = r.string("path", "");
        if (rel.empty())
            r.fail(pn, "path",
                   "expected the path of an exemplar image (relative to the scene file)");
        for (const char* g :
             {"energy", "nyquist", "rolloff", "max_radius", "model", "expression", "table"})
            if (r.has(g)) r.warn(g, "ignored for kernel type exemplar");
        K::ExemplarOptions o;
        o.radius = radius;
        o.window = window;
        // Normalised at this layer's density and amplitude distribution (read here as well as
        // in read_scene: same values, same messages).
        o.density = layer_density();
        o.amplitude_second_moment = sim::amplitude_second_moment(
            static_cast<sim::Amplitude>(layer.choice("amplitude", sim::kAmplitudeNames, 0)));
        render::Frame image;
        try {
            image = output::read_image(path_of(pn, rel).string());
        } catch (const Error& e) {
            r.fail(pn, "path", e.what());
        }
        try {
            k = K::kernel_from_exemplar(image.data.data(), image.width, image.height, o).params;
        } catch (const ValueError& e) {
            if (radius_node) r.fail(radius_node, "radius", e.what());
            r.fail(pn, "path", e.what());
        }
    } else {
        K::DesignOptions o;
        o.window = window;
        o.radius = radius;
        o.max_bytes = max_memory_mib * 1024.0 * 1024.0;
        K::DesignedKernel d = read_design(r, type == "autocorrelation", base, o);
        // Scale so the layer's spectrum is S itself: lambda E[a^2] |H|^2 = S with this layer's
        // lambda = density / (pi R^2) (the aspect squeeze changes lambda and int h^2 by inverse
        // factors, so the variance stays int S d^2k = R(0)).
        const double density = layer_density();
        const auto amp =
            static_cast<sim::Amplitude>(layer.choice("amplitude", sim::kAmplitudeNames, 0));
        const double ea2 = sim::amplitude_second_moment(amp),
                     ea4 = sim::amplitude_fourth_moment(amp);
        const double lambda = density / (std::numbers::pi * d.params.radius * d.params.radius);
        {
            auto scaled = std::make_shared<K::SampledKernel>(*d.params.sampled);
            for (double& v : scaled->values) v /= std::sqrt(lambda * ea2);
            d.params.sampled = scaled;
        }
        // A peaked kernel needs more impulses to look Gaussian (Campbell: the fourth cumulant).
        const double kurtosis = ea4 / (ea2 * ea2) / (lambda * d.report.effective_area);
        if (kurtosis > 1.0) {
            std::ostringstream s;
            s << std::setprecision(3) << "the designed kernel is peaked (its energy spreads over "
              << std::lround(d.report.effective_area) << " units^2 of its "
              << std::lround(std::numbers::pi * d.params.radius * d.params.radius)
              << "): at density " << density << " the field's excess kurtosis is " << kurtosis
              << " and it looks speckled; density >= " << std::ceil(density * kurtosis / 0.3)
              << " brings it to 0.3";
            layer.warn("density", s.str());
        }
        if (d.report.passband_error > 0.2) {
            std::ostringstream s;
            s << std::setprecision(3) << "the designed kernel (radius " << d.report.radius << ", "
              << 100 * d.report.energy_fraction
              << " % of the energy) misses the target spectrum by up to "
              << std::lround(100 * d.report.passband_error)
              << " % in the pass band; a larger energy (e.g. 0.999) or radius costs no time per "
                 "pixel";
            r.warn(radius_node ? "radius" : "energy", s.str());
        }
        k = d.params;
    }
    k.orientation = orientation.value(0.0);
    k.aspect = aspect.value(0.0);
    if (!orientation.is_constant()) keys.push_back({&K::KernelParams::orientation, orientation});
    if (!aspect.is_constant()) keys.push_back({&K::KernelParams::aspect, aspect});
    r.finish();
    return k;
}

/// A Gaussian's radius cuts it with a step exp(-R^2 / (2 sigma^2)) of its peak, which is not
/// band-limited (docs/multirate.md §4): an unset radius follows sigma to a step of 1e-3
/// (R = sqrt(2 ln 1000) sigma, the largest sigma when it is keyed); a given one leaving a step
/// above exp(-9/2) = 1.1 % (R < 3 sigma, the common cut, which the scenes and tests use) is
/// warned about.
void gaussian_radius(Reader& r, const std::vector<KernelKey>& keys, kernels::KernelParams& k) {
    constexpr double kFollow = 3.7169221888498383;  // sqrt(2 ln 1000)
    double sigma = k.sigma;
    bool radius_keyed = false;
    for (const auto& key : keys) {
        if (key.field == &kernels::KernelParams::sigma) sigma = key.value.max();
        radius_keyed = radius_keyed || key.field == &kernels::KernelParams::radius;
    }
    if (!r.has("radius")) {
        k.radius = kFollow * sigma;
        return;
    }
    const double step = std::exp(-0.5 * (k.radius / sigma) * (k.radius / sigma));
    if (!radius_keyed && k.radius < 3.0 * sigma * (1.0 - 1e-9)) {
        std::ostringstream s;
        s << std::setprecision(3) << "cuts the Gaussian (sigma = " << sigma << ") with a step of "
          << 100.0 * step  << " % of its peak, which is not band-limited (aliasing, and the "
          << "lattice rule keeps it at every pixel); radius >= " << 3.0 * sigma
          << " keeps the step at 1.1 %, or leave radius unset (" << kFollow * sigma
          << ": a step of 1e-3)";
        r.warn("radius", s.str());
    }
}

}  // namespace

/// The [layer.kernel] table; keyframed fields go to `keys` (their values at t = 0 into the
/// result). `pyramid`: the camera anti-aliases through a kernel pyramid, built once per layer,
/// so only the orientation (a rotation of every impulse) may vary in time. A design's working
/// memory is held to `max_memory_mib` (limits.max_memory_mib).
kernels::KernelParams read_kernel(std::optional<Reader> r, Reader& layer, const fs::path& base,
                                  std::vector<KernelKey>& keys, bool pyramid,
                                  double max_memory_mib) {
    namespace K = kernels;
    K::KernelParams k;
    if (!r) return k;
    const size_t type = r->choice("type", kSceneKernelTypes, 0);
    auto field = [&](const char* key, double K::KernelParams::*member, double fallback,
                     const std::function<bool(double)>& ok, const char* expected) {
        const numeric::Keyframed v = r->keyframed(key, fallback, ok, expected);
        k.*member = v.value(0.0);
        if (!v.is_constant()) keys.push_back({member, v});
    };
    if (type >= K::kKernelTypeNames.size()) {
        k = read_designed_kernel(*r, kSceneKernelTypes[type], layer, base, keys, max_memory_mib);
    } else {
        k.type = static_cast<K::KernelType>(type);
        field("radius", &K::KernelParams::radius, k.radius, kPositive,
              "a radius > 0 (texture units)");
        field("sigma", &K::KernelParams::sigma, k.sigma, kPositive, "a standard deviation > 0");
        field("frequency", &K::KernelParams::frequency, k.frequency, kNonNegative,
              "a frequency >= 0 (cycles per unit)");
        field("bandwidth", &K::KernelParams::bandwidth, k.bandwidth, kNonNegative,
              "a bandwidth >= 0 (0: from radius)");
        field("phase", &K::KernelParams::phase, k.phase, {}, "");
        field("orientation", &K::KernelParams::orientation, k.orientation, {}, "");
        field("aspect", &K::KernelParams::aspect, k.aspect, [](double v) { return v >= 1.0; },
              "a ratio >= 1");
        if (k.type == K::KernelType::Gaussian) gaussian_radius(*r, keys, k);
        if (k.type != K::KernelType::Gaussian && r->has("sigma"))
            r->warn("sigma", "ignored for kernel type " + std::string(K::to_string(k.type)));
        if (k.type != K::KernelType::Gabor)
            for (const char* g : {"frequency", "bandwidth", "phase"})
                if (r->has(g))
                    r->warn(g, "ignored for kernel type " + std::string(K::to_string(k.type)));
        r->finish();
    }
    auto name_of = [](double K::KernelParams::*member) -> const char* {
        using P = K::KernelParams;
        const std::pair<double P::*, const char*> names[] = {
            {&P::radius, "radius"}, {&P::sigma, "sigma"},       {&P::frequency, "frequency"},
            {&P::bandwidth, "bandwidth"}, {&P::phase, "phase"}, {&P::orientation, "orientation"},
            {&P::aspect, "aspect"}};
        for (const auto& [m, n] : names)
            if (m == member) return n;
        return "kernel";
    };
    for (const auto& key : keys)
        if (pyramid && key.field != &K::KernelParams::orientation)
            r->fail(r->node(name_of(key.field)), name_of(key.field),
                    "cannot vary in time with anti-aliasing (a perspective camera, or "
                    "camera.antialias): the kernel pyramid is built once per layer (0.2 to 0.3 s); "
                    "keyframe orientation, or set camera.antialias = \"off\" on an orthographic "
                    "camera");
    // Combinations the per-key checks cannot see (radius / sigma, cycles across the radius) must
    // hold at every time.
    if (!keys.empty()) {
        std::vector<const numeric::Keyframed*> ks;
        for (const auto& key : keys) ks.push_back(&key.value);
        LayerConfig probe;
        probe.kernel = k;
        probe.kernel_keys = keys;
        for (double t : key_check_times(ks)) {
            try {
                K::validate(probe.kernel_at(t));
            } catch (const ValueError& e) {
                // The message starts with the field it blames ("sigma = 0.01: ...").
                const std::string what = e.what();
                const std::string blamed = what.substr(0, what.find(' '));
                const char* at = r->has(blamed) ? blamed.c_str() : name_of(keys.front().field);
                r->fail(r->node(at), at, "at t = " + num(t) + " s: " + what);
            }
        }
    }
    return k;
}

}  // namespace impulse::scenes::detail
