// SPDX-License-Identifier: Apache-2.0
// A volume scene's [volume] (with [volume.kernel], [volume.shape], [[volume.flow]]) and
// [preview] tables (docs/volume.md).

#include <array>
#include <string>

#include "scenes/detail/loader.h"
#include "scenes/volume_scene.h"

namespace impulse::scenes::detail {
namespace {

/// An array of three numbers, each accepted by `ok`.
std::optional<std::array<double, 3>> triple(Reader& r, std::string_view key, const char* expected,
                                            const std::function<bool(double)>& ok = {}) {
    r.refuse_keyframes(key);
    const toml::node* n = r.node(key);
    if (!n) return std::nullopt;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) r.fail(n, key, std::string("expected ") + expected);
    std::array<double, 3> v{};
    for (size_t i = 0; i < 3; ++i) {
        const auto x = (*a)[i].value<double>();
        if (!x || !std::isfinite(*x) || (ok && !ok(*x))) r.fail(n, key, std::string("expected ") + expected);
        v[i] = *x;
    }
    return v;
}

const auto kFinite = [](double v) { return std::isfinite(v); };

void read_size(Reader& v, volume::CloudConfig& c) {
    const toml::node* n = v.node("size");
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) v.fail(n, "size", "expected [width, height, depth] in whole voxels");
    for (size_t i = 0; i < 3; ++i) {
        const auto x = (*a)[i].value<int64_t>();
        if (!(*a)[i].is_integer() || !x || *x < 1 || *x > 2048)
            v.fail(n, "size", "expected [width, height, depth] with each in [1, 2048]");
        c.size[i] = int(*x);
    }
}

void read_cloud_kernel(std::optional<Reader> k, volume::CloudConfig& c) {
    c.kernel.radius = 32.0;
    if (k) {
        const std::array<std::string_view, 2> types = {"cosine", "gaussian"};
        c.kernel.type = k->choice("type", types, 0) == 0 ? kernels::KernelType::Cosine
                                                         : kernels::KernelType::Gaussian;
        c.kernel.radius = k->number("radius", 32.0, [](double r) { return r >= 0.5 && r <= 1024; },
                                    "a radius in voxels in [0.5, 1024]");
        c.aspect = k->number("aspect", 1.0, [](double a) { return a > 0.0 && a <= 16.0; },
                             "a length along the kernel's axis over its width in (0, 16]");
        k->finish();
    }
    c.kernel.sigma = c.kernel.radius / 3.0;
}

/// [volume] orientation: one of sim::kOrientationModeNames (the 2-D layer's names and meanings;
/// docs/volume.md "Orientation"), a near miss named.
sim::OrientationMode read_orientation(Reader& v) {
    const toml::node* n = v.node("orientation");
    if (!n) return sim::OrientationMode::Fixed;
    const std::string name = v.string("orientation", "");
    std::vector<std::string> names;
    for (size_t i = 0; i < sim::kOrientationModeNames.size(); ++i) {
        if (sim::kOrientationModeNames[i] == name) return sim::OrientationMode(i);
        names.emplace_back(sim::kOrientationModeNames[i]);
    }
    std::string what = "expected one of ";
    for (size_t i = 0; i < names.size(); ++i) what += (i ? ", " : "") + names[i];
    if (const auto near = nearest(name, names)) what += " (did you mean \"" + *near + "\"?)";
    v.fail(n, "orientation", what);
}

void read_shape(std::optional<Reader> r, volume::CloudShape& s) {
    if (!r) return;
    const auto unit = [](double v) { return v >= 0.0 && v <= 1.0; };
    s.enabled = r->boolean("enabled", true);
    s.threshold = r->number("threshold", s.threshold, kFinite, "a number of standard deviations");
    s.gain = r->number("gain", s.gain, kPositive, "density per standard deviation, > 0");
    s.base = r->number("base", s.base, unit, "a fraction of the height in [0, 1]");
    s.top = r->number("top", s.top, unit, "a fraction of the height in [0, 1]");
    if (!(s.top > s.base)) r->fail(r->node("top"), "top", "expected top > base");
    s.softness = r->number("softness", s.softness, [](double v) { return v > 0.0 && v <= 0.5; },
                           "a fraction of the height in (0, 0.5]");
    r->finish();
}

std::shared_ptr<volume::Flow3> read_volume_flows(Reader& v, uint64_t global_seed,
                                                 const volume::CloudConfig& c,
                                                 const std::filesystem::path& base) {
    auto list = v.tables("flow");
    if (list.empty()) return nullptr;
    auto sum = std::make_shared<volume::FlowSum3>();
    const std::array<std::string_view, 4> types = {"uniform", "divergent", "curl", "sequence"};
    for (size_t i = 0; i < list.size(); ++i) {
        Reader& f = list[i];
        if (!f.has("type")) f.fail(nullptr, "type", "missing: expected one of uniform, divergent, curl, sequence");
        switch (f.choice("type", types, 0)) {
            case 0:
                sum->push(volume::make_uniform_flow3(
                    triple(f, "velocity", "[vx, vy, vz] in voxels per second", kFinite)
                        .value_or(std::array<double, 3>{0, 0, 0})));
                break;
            case 1: {
                const auto center = triple(f, "center", "[x, y, z] in voxels", kFinite);
                const double rate = f.number("rate", 0.1, [](double r) { return std::abs(r) <= 10; },
                                             "a rate in 1/s within +-10");
                const double pulse = f.number("pulse", 0.0, [](double r) { return std::abs(r) <= 10; },
                                              "a rate amplitude in 1/s within +-10");
                const double period = f.number("period", 4.0, kPositive, "seconds > 0");
                if (!center) f.fail(nullptr, "center", "missing: expected [x, y, z] in voxels");
                sum->push(volume::make_divergent_flow3(*center, rate, pulse, period));
                break;
            }
            case 3:  // a velocity sequence (scenes/language/sequence_config.cpp)
                read_volume_sequence_flow(f, c.lifetime_s, c.jacobian, v, base, *sum);
                break;
            default: {
                const double scale = f.number("scale", 48.0, [](double s) { return s >= 1 && s <= 1e5; },
                                              "a potential radius in voxels in [1, 1e5]");
                const double speed = f.number("speed", 4.0, kNonNegative, "an RMS speed >= 0 in voxels per second");
                sum->push(volume::make_curl_flow3(mix_seed(global_seed, 0x43000000u + i), scale, speed));
            }
        }
        f.finish();
    }
    return sum;
}

void read_preview(std::optional<Reader> r, volume::MarchOptions& m) {
    if (!r) return;
    const auto nonzero = [](const std::array<double, 3>& v) { return v[0] != 0 || v[1] != 0 || v[2] != 0; };
    if (auto s = triple(*r, "sun", "a direction [x, y, z] towards the light, not zero", kFinite)) {
        if (!nonzero(*s)) r->fail(r->node("sun"), "sun", "expected a direction [x, y, z], not zero");
        m.sun = *s;
    }
    const auto colour = [](double v) { return v >= 0.0 && v <= 100.0; };
    if (auto c = triple(*r, "sun_color", "[r, g, b] in [0, 100]", colour)) m.sun_color = *c;
    if (auto c = triple(*r, "sky_zenith", "[r, g, b] in [0, 100]", colour)) m.sky_zenith = *c;
    if (auto c = triple(*r, "sky_horizon", "[r, g, b] in [0, 100]", colour)) m.sky_horizon = *c;
    m.extinction = r->number("extinction", m.extinction, kPositive, "sigma_t per unit density per voxel, > 0");
    m.albedo = r->number("albedo", m.albedo, [](double v) { return v >= 0 && v <= 1; }, "in [0, 1]");
    m.anisotropy = r->number("anisotropy", m.anisotropy, [](double v) { return v > -1 && v < 1; }, "g in (-1, 1)");
    m.ambient = r->number("ambient", m.ambient, kNonNegative, "a number >= 0");
    m.exposure = r->number("exposure", m.exposure, kPositive, "a number > 0");
    if (auto e = triple(*r, "eye", "[x, y, z] in voxels", kFinite)) m.eye = *e;
    if (auto t = triple(*r, "target", "[x, y, z] in voxels", kFinite)) m.target = *t;
    if (r->has("eye") != r->has("target")) r->fail(nullptr, "eye", "give both eye and target (or neither)");
    if (r->has("eye") && m.eye == m.target) r->fail(r->node("target"), "target", "expected a point other than eye");
    m.fov_deg = r->number("fov", m.fov_deg, [](double v) { return v > 0 && v < 180; }, "degrees in (0, 180)");
    m.step = r->number("step", m.step, [](double v) { return v >= 0.05 && v <= 64; }, "voxels in [0.05, 64]");
    r->finish();
}

}  // namespace

std::shared_ptr<const VolumeSceneConfig> read_volume_scene(Reader& top, uint64_t global_seed,
                                                          const OutputConfig& output,
                                                          const std::filesystem::path& base) {
    auto cfg = std::make_shared<VolumeSceneConfig>();
    volume::CloudConfig& c = cfg->cloud;
    Reader v = *top.table("volume");
    c.seed = mix_seed(global_seed, 0x564F4Cu);  // "VOL"
    c.fps = output.fps;
    read_size(v, c);
    cfg->voxel_size = v.number("voxel_size", 1.0, [](double s) { return s > 0 && s <= 1e6; },
                               "world units per voxel in (0, 1e6]");
    c.density = v.number("density", c.density, [](double d) { return d > 0 && d <= 1000; },
                         "impulses per kernel volume in (0, 1000]");
    c.octaves = int(v.integer("octaves", c.octaves, 1, 6));
    c.lacunarity = v.number("lacunarity", c.lacunarity, [](double l) { return l > 1 && l <= 8; }, "a ratio in (1, 8]");
    c.gain = v.number("gain", c.gain, [](double g) { return g > 0 && g <= 1; }, "an amplitude ratio in (0, 1]");
    // The zero-mean laws only (the first three names): the volume's theory is a zero-mean one.
    constexpr std::array<std::string_view, 3> kZeroMean = {sim::kAmplitudeNames[0], sim::kAmplitudeNames[1],
                                                           sim::kAmplitudeNames[2]};
    c.amplitude = sim::Amplitude(v.choice("amplitude", kZeroMean, 0));
    c.lifetime_s = v.number("lifetime", c.lifetime_s, [](double t) { return t > 0 && t <= 1e4; },
                            "seconds in (0, 1e4]");
    c.envelope = sim::Envelope(v.choice("envelope", sim::kEnvelopeNames, 0));
    c.jacobian = v.boolean("jacobian", true);
    c.substeps = int(v.integer("substeps", 1, 1, 64));
    c.orientation = read_orientation(v);
    read_cloud_kernel(v.table("kernel"), c);
    read_shape(v.table("shape"), c.shape);
    c.flow = read_volume_flows(v, global_seed, c, base);
    v.finish();
    read_preview(top.table("preview"), cfg->march);
    cfg->march.width = output.width, cfg->march.height = output.height;
    return cfg;
}

}  // namespace impulse::scenes::detail
