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

#include "scenes/detail/camera.h"
#include "scenes/detail/compose.h"
#include "scenes/detail/loader.h"
#include "scenes/detail/marginal.h"
#include "scenes/detail/reader.h"
#include "scenes/detail/source.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace impulse::scenes {

namespace detail {

uint64_t mix_seed(uint64_t global, uint64_t layer) {
    uint64_t z = layer + 0x9E3779B97F4A7C15ull * (global + 1);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

}  // namespace detail

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


std::string fnv1a_hex(std::string_view text) {
    uint64_t h = 1469598103934665603ull;
    for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
    std::ostringstream s;
    s << std::hex << h;
    return s.str();
}

using detail::kNonNegative;
using detail::kPositive;
using detail::mix_seed;
using detail::num;
using detail::read_camera;
using detail::read_flows;
using detail::read_kernel;
using detail::read_source_layer;

/// MiB the tiles of the source layers read so far hold (a frame's buffers not counted: the
/// Renderer adds them to its estimate once the size is known).
double held_tiles_mib(const std::vector<LayerConfig>& layers) {
    double bytes = 0.0;
    for (const LayerConfig& l : layers)
        if (l.source) bytes += l.source->memory_bytes(0.0, false);
    return bytes / (1024.0 * 1024.0);
}

/// output.compression: one of OpenEXR's compressions as OpenImageIO names them.
std::string exr_compression(detail::Reader& o) {
    std::array<std::string_view, std::size(output::kExrCompressions)> names;
    size_t fallback = 0;
    for (size_t i = 0; i < names.size(); ++i) {
        names[i] = output::kExrCompressions[i];
        if (names[i] == output::kDefaultExrCompression) fallback = i;
    }
    return std::string(names[o.choice("compression", names, fallback)]);
}

bool whole_frames(double seconds, double fps) {
    const double f = seconds * fps;
    return std::abs(f - std::round(f)) < 1e-6;
}

/// The value of "--set key=value" as the table { v = value }: a TOML value, or a bare word as
/// a string.
toml::table override_value(const std::string& text, const std::string& value) {
    try {
        return toml::parse("v = " + value);
    } catch (const toml::parse_error& e) {
        // A bare word is a string (--set layer.0.kernel.type=gabor); something that starts
        // like a number or a TOML value but does not parse is an error, not a string.
        const char c = value.empty() ? ' ' : value[0];
        if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.' ||
            c == '[' || c == '{' || c == '"' || c == '\'')
            throw SceneError("--set " + text +
                             ": cannot parse the value: " + std::string(e.description()));
        toml::table doc;
        doc.insert("v", value);
        return doc;
    }
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
    const toml::table doc = override_value(text, value);
    t->insert_or_assign(last, *doc.get("v"));
    src.overrides[shown] = text;
}





/// output.channels: names of kChannelNames (docs/channels.md); empty when absent.
std::vector<std::string> output_channels(Reader& o) {
    o.refuse_keyframes("channels");
    const toml::node* n = o.node("channels");
    if (!n) return {};
    const toml::array* a = n->as_array();
    if (!a || a->empty()) o.fail(n, "channels", "expected a list of channel names, e.g. [\"value\", \"dx\", \"dy\"]");
    std::vector<std::string> names;
    for (const toml::node& e : *a) {
        if (!e.is_string()) o.fail(&e, "channels", "expected channel names (strings), found " + detail::type_name(e));
        names.push_back(*e.value<std::string>());
    }
    try {
        parse_channels(names, "channels");
    } catch (const ValueError& e) {
        const std::string why = e.what();
        o.fail(n, "channels", why.substr(why.find(": ") + 2));
    }
    return names;
}

/// [output]: size, frames, timing, codec and its settings, display range, bits, compression.
void read_output(Reader& o, OutputConfig& out) {
    o.refuse_keyframes("size");
    if (const toml::node* n = o.node("size")) {
        const toml::array* a = n->as_array();
        if (!a || a->size() != 2 || !(*a)[0].is_integer() || !(*a)[1].is_integer())
            o.fail(n, "size", "expected [width, height] in whole pixels");
        const int64_t w = (*a)[0].value<int64_t>().value_or(0), h = (*a)[1].value<int64_t>().value_or(0);
        if (w < 1 || h < 1 || w > 32768 || h > 32768)
            o.fail(n, "size", "expected [width, height] with each in [1, 32768]");
        out.width = static_cast<int>(w), out.height = static_cast<int>(h);
    }
    out.frames = o.integer("frames", 1, 1, 100000000);
    out.fps = o.number("fps", 30.0, [](double v) { return v > 0 && v <= 1000; }, "frames per second in (0, 1000]");
    out.start_s = o.number("start", 0.0, kNonNegative, "a time >= 0 in seconds");
    if (!whole_frames(out.start_s, out.fps))
        o.fail(o.node("start"), "start", "expected a whole number of frames at fps = " + num(out.fps));
    const std::array<std::string_view, 5> codecs = {"auto", "h264", "prores", "ffv1", "vp9"};
    out.codec = std::string(codecs[o.choice("codec", codecs, 0)]);
    out.crf = static_cast<int>(o.integer("crf", 18, 0, 63));
    const std::array<std::string_view, 9> presets = {"ultrafast", "superfast", "veryfast", "faster", "fast",
                                                     "medium", "slow", "slower", "veryslow"};
    out.preset = std::string(presets[o.choice("preset", presets, 5)]);
    out.range = o.pair("range", "[low, high] field values mapped to black and white");
    if (out.range && !((*out.range)[1] > (*out.range)[0]))
        o.fail(o.node("range"), "range", "expected low < high");
    out.bits = static_cast<int>(o.integer("bits", 8, 8, 16));
    if (out.bits != 8 && out.bits != 16) o.fail(o.node("bits"), "bits", "expected 8 or 16");
    out.compression = exr_compression(o);
    out.channels = output_channels(o);
    o.finish();
}

/// [limits]: the budgets a render is held to.
void read_limits(Reader& l, Limits& limits) {
    limits.max_impulses = l.number("max_impulses", limits.max_impulses, kPositive, "a count > 0");
    limits.max_memory_mib = l.number("max_memory_mib", limits.max_memory_mib, kPositive, "MiB > 0");
    limits.max_pixel_evaluations = l.number(
        "max_pixel_evaluations", limits.max_pixel_evaluations, kPositive, "a count > 0");
    limits.max_flow_steps =
        l.number("max_flow_steps", limits.max_flow_steps, kPositive, "a count > 0");
    l.finish();
}

/// One [[layer]] of impulses (the point process): kernel, process, orientation, region, flows,
/// marginal, composition keys and dispersion (its quadrature twin goes to `twins`).
/// Exponential (positive) amplitudes give a field of mean lambda E[a] int h (Campbell). What
/// assumes a zero-mean impulse train refuses them: the shot-noise marginal (its CDF knows the
/// zero-mean laws) and the perspective camera, whose fade to the mean towards the horizon drops
/// a faded impulse's mass instead of keeping it. (An orthographic view fades only when zoomed
/// out until a kernel keeps under 2 % of its sd; the low-passed levels keep int h, so the mean.)
void check_positive_amplitudes(Reader& r, const LayerConfig& L, bool perspective) {
    if (L.process.amplitude != sim::Amplitude::Exponential) return;
    if (L.marginal)
        r.fail(r.node("amplitude"), "amplitude",
               "exponential amplitudes have no shot-noise marginal: expected normal, uniform or "
               "sign with [layer.marginal]");
    if (perspective)
        r.fail(r.node("amplitude"), "amplitude",
               "exponential amplitudes cannot be faded to the mean by a perspective camera: "
               "expected normal, uniform or sign");
}

void read_impulse_layer(Reader& r, size_t i, uint64_t global_seed, const fs::path& base,
                        const Scene& s, detail::CompositionReader& compose,
                        std::vector<LayerConfig>& twins, LayerConfig& L) {
    const bool pyramid = s.camera.type == CameraConfig::Type::Perspective || s.camera.antialiased();
    L.kernel = read_kernel(r.table("kernel"), r, base, L.kernel_keys, pyramid,
                           s.limits.max_memory_mib);
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
    L.flow = read_flows(r, p, base, compose, i, &L.uniform_flows);
    detail::read_marginal(r, L, base);
    detail::read_scale(r, base, L);  // after the marginal, which it cannot shape
    check_positive_amplitudes(r, L, s.camera.type == CameraConfig::Type::Perspective);
    compose.read_layer(r, i, L);
    detail::read_dispersion(r, L, twins, [&] { return read_flows(r, p, base, compose, i); });
    if (L.density.min() < 1.0)
        r.warn("density", "below 1 impulse per kernel area the noise is lumpy, see Lewis 1989 §4.1");
    else if (!L.source && L.kernel.type != kernels::KernelType::Sampled)
        warn_overlap(r, L);  // sampled (designed) kernels have their own peakedness warning
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
    if (auto o = top.table("output")) read_output(*o, s.output);
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
    if (auto l = top.table("limits")) read_limits(*l, s.limits);
    if (auto r = top.table("render")) {
        s.render.tolerance = r->number(
            "tolerance", s.render.tolerance,
            [](double v) { return v >= 0.0 && v <= render::kMaxLatticeTolerance; },
            "a fraction of each layer's sd in [0, 0.1] (0: direct evaluation)");
        r->finish();
    }

    if (top.has("volume")) {  // impulses in 3-D (docs/volume.md): no [[layer]], no 2-D view
        if (top.has("layer"))
            top.fail(top.node("layer"), "layer", "a volume scene ([volume]) has no [[layer]]");
        for (const char* k : {"camera", "shading"})
            if (top.has(k)) top.fail(top.node(k), k, "a volume scene is lit and framed by [preview]");
        s.volume = detail::read_volume_scene(top, global_seed, s.output, base);
        top.finish();
        return s;
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
            read_source_layer(
                r, i, global_seed, base, {s.limits.max_memory_mib, held_tiles_mib(s.layers)},
                s.camera.zoom.min(), s.camera.type == CameraConfig::Type::Perspective, compose, L);
            s.layers.push_back(std::move(L));
            continue;
        }
        read_impulse_layer(r, i, global_seed, base, s, compose, twins, L);
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
    if (s.output.width != own.width || s.output.height != own.height) {
        all += "\n--size " + std::to_string(s.output.width) + "x" + std::to_string(s.output.height);
        s.resized = {s.output.width, s.output.height};
    }
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
