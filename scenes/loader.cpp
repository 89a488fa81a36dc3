// SPDX-License-Identifier: Apache-2.0
// Scene files -> typed configuration (schema: docs/scenes.md).

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <optional>
#include <sstream>

#include "output/image_input.h"
#include "scenes/camera_detail.h"
#include "scenes/compose_detail.h"
#include "scenes/marginal.h"
#include "scenes/reader.h"
#include "scenes/source_detail.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace impulse::scenes {
namespace {

/// Below this many impulses overlapping where the kernel has its energy (scenes::layer_moments,
/// docs/scenes.md "Density, overlap and kurtosis") the field is lumpy: excess kurtosis above 6
/// with normal amplitudes.
constexpr double kMinEffectiveImpulses = 0.5;

void warn_overlap(detail::Reader& r, const LayerConfig& L) {
    const LayerMoments m = layer_moments(L);
    if (!(m.effective_impulses < kMinEffectiveImpulses)) return;
    std::ostringstream s;
    s << std::setprecision(3) << "only " << m.effective_impulses
      << " impulses overlap where the kernel has its energy (excess kurtosis "
      << m.excess_kurtosis << "): lumpy noise; density >= "
      << std::ceil(L.density.min() * kMinEffectiveImpulses / m.effective_impulses)
      << " brings it to " << kMinEffectiveImpulses
      << " (docs/scenes.md \"Density, overlap and kurtosis\")";
    r.warn("density", s.str());
}

namespace fs = std::filesystem;
using detail::Reader;
using detail::Source;
using detail::key_check_times;

const auto kPositive = [](double v) { return v > 0.0; };
const auto kNonNegative = [](double v) { return v >= 0.0; };

std::string fnv1a_hex(std::string_view text) {
    uint64_t h = 1469598103934665603ull;
    for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
    std::ostringstream s;
    s << std::hex << h;
    return s.str();
}

/// Mix the scene-wide seed into a layer's seed (splitmix64 finaliser).
uint64_t mix_seed(uint64_t global, uint64_t layer) {
    uint64_t z = layer + 0x9E3779B97F4A7C15ull * (global + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/// A number as a person writes it (30, 2.5), for messages.
std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

bool whole_frames(double seconds, double fps) {
    const double f = seconds * fps;
    return std::abs(f - std::round(f)) < 1e-6;
}

/// Apply one "--set a.b.0.c=value" to the document.
void apply_override(toml::table& root, const std::string& text, Source& src) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0)
        throw SceneError("--set " + text + ": expected key=value (e.g. layer.0.kernel.radius=8)");
    const std::string key = text.substr(0, eq), value = text.substr(eq + 1);
    std::vector<std::string> parts;
    std::stringstream ss(key);
    for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
    toml::table* t = &root;
    std::string shown;  // the Reader's spelling of the path: layer[0].kernel.radius
    for (size_t i = 0; i + 1 < parts.size(); ++i) {
        const std::string& p = parts[i];
        const bool index = !p.empty() && std::all_of(p.begin(), p.end(), ::isdigit);
        if (index) {
            throw SceneError("--set " + text + ": index " + p + " must follow an array name");
        }
        toml::node* child = t->get(p);
        shown += (shown.empty() ? "" : ".") + p;
        if (child && child->is_array() && i + 2 < parts.size() + 1) {
            const std::string& ix = parts[i + 1];
            if (ix.empty() || !std::all_of(ix.begin(), ix.end(), ::isdigit))
                throw SceneError("--set " + text + ": " + p + " is an array: give an index (" + p + ".0...)");
            const size_t n = std::stoul(ix);
            toml::array* a = child->as_array();
            if (n >= a->size() || !(*a)[n].is_table())
                throw SceneError("--set " + text + ": " + p + " has " + std::to_string(a->size()) +
                                 " elements, no index " + ix);
            t = (*a)[n].as_table();
            shown += "[" + ix + "]";
            ++i;
            if (i + 1 >= parts.size())
                throw SceneError("--set " + text + ": expected a key after the index");
            continue;
        }
        if (child && child->is_table()) {
            t = child->as_table();
            if (p == "layer") shown += "[0]";
            if (i + 1 < parts.size() && parts[i + 1] == "0" && p == "layer") ++i;
            continue;
        }
        if (child) throw SceneError("--set " + text + ": " + p + " is not a table");
        t = t->insert_or_assign(p, toml::table{}).first->second.as_table();
    }
    const std::string& last = parts.back();
    shown += (shown.empty() ? "" : ".") + last;
    toml::node_view<toml::node> parsed;
    toml::table doc;
    try {
        doc = toml::parse("v = " + value);
    } catch (const toml::parse_error& e) {
        // A bare word is a string (--set layer.0.kernel.type=gabor); something that starts
        // like a number or a TOML value but does not parse is an error, not a string.
        const char c = value.empty() ? ' ' : value[0];
        if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.' ||
            c == '[' || c == '{' || c == '"' || c == '\'')
            throw SceneError("--set " + text + ": cannot parse the value: " + std::string(e.description()));
        doc = toml::table{};
        doc.insert("v", value);
    }
    t->insert_or_assign(last, *doc.get("v"));
    src.overrides[shown] = text;
}

/// A [[layer]] drawn by another synthesizer (source = "fbm", "subdivision", "solid"): its seed,
/// mean, gain, marginal and
/// composition; the impulse process's keys are refused (scenes/source.h).
void read_source_layer(Reader& r, size_t i, uint64_t global_seed, const fs::path& base,
                       const Limits& limits, detail::CompositionReader& compose, LayerConfig& L) {
    const std::string kind(detail::kLayerSourceNames[r.choice("source", detail::kLayerSourceNames, 0)]);
    for (std::string_view key : {"kernel", "density", "amplitude", "period", "lifetime", "envelope",
                                 "loop", "integrator", "substeps", "jacobian", "orientation",
                                 "region", "max_travel", "flow"})
        if (r.has(key))
            r.fail(r.node(key), key,
                   "a " + kind + " layer has no " + std::string(key) +
                       ": it belongs to the impulse process (source = \"impulses\")");
    L.process.layer = static_cast<uint32_t>(i);
    L.process.seed = mix_seed(global_seed, static_cast<uint64_t>(r.integer("seed", 1, 0, INT64_MAX)));
    L.mean = r.keyframed("mean", 0.0);
    L.gain = r.keyframed("gain", 1.0);
    if (kind == "fbm") {
        L.source = detail::read_fbm_source(r.table(kind), L.process.seed, limits.max_memory_mib);
    } else if (kind == "solid") {
        L.source = detail::read_solid_source(r.table(kind), L.process.seed);
    } else {
        std::optional<Reader> t = r.table(kind);
        if (!t)
            r.fail(r.node("source"), "source",
                   "a subdivision layer needs its [layer.subdivision] table with acf (markov, "
                   "gaussian, oscillatory_markov, ...) and the model's lengths");
        L.source = detail::read_subdivision_source(&*t, L.process.seed, base, limits.max_memory_mib);
    }
    detail::read_marginal(r, L, base);
    compose.read_layer(r, i, L);
    r.finish();
}

CameraConfig read_camera(std::optional<Reader> r, int width, int height) {
    CameraConfig c;
    c.center_x = numeric::Keyframed(width / 2.0);
    c.center_y = numeric::Keyframed(height / 2.0);
    if (!r) return c;
    r->refuse_keyframes("center");
    if (auto ct = r->node("center")) {
        if (ct->is_array()) {
            auto p = r->pair("center", "[x, y] in texture units, each within +-1e12", detail::on_plane);
            c.center_x = numeric::Keyframed((*p)[0]);
            c.center_y = numeric::Keyframed((*p)[1]);
        } else {
            r->fail(ct, "center", "expected [x, y] in texture units");
        }
    }
    if (r->has("center_x"))
        c.center_x = r->keyframed("center_x", width / 2.0, detail::on_plane, detail::kOnPlane);
    if (r->has("center_y"))
        c.center_y = r->keyframed("center_y", height / 2.0, detail::on_plane, detail::kOnPlane);
    c.zoom = r->keyframed("zoom", 1.0, kPositive, "a number > 0 (pixels per texture unit)");
    detail::read_camera_view(*r, c, width, height);  // type, perspective, anti-aliasing
    r->finish();
    return c;
}

std::shared_ptr<sim::Flow> read_flows(Reader& layer, const sim::ProcessConfig& process,
                                      const fs::path& base, detail::CompositionReader& compose,
                                      size_t index) {
    auto list = layer.tables("flow");
    if (list.empty()) return nullptr;
    if (process.lifetime_s <= 0)
        layer.fail(layer.node("flow"), "flow",
                   "a flow moves particles that are born and die: set lifetime > 0 in this layer");
    auto sum = std::make_shared<sim::FlowSum>();
    const std::array<std::string_view, 7> types = {"uniform", "shear", "vortex", "source",
                                                   "curl",    "image", "layer"};
    for (auto& f : list) {
        if (!f.has("type"))
            f.fail(nullptr, "type",
                   "missing: expected one of uniform, shear, vortex, source, curl, image, layer");
        const size_t type = f.choice("type", types, 0);
        auto center = [&](numeric::Keyframed& x, numeric::Keyframed& y) {
            const toml::node* n = f.node("center");
            if (!n) {
                x = f.keyframed("center_x", 0.0);
                y = f.keyframed("center_y", 0.0);
                return;
            }
            auto p = f.pair("center", "[x, y] in texture units");
            x = numeric::Keyframed((*p)[0]);
            y = numeric::Keyframed((*p)[1]);
            f.node("center_x"), f.node("center_y");
        };
        switch (type) {
            case 0: {  // uniform
                numeric::Keyframed vx(0.0), vy(0.0);
                if (f.node("velocity")) {
                    auto v = f.pair("velocity", "[vx, vy] in units per second");
                    vx = numeric::Keyframed((*v)[0]);
                    vy = numeric::Keyframed((*v)[1]);
                }
                if (f.has("vx")) vx = f.keyframed("vx", 0.0);
                if (f.has("vy")) vy = f.keyframed("vy", 0.0);
                sum->push(sim::make_uniform_flow(vx, vy));
                break;
            }
            case 1: {  // shear
                auto rate = f.keyframed("rate", 0.1);
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto angle = f.keyframed("angle", 0.0);
                sum->push(sim::make_shear_flow(rate, cx, cy, angle));
                break;
            }
            case 2: {  // vortex
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto gamma = f.keyframed("circulation", 2000.0);
                auto core = f.keyframed("core", 40.0, kPositive, "a radius > 0");
                const auto model = static_cast<sim::VortexModel>(f.choice("model", sim::kVortexModelNames, 0));
                sum->push(sim::make_vortex_flow(model, cx, cy, gamma, core));
                break;
            }
            case 3: {  // source / sink
                numeric::Keyframed cx, cy;
                center(cx, cy);
                auto rate = f.keyframed("rate", 0.1);
                auto radius = f.keyframed("radius", 0.0, kNonNegative, "a radius >= 0 (0: everywhere)");
                if (!radius.is_constant() && !(radius.min() > 0))
                    f.fail(f.node("radius"), "radius",
                           "expected a radius > 0 at every key (radius 0, a divergence everywhere, "
                           "is another field, not a limit of this one)");
                sum->push(sim::make_source_flow(cx, cy, rate, radius));
                break;
            }
            case 4: {  // curl noise
                const double scale = f.number(
                    "scale", 64.0,
                    [](double v) { return v >= sim::kMinCurlScale && v <= sim::kMaxCurlScale; },
                    "a length in [1e-3, 1e9] texture units");
                auto speed = f.keyframed("speed", 10.0, kNonNegative, "a speed >= 0");
                const uint64_t seed = static_cast<uint64_t>(f.integer("seed", 1, 0, INT64_MAX));
                sum->push(sim::make_curl_noise_flow(mix_seed(process.seed, seed), scale, speed, process.period));
                break;
            }
            case 5: {  // image
                const toml::node* pn = f.node("path");
                const std::string rel = f.string("path", "");
                if (rel.empty()) f.fail(pn, "path", "expected the path of a 2-channel velocity image");
                const fs::path p = detail::resolve_path(pn, rel, base);
                std::string error;
                auto in = output::open_image_input(p.string(), error);
                if (!in) f.fail(pn, "path", error);
                const auto& spec = in->spec();
                if (const std::string bad = output::image_size_problem(
                        spec.width, spec.height, spec.depth, spec.nchannels);
                    !bad.empty())
                    f.fail(pn, "path", bad);
                if (spec.nchannels < 2)
                    f.fail(pn, "path", "expected an image with 2 or more channels (vx, vy), found " +
                                           std::to_string(spec.nchannels));
                std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels);
                if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data()))
                    f.fail(pn, "path", "cannot read: " + in->geterror());
                sim::VectorGrid g;
                g.width = spec.width, g.height = spec.height;
                // Integer images store [0, 1]: map to [-1, 1] so grey means still.
                const bool unsigned_data = spec.format != OIIO::TypeDesc::FLOAT &&
                                           spec.format != OIIO::TypeDesc::HALF;
                for (size_t i = 0; i < size_t(g.width) * g.height; ++i) {
                    float vx = px[i * spec.nchannels], vy = px[i * spec.nchannels + 1];
                    if (unsigned_data) vx = 2 * vx - 1, vy = 2 * vy - 1;
                    g.vx.push_back(vx), g.vy.push_back(vy);
                }
                g.spacing = f.number("spacing", 1.0, kPositive, "texture units per image pixel, > 0");
                if (auto o = f.pair("origin", "[x, y] in texture units")) g.origin_x = (*o)[0], g.origin_y = (*o)[1];
                auto gain = f.keyframed("gain", 1.0);
                try {
                    sum->push(sim::make_grid_flow(std::move(g), gain));
                } catch (const ValueError& e) {
                    f.fail(pn, "path", e.what());
                }
                break;
            }
            case 6:  // another layer's field as stream function (scenes/compose_config.cpp)
                compose.read_flow(f, index, *sum);
                break;
        }
        f.finish();
    }
    return sum;
}

/// Kernel types of scene files: the analytic ones (kernels::kKernelTypeNames, in enum order),
/// then the designed ones (docs/scenes.md "Designed kernels").
const std::array<std::string_view, 6> kSceneKernelTypes = {
    "cosine", "gaussian", "gabor", "spectrum", "autocorrelation", "exemplar"};

/// A designed kernel: `spectrum`, `autocorrelation` or `exemplar` (kernels/spectral.h). Library
/// errors (ValueError, IoError) are reported at the key whose value caused them.
kernels::KernelParams read_designed_kernel(Reader& r, std::string_view type, Reader& layer,
                                           const fs::path& base, std::vector<KernelKey>& keys) {
    namespace K = kernels;
    const std::string tname(type);
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
        const bool acf = type == "autocorrelation";
        K::DesignOptions o;
        o.window = window;
        o.radius = radius;
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
                    sp = K::model_spectrum(mp, o.nyquist);
                else if (source == "expression")
                    sp = K::expression_spectrum(r.string("expression", ""));
                else
                    sp = K::table_spectrum(path_of(sn, r.string("table", "")).string());
                d = K::kernel_from_spectrum(sp, o);
            }
        } catch (const Error& e) {
            const std::string prefix =
                source == "expression" ? "expression \"" + r.string("expression", "") + "\"" : "";
            // Radius problems belong to the radius or energy key when one was given.
            const std::string what = e.what();
            if (what.find("radius") != std::string::npos && (radius_node || energy_node))
                r.fail(radius_node ? radius_node : energy_node, radius_node ? "radius" : "energy",
                       detail_of(e, prefix));
            r.fail(sn, source, detail_of(e, prefix));
        }
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

/// The [layer.kernel] table; keyframed fields go to `keys` (their values at t = 0 into the
/// result). `pyramid`: the camera anti-aliases through a kernel pyramid, built once per layer,
/// so only the orientation (a rotation of every impulse) may vary in time.
kernels::KernelParams read_kernel(std::optional<Reader> r, Reader& layer, const fs::path& base,
                                  std::vector<KernelKey>& keys, bool pyramid) {
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
        k = read_designed_kernel(*r, kSceneKernelTypes[type], layer, base, keys);
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

Scene read_scene(const toml::table& root, Source& src, const fs::path& base, OutputSize size,
                 OutputSize* own_size) {
    Scene s;
    Reader top(root, "", src);
    const uint64_t global_seed = static_cast<uint64_t>(top.integer("seed", 0, 0, INT64_MAX));
    s.seed = global_seed;

    if (top.has("include"))
        top.fail(top.node("include"), "include",
                 "includes are resolved before --set applies: write include in the scene file");
    if (auto o = top.table("output")) {
        o->refuse_keyframes("size");
        if (const toml::node* n = o->node("size")) {
            const toml::array* a = n->as_array();
            if (!a || a->size() != 2 || !(*a)[0].is_integer() || !(*a)[1].is_integer())
                o->fail(n, "size", "expected [width, height] in whole pixels");
            const int64_t w = (*a)[0].value<int64_t>().value_or(0), h = (*a)[1].value<int64_t>().value_or(0);
            if (w < 1 || h < 1 || w > 32768 || h > 32768)
                o->fail(n, "size", "expected [width, height] with each in [1, 32768]");
            s.output.width = static_cast<int>(w), s.output.height = static_cast<int>(h);
        }
        s.output.frames = o->integer("frames", 1, 1, 100000000);
        s.output.fps = o->number("fps", 30.0, [](double v) { return v > 0 && v <= 1000; }, "frames per second in (0, 1000]");
        s.output.start_s = o->number("start", 0.0, kNonNegative, "a time >= 0 in seconds");
        if (!whole_frames(s.output.start_s, s.output.fps))
            o->fail(o->node("start"), "start", "expected a whole number of frames at fps = " + num(s.output.fps));
        const std::array<std::string_view, 5> codecs = {"auto", "h264", "prores", "ffv1", "vp9"};
        s.output.codec = std::string(codecs[o->choice("codec", codecs, 0)]);
        s.output.crf = static_cast<int>(o->integer("crf", 18, 0, 63));
        const std::array<std::string_view, 9> presets = {"ultrafast", "superfast", "veryfast", "faster", "fast",
                                                         "medium", "slow", "slower", "veryslow"};
        s.output.preset = std::string(presets[o->choice("preset", presets, 5)]);
        s.output.range = o->pair("range", "[low, high] field values mapped to black and white");
        if (s.output.range && !((*s.output.range)[1] > (*s.output.range)[0]))
            o->fail(o->node("range"), "range", "expected low < high");
        s.output.bits = static_cast<int>(o->integer("bits", 8, 8, 16));
        if (s.output.bits != 8 && s.output.bits != 16) o->fail(o->node("bits"), "bits", "expected 8 or 16");
        o->finish();
    }
    // Defaults that depend on the frame size (centres) come from the scene's own size; --size
    // then scales the orthographic zoom so the same texture region fills the new size.
    const int scene_w = s.output.width, scene_h = s.output.height;
    if (size.width > 0 && size.height > 0)
        s.output.width = size.width, s.output.height = size.height;
    s.camera = read_camera(top.table("camera"), scene_w, scene_h);
    if (s.output.height != scene_h && s.camera.type == CameraConfig::Type::Orthographic)
        for (auto& key : s.camera.zoom.keys) key.second *= s.output.height / double(scene_h);
    if (own_size) *own_size = {scene_w, scene_h};
    auto shading = top.table("shading");
    if (shading)  // read first so read_shading knows the key
        s.transform = detail::read_transform(shading->table("transform"), s.camera, scene_w,
                                             scene_h, global_seed);
    s.shading = detail::read_shading(shading, base, s.shading_keys);
    if (auto l = top.table("limits")) {
        s.limits.max_impulses = l->number("max_impulses", s.limits.max_impulses, kPositive, "a count > 0");
        s.limits.max_memory_mib = l->number("max_memory_mib", s.limits.max_memory_mib, kPositive, "MiB > 0");
        s.limits.max_pixel_evaluations = l->number(
            "max_pixel_evaluations", s.limits.max_pixel_evaluations, kPositive, "a count > 0");
        l->finish();
    }

    auto layers = top.tables("layer");
    if (layers.empty()) {
        top.finish();  // an unknown key (a misspelt [[layer]]) explains more than the absence
        top.fail(nullptr, "layer", "a scene needs at least one [[layer]]");
    }
    detail::CompositionReader compose;  // keys naming other layers, resolved after the loop
    std::vector<LayerConfig> twins;  // quadrature twins of dispersive layers
    for (size_t i = 0; i < layers.size(); ++i) {
        Reader& r = layers[i];
        LayerConfig L;
        if (r.has("source") && r.choice("source", detail::kLayerSourceNames, 0) != 0) {
            read_source_layer(r, i, global_seed, base, s.limits, compose, L);
            s.layers.push_back(std::move(L));
            continue;
        }
        const bool pyramid = s.camera.type == CameraConfig::Type::Perspective || s.camera.antialiased();
        L.kernel = read_kernel(r.table("kernel"), r, base, L.kernel_keys, pyramid);
        if (!r.has("kernel")) r.node("kernel");
        sim::ProcessConfig& p = L.process;
        p.layer = static_cast<uint32_t>(i);
        p.seed = mix_seed(global_seed, static_cast<uint64_t>(r.integer("seed", 1, 0, INT64_MAX)));
        L.density = r.keyframed("density", 16.0, kPositive, "a density > 0 (impulses per kernel area)");
        p.amplitude = static_cast<sim::Amplitude>(r.choice("amplitude", sim::kAmplitudeNames, 0));
        L.mean = r.keyframed("mean", 0.0);
        L.gain = r.keyframed("gain", 1.0);
        p.period = r.pair("period", "[width, height] > 0 of the periodic domain", kPositive);
        p.lifetime_s = r.number("lifetime", 0.0, kNonNegative, "a lifetime >= 0 in seconds (0: still)");
        p.envelope = static_cast<sim::Envelope>(r.choice("envelope", sim::kEnvelopeNames, 0));
        p.loop_s = r.number("loop", 0.0, kNonNegative, "a period >= 0 in seconds (0: no loop)");
        if (p.loop_s > 0) {
            if (p.lifetime_s <= 0)
                r.fail(r.node("loop"), "loop", "a loop needs moving particles: set lifetime > 0");
            if (p.loop_s < p.lifetime_s)
                r.fail(r.node("loop"), "loop",
                       "a loop shorter than the lifetime (" + num(p.lifetime_s) +
                           " s) cannot repeat its births: expected loop >= lifetime");
            if (!whole_frames(p.loop_s, s.output.fps))
                r.fail(r.node("loop"), "loop", "expected a whole number of frames at fps = " + num(s.output.fps));
        }
        p.integrator = static_cast<sim::Integrator>(r.choice("integrator", sim::kIntegratorNames, 0));
        p.substeps = static_cast<int>(r.integer("substeps", 2, 1, 64));
        p.jacobian = r.boolean("jacobian", true);
        // a mode name or a field table; { type = "layer" } is composition's
        detail::read_orientation(r, p, base, [&](Reader& f) { compose.read_orientation(f, i); });
        detail::read_region(r, p, base);       // births confined to a shape or a mask
        p.max_travel = r.number("max_travel", 4096.0, kPositive, "a distance > 0 in texture units");
        if (p.lifetime_s <= 0 && !L.density.is_constant())
            r.fail(r.node("density"), "density",
                   "cannot vary in time in a still layer (lifetime = 0): its impulses are never "
                   "born or die, so their number cannot change without popping; set lifetime > 0");
        try {
            prepare_layer(L);
        } catch (const ValueError& e) {  // combinations the per-key checks cannot see
            r.fail(r.node("kernel"), "kernel", e.what());
        }
        L.flow = read_flows(r, p, base, compose, i);
        detail::read_marginal(r, L, base);
        compose.read_layer(r, i, L);
        detail::read_dispersion(r, L, twins, [&] { return read_flows(r, p, base, compose, i); });
        if (L.density.min() < 1.0)
            r.warn("density", "below 1 impulse per kernel area the noise is lumpy, see Lewis 1989 §4.1");
        else if (!L.source && L.kernel.type != kernels::KernelType::Sampled)
            warn_overlap(r, L);  // sampled (designed) kernels have their own peakedness warning
        r.finish();
        s.layers.push_back(std::move(L));
    }
    compose.resolve(s);
    // Quadrature twins of dispersive layers last: added layers commute, and the scene's own
    // layers keep their indices.
    for (auto& t : twins) s.layers.push_back(std::move(t));
    top.finish();
    return s;
}

}  // namespace

void prepare_layer(LayerConfig& layer) {
    namespace K = kernels;
    sim::ProcessConfig& p = layer.process;
    // Seeding cells as large as the kernel at its largest: a pixel's support meets at most
    // 3 x 3 cells (Lewis 1989 §4.1), which the naive reference relies on.
    p.cell_size = layer.max_radius();
    p.density_scale = nullptr;
    const double area0 = K::Kernel(layer.kernel).support_area();
    // The kernel area pi R^2 / aspect varies when radius or aspect is keyframed.
    const numeric::Keyframed* radius = nullptr;
    const numeric::Keyframed* aspect = nullptr;
    for (const auto& k : layer.kernel_keys) {
        if (k.field == &K::KernelParams::radius) radius = &k.value;
        if (k.field == &K::KernelParams::aspect) aspect = &k.value;
    }
    // A still layer's impulses never change: its intensity is set by the kernel at t = 0.
    if (p.lifetime_s <= 0 || (layer.density.is_constant() && !radius && !aspect)) {
        p.intensity = layer.density.value(0.0) / area0;
        return;
    }
    // lambda(t) = density(t) / area(t): births at the largest rate, thinned by
    // lambda(t_b) / lambda_max (sim::ProcessConfig::density_scale). The smallest radius and the
    // largest aspect bound the smallest area.
    K::KernelParams smallest = layer.kernel;
    if (radius) smallest.radius = radius->min();
    if (aspect) smallest.aspect = aspect->max();
    p.intensity = layer.density.max() / K::Kernel(smallest).support_area();
    const double r0 = layer.kernel.radius, a0 = layer.kernel.aspect;
    const numeric::Keyframed R = radius ? *radius : numeric::Keyframed(r0);
    const numeric::Keyframed A = aspect ? *aspect : numeric::Keyframed(a0);
    p.density_scale = [density = layer.density, R, A, lambda_max = p.intensity](double t) {
        const double r = R.value(t);
        const double area = std::numbers::pi * r * r / A.value(t);  // Kernel::support_area
        return density.value(t) / area / lambda_max;
    };
}

kernels::KernelParams LayerConfig::kernel_at(double t) const {
    kernels::KernelParams k = kernel;
    for (const auto& key : kernel_keys) k.*key.field = key.value.value(t);
    return k;
}

double LayerConfig::max_radius() const {
    for (const auto& key : kernel_keys)
        if (key.field == &kernels::KernelParams::radius) return key.value.max();
    return kernel.radius;
}

kernels::MarginalParams LayerConfig::marginal_at(double t) const {
    kernels::MarginalParams m = marginal->target().params();
    for (const auto& key : marginal_keys) m.*key.field = key.value.value(t);
    return m;
}

double LayerConfig::carrier_weight(double t) const {
    if (carrier_rate == 0.0) return 1.0;
    return carrier_quadrature ? -std::sin(carrier_rate * t) : std::cos(carrier_rate * t);
}

bool LayerConfig::keyframed() const {
    return !density.is_constant() || !mean.is_constant() || !gain.is_constant() ||
           !kernel_keys.empty() || !marginal_keys.empty();
}

double LayerConfig::layer_time(double t) const {
    const double P = process.loop_s;
    return P > 0 ? t - std::floor(t / P) * P : t;
}

namespace {

/// The text of a file, or nullopt with the system's reason in `error`.
/// Scene files and their includes are at most this long: a scene is a page of TOML, and a
/// larger file is a mistake (an include of a data file or a device).
constexpr std::uintmax_t kMaxSceneBytes = 1 << 20;

/// What a file that is not regular is, for messages.
const char* file_kind(fs::file_type t) {
    switch (t) {
        case fs::file_type::directory: return "a directory";
        case fs::file_type::fifo: return "a FIFO";
        case fs::file_type::character: return "a character device";
        case fs::file_type::block: return "a block device";
        case fs::file_type::socket: return "a socket";
        default: return "not a regular file";
    }
}

/// The text of a scene file, or nullopt with `error` set. Only regular files of at most
/// kMaxSceneBytes: the type is checked before opening, so a FIFO cannot block and /dev/zero
/// cannot fill memory.
std::optional<std::string> read_text(const std::string& path, std::string& error) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec) {
        error = ec.message();
        return std::nullopt;
    }
    if (st.type() != fs::file_type::regular) {
        error = std::string(file_kind(st.type())) + ": expected a regular file";
        return std::nullopt;
    }
    if (const auto size = fs::file_size(path, ec); !ec && size > kMaxSceneBytes) {
        error = std::to_string(size) + " bytes: a scene file is at most 1 MiB";
        return std::nullopt;
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        error = std::strerror(errno);
        return std::nullopt;
    }
    std::string text(kMaxSceneBytes + 1, '\0');  // a file grown since the check is cut here
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(size_t(in.gcount()));
    if (text.size() > kMaxSceneBytes) {
        error = "more than 1 MiB: a scene file is at most 1 MiB";
        return std::nullopt;
    }
    return text;
}

/// A path made absolute and normal, for comparing files (no exception for odd names).
fs::path same_file_key(const fs::path& p) {
    std::error_code ec;
    const fs::path c = fs::weakly_canonical(p, ec);
    return ec ? p.lexically_normal() : c;
}

/// Parses scene text; `name` names the file in messages and in every node's source.
toml::table parse_text(std::string_view text, const std::string& name) {
    try {
        return toml::parse(text, name);
    } catch (const toml::parse_error& e) {
        std::ostringstream s;
        s << name << ':' << e.source().begin.line << ':' << e.source().begin.column << ": "
          << e.description();
        throw SceneError(s.str());
    }
}

/// Puts `base` under `top`: keys of `top` win; a table written as a [section] in both merges
/// key by key; anything else (a value, an inline { ... } table such as a keyframe table, an
/// array, an array of tables such as [[layer]]) is replaced whole. Nodes are moved, so they
/// keep their file and position for messages.
void merge_under(toml::table& top, toml::table& base) {
    for (auto&& [key, node] : base) {
        toml::node* mine = top.get(key.str());
        if (!mine) {
            top.insert(key, std::move(node));
            continue;
        }
        toml::table* a = mine->as_table();
        toml::table* b = node.as_table();
        if (a && b && !a->is_inline() && !b->is_inline()) merge_under(*a, *b);
    }
}

/// Replaces the top-level `include` of `root` (the file `name`) by the included files' tables,
/// recursively: an included file's tables are the base and the including file's keys override
/// them; of a list of includes, later ones override earlier ones. `chain` holds the files being
/// included (to refuse cycles); `texts` collects the included files' texts (for the hash).
void resolve_includes(toml::table& root, const std::string& name,
                      std::vector<std::pair<fs::path, std::string>>& chain, std::string& texts) {
    const toml::node* n = root.get("include");
    if (!n) return;
    Source src;
    src.file = name;
    Reader r(root, "", src);
    std::vector<const toml::node*> files;
    if (n->is_string()) {
        files.push_back(n);
    } else if (const toml::array* a = n->as_array(); a && !a->empty()) {
        for (const auto& e : *a) {
            if (!e.is_string()) r.fail(&e, "include", "expected a file name (a string)");
            files.push_back(&e);
        }
    } else {
        r.fail(n, "include", "expected a file name or a list of file names");
    }
    std::vector<toml::table> included;
    for (const toml::node* f : files) {
        const std::string rel(f->value<std::string_view>().value_or(""));
        const fs::path path =
            detail::resolve_path(f, rel, fs::path(name).parent_path()).lexically_normal();
        const fs::path canonical = same_file_key(path);
        for (size_t i = 0; i < chain.size(); ++i)
            if (chain[i].first == canonical) {
                std::string cycle;
                for (size_t j = i; j < chain.size(); ++j) cycle += chain[j].second + " -> ";
                r.fail(f, "include", "include cycle: " + cycle + path.string());
            }
        std::string error;
        std::error_code ec;
        const auto text = read_text(path.string(), error);
        if (!text)
            r.fail(f, "include",
                   "cannot open: " + error +
                       (fs::path(rel).is_absolute() || fs::exists(path, ec)
                            ? ""
                            : " (relative to this file's directory)"));
        texts += "\n--include " + path.string() + "\n" + *text;
        included.push_back(parse_text(*text, path.string()));
        chain.emplace_back(canonical, path.string());
        resolve_includes(included.back(), path.string(), chain, texts);
        chain.pop_back();
    }
    root.erase("include");
    for (size_t i = included.size(); i-- > 0;) merge_under(root, included[i]);
}

}  // namespace

Scene load_scene_string(std::string_view text, const std::string& name,
                        const std::vector<std::string>& overrides, OutputSize size) {
    Source src;
    src.file = name;
    std::vector<std::string> warnings;
    src.warnings = &warnings;
    toml::table root = parse_text(text, name);
    std::string all(text);
    std::vector<std::pair<fs::path, std::string>> chain = {{same_file_key(name), name}};
    resolve_includes(root, name, chain, all);
    for (const auto& o : overrides) {
        apply_override(root, o, src);
        all += "\n--set " + o;
    }
    fs::path base = fs::path(name).parent_path();
    OutputSize own;
    Scene s = read_scene(root, src, base, size, &own);
    // Another resolution is another picture: the hash says so (the scene's own size does not).
    if (s.output.width != own.width || s.output.height != own.height)
        all += "\n--size " + std::to_string(s.output.width) + "x" + std::to_string(s.output.height);
    s.path = name;
    s.hash = fnv1a_hex(all);
    s.warnings = std::move(warnings);
    return s;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides,
                 OutputSize size) {
    std::string error;
    const auto text = read_text(path, error);
    if (!text) throw IoError(path + ": cannot open scene file: " + error);
    return load_scene_string(*text, path, overrides, size);
}

}  // namespace impulse::scenes
