// SPDX-License-Identifier: Apache-2.0
// Composition keys of [[layer]] tables (docs/scenes.md "Composition"): name, visible, blend,
// opacity, alpha, warp, orientation = { type = "layer" } and [[layer.flow]] type = "layer".
// References to other layers are collected while the layers are read and resolved once all of
// them are known, so a layer may name one defined after it.

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>

#include "scenes/detail/compose.h"
#include "numeric/errors.h"

namespace impulse::scenes::detail {
namespace {

/// A flow term whose field is known only once every layer is read (type = "layer"): it holds
/// the term's place in the layer's sum of flows, so the terms add in the order of the file.
class DeferredFlow final : public sim::Flow {
public:
    void set(std::unique_ptr<sim::Flow> flow) { m_flow = std::move(flow); }
    void add(double t, size_t n, const double* x, const double* y, double* vx, double* vy,
             double* div, double* curl) const override {
        m_flow->add(t, n, x, y, vx, vy, div, curl);
    }
    double max_speed(const numeric::Box& region) const override { return m_flow->max_speed(region); }
    std::array<double, 4> velocity_bounds(const numeric::Box& region) const override {
        return m_flow->velocity_bounds(region);
    }
    void prepare(const numeric::Box& region) override { m_flow->prepare(region); }
    double cache_bytes(const numeric::Box& region) const override {
        return m_flow ? m_flow->cache_bytes(region) : 0.0;
    }

private:
    std::unique_ptr<sim::Flow> m_flow;
};

std::string layer_name(size_t i) { return "layer[" + std::to_string(i) + "]"; }

/// A number as a person writes it (2, 0.5), for messages.
std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

}  // namespace

/// A key that names another layer, kept with its table's reader for the message.
struct CompositionReader::Ref {
    enum class Use { WarpX, WarpY, Orientation, Flow };
    Use use;
    size_t layer;  ///< the layer that reads the other
    Reader reader;
    std::string key;
    const toml::node* node;
    bool level_lines = false;  ///< Use::Orientation
    size_t flow = 0;           ///< Use::Flow: index into m_flows
    size_t target = 0;         ///< the resolved layer
};

struct CompositionReader::PendingFlow {
    DeferredFlow* term;
    numeric::Keyframed speed;
};

CompositionReader::CompositionReader() = default;
CompositionReader::~CompositionReader() = default;

void CompositionReader::read_layer(Reader& r, size_t index, LayerConfig& layer) {
    if (m_layers.size() <= index) m_layers.resize(index + 1);
    m_layers[index].emplace(r);
    Composition& c = layer.compose;
    if (const toml::node* n = r.node("name")) {
        c.name = r.string("name", "");
        if (c.name.empty()) r.fail(n, "name", "expected a non-empty name");
    }
    c.visible = r.boolean("visible", true);
    c.blend = static_cast<Blend>(r.choice("blend", kBlendNames, 0));
    c.opacity = r.keyframed(
        "opacity", 1.0, [](double v) { return v >= 0.0 && v <= 1.0; }, "an opacity in [0, 1]");
    c.alpha = r.pair("alpha", "[lo, hi]: the layer values over which its alpha ramps from 0 to 1");
    if (c.alpha && !((*c.alpha)[0] != (*c.alpha)[1]))
        r.fail(r.node("alpha"), "alpha", "expected lo != hi (the alpha ramp needs a width)");
    if (c.alpha && c.blend != Blend::Over)
        r.warn("alpha", "ignored for blend = \"" + std::string(kBlendNames[size_t(c.blend)]) +
                            "\" (the alpha range applies to blend = \"over\")");
    if (auto w = r.table("warp")) {
        const toml::node* sn = w->node("source");
        const toml::array* a = sn ? sn->as_array() : nullptr;
        if (!a || a->size() != 2)
            w->fail(sn, "source",
                    "expected two layers [x, y] (names or indices) whose values displace this "
                    "layer along x and y");
        m_refs.push_back({Ref::Use::WarpX, index, *w, "source[0]", &(*a)[0]});
        m_refs.push_back({Ref::Use::WarpY, index, *w, "source[1]", &(*a)[1]});
        if (!w->has("amount"))
            w->fail(nullptr, "amount",
                    "missing: expected the displacement in texture units per standard deviation "
                    "of the sources");
        WarpConfig warp;
        warp.amount = w->keyframed(
            "amount", 0.0, [](double v) { return v >= 0.0; },
            "a distance >= 0 in texture units (per standard deviation of the sources)");
        w->finish();
        c.warp = warp;
    }
}

void CompositionReader::read_orientation(Reader& f, size_t index) {
    const toml::node* sn = f.node("source");
    if (!sn)
        f.fail(nullptr, "source",
               "missing: expected the name or index of the layer whose field orients this one");
    const std::array<std::string_view, 2> along = {"gradient", "level"};
    Ref ref{Ref::Use::Orientation, index, f, "source", sn};
    ref.level_lines = f.choice("along", along, 0) == 1;
    m_refs.push_back(ref);
}

void CompositionReader::read_flow(Reader& f, size_t index, sim::FlowSum& sum) {
    const toml::node* sn = f.node("source");
    if (!sn)
        f.fail(nullptr, "source",
               "missing: expected the name or index of a still layer whose field is the stream "
               "function");
    auto term = std::make_unique<DeferredFlow>();
    m_flows.push_back(std::make_unique<PendingFlow>(PendingFlow{
        term.get(), f.keyframed("speed", 10.0, [](double v) { return v >= 0.0; },
                                "a speed >= 0 (RMS, texture units per second)")}));
    sum.push(std::move(term));
    Ref ref{Ref::Use::Flow, index, f, "source", sn};
    ref.flow = m_flows.size() - 1;
    m_refs.push_back(ref);
}

namespace {

/// What to suggest for an unknown layer name: the nearest name, or the list of names.
std::string name_hint(const std::string& name, const std::vector<std::string>& names) {
    if (auto near = nearest(name, names)) return " (did you mean \"" + *near + "\"?)";
    if (names.empty()) return " (no layer has a name: give the source layer name = \"...\")";
    std::string hint = " (names:";
    for (size_t i = 0; i < names.size(); ++i) hint += (i ? ", " : " ") + names[i];
    return hint + ")";
}

/// Why `source` cannot be a stream function (the first reason), or nothing when it can.
std::optional<std::string> unfit_stream_function(const LayerConfig& source) {
    if (source.source)
        return "is a " + std::string(source.source->kind()) +
               " layer: a stream function is an impulse layer's field, whose "
               "derivatives the flow takes in closed form";
    const auto& p = source.process;
    if (p.lifetime_s > 0)
        return "has lifetime = " + num(p.lifetime_s) +
               ": a stream function must be a still layer (lifetime = 0), so the flow "
               "is the same at every time and each frame stays independent of the "
               "others";
    if (source.marginal) return "has a marginal: a stream function must be an unshaped layer";
    if (source.compose.warp) return "is warped: a stream function must be an unwarped layer";
    if (p.orientation == sim::OrientationMode::Field)
        return "has an orientation field: a stream function takes fixed or random "
               "orientations only";
    if (source.scale)
        return "has a kernel scale field: a stream function's kernel is the same everywhere";
    if (source.keyframed())
        return "has keyframed parameters: a stream function must be the same at every "
               "time, so each frame stays independent of the others";
    if (source.gain.value(0.0) == 0.0) return "has gain = 0: a constant field has no level lines";
    return std::nullopt;
}

/// The still impulse layer `source` as a stream function psi, whose kernel and semivariogram
/// the flow differentiates.
sim::StreamFunction stream_function_of(const LayerConfig& source) {
    auto kernel = std::make_shared<const kernels::Kernel>(source.kernel);
    const bool random = source.process.orientation == sim::OrientationMode::Random;
    sim::StreamFunction psi;
    psi.process = source.process;
    psi.gain = source.gain.value(0.0);
    psi.radius = source.kernel.radius;
    psi.kernel = [kernel](double dx, double dy, double theta) {
        return kernel->evaluate(dx, dy, theta);
    };
    psi.semivariogram = [kernel, random](double tx, double ty) {
        return sampled_semivariogram(*kernel, random, tx, ty);
    };
    return psi;
}

}  // namespace

std::map<std::string, size_t> CompositionReader::unique_names(
    const std::vector<LayerConfig>& layers, std::vector<std::string>& names) {
    std::map<std::string, size_t> by_name;
    for (size_t i = 0; i < layers.size(); ++i) {
        const std::string& name = layers[i].compose.name;
        if (name.empty()) continue;
        auto [it, fresh] = by_name.emplace(name, i);
        if (!fresh)
            m_layers[i]->fail(m_layers[i]->node("name"), "name",
                              layer_name(it->second) + " has the same name: names must be unique");
        names.push_back(name);
    }
    return by_name;
}

void CompositionReader::resolve_target(Ref& ref, const std::map<std::string, size_t>& by_name,
                                       const std::vector<std::string>& names, size_t n) {
    const toml::node* v = ref.node;
    if (const auto* s = v->as_string()) {
        auto it = by_name.find(s->get());
        if (it == by_name.end())
            ref.reader.fail(v, ref.key,
                            "no layer is named \"" + s->get() + "\"" + name_hint(s->get(), names));
        ref.target = it->second;
    } else if (v->is_integer()) {
        const int64_t i = v->value<int64_t>().value_or(-1);
        if (i < 0 || i >= static_cast<int64_t>(n))
            ref.reader.fail(
                v, ref.key,
                "expected a layer index in [0, " + std::to_string(n - 1) + "] or a layer's name");
        ref.target = static_cast<size_t>(i);
    } else {
        ref.reader.fail(v, ref.key, "expected a layer's name or index, found " + type_name(*v));
    }
    if (ref.target == ref.layer) {
        static const char* kSelf[] = {"a layer cannot warp itself", "a layer cannot warp itself",
                                      "a layer cannot take its orientation from itself",
                                      "a layer cannot flow along its own field"};
        ref.reader.fail(v, ref.key, kSelf[static_cast<int>(ref.use)]);
    }
}

void CompositionReader::connect_warp(const Ref& ref, Scene& scene) {
    if (scene.camera.type == CameraConfig::Type::Perspective) {
        Reader& r = *m_layers[ref.layer];
        r.fail(r.node("warp"), "warp",
               "a domain warp needs an orthographic camera, not camera.type = "
               "\"perspective\" (the warp resamples the layer's image)");
    }
    if (!(layer_theory(scene.layers[ref.target]).variance > 0.0))
        ref.reader.fail(ref.node, ref.key,
                        layer_name(ref.target) +
                            " has no variance (gain = 0): its standardised values, "
                            "the displacement, are undefined");
    scene.layers[ref.layer].compose.warp->source[ref.use == Ref::Use::WarpX ? 0 : 1] = ref.target;
}

void CompositionReader::connect_flow(const Ref& ref, std::vector<LayerConfig>& layers) {
    const LayerConfig& source = layers[ref.target];
    auto unfit = [&](const std::string& why) {
        ref.reader.fail(ref.node, ref.key, layer_name(ref.target) + " " + why);
    };
    if (auto why = unfit_stream_function(source)) unfit(*why);
    PendingFlow& pf = *m_flows[ref.flow];
    try {
        pf.term->set(sim::make_stream_flow(stream_function_of(source), pf.speed));
    } catch (const ValueError& e) {
        unfit(std::string("cannot be a stream function: ") + e.what());
    }
    layers[ref.layer].compose.flow_sources.push_back(ref.target);
}

void CompositionReader::refuse_cycles(size_t n) {
    std::vector<std::vector<const Ref*>> needs(n);
    for (const Ref& ref : m_refs)
        if (ref.use != Ref::Use::Flow) needs[ref.layer].push_back(&ref);
    std::vector<int> state(n, 0);  // 0 unvisited, 1 on the path, 2 done
    std::vector<size_t> path;
    auto visit = [&](auto&& self, size_t i) -> void {
        state[i] = 1;
        path.push_back(i);
        for (const Ref* ref : needs[i]) {
            if (state[ref->target] == 1) {
                std::string cycle;
                auto from = std::find(path.begin(), path.end(), ref->target);
                for (auto it = from; it != path.end(); ++it) cycle += layer_name(*it) + " -> ";
                cycle += layer_name(ref->target);
                ref->reader.fail(ref->node, ref->key,
                                 "a cycle: " + cycle + " (each needs the next one's field)");
            }
            if (state[ref->target] == 0) self(self, ref->target);
        }
        path.pop_back();
        state[i] = 2;
    };
    for (size_t i = 0; i < n; ++i)
        if (state[i] == 0) visit(visit, i);
}

void CompositionReader::check_visibility(const std::vector<LayerConfig>& layers) {
    const size_t n = layers.size();
    std::vector<bool> used(n, false);
    for (const Ref& ref : m_refs) used[ref.target] = true;
    size_t first = n;
    for (size_t i = 0; i < n; ++i)
        if (layers[i].compose.visible) {
            first = i;
            break;
        }
    if (first == n) {
        Reader& r = *m_layers[n - 1];
        r.fail(r.node("visible"), "visible", "every layer is hidden: nothing to show");
    }
    const Blend b = layers[first].compose.blend;
    if (b == Blend::Multiply || b == Blend::Max || b == Blend::Min) {
        Reader& r = *m_layers[first];
        r.fail(r.node("blend"), "blend",
               "the first visible layer has nothing under it to blend with: expected add or over "
               "(or move the layer after another)");
    }
    for (size_t i = 0; i < n; ++i)
        if (!layers[i].compose.visible && !used[i])
            m_layers[i]->warn("visible", "this hidden layer is no layer's source: it is never "
                                         "rendered");
}

void CompositionReader::resolve(Scene& scene) {
    auto& layers = scene.layers;
    std::vector<std::string> names;
    const std::map<std::string, size_t> by_name = unique_names(layers, names);
    for (Ref& ref : m_refs) resolve_target(ref, by_name, names, layers.size());
    // Each use, with what it needs of its source.
    for (const Ref& ref : m_refs) {
        switch (ref.use) {
            case Ref::Use::WarpX:
            case Ref::Use::WarpY:
                connect_warp(ref, scene);
                break;
            case Ref::Use::Orientation:
                layers[ref.layer].compose.orientation =
                    LayerOrientation{ref.target, ref.level_lines};
                break;
            case Ref::Use::Flow:
                connect_flow(ref, layers);
                break;
        }
    }
    // No layer may need its own field through a chain of warps and orientations.
    refuse_cycles(layers.size());
    // Visibility: something to show, and a first layer that has nothing under it can only add
    // or lie over the empty (zero) picture.
    check_visibility(layers);
}

double sampled_semivariogram(const kernels::Kernel& kernel, bool random_orientation, double tx,
                             double ty) {
    const double R = kernel.radius();
    auto at = [&](double ax, double ay) {
        // (h(x) - h(x + a))^2 is zero outside the union of the two supports.
        const double reach = R + std::hypot(ax, ay);
        constexpr int kN = 96;
        const double step = 2.0 * reach / kN;
        double sum = 0.0;
        for (int j = 0; j < kN; ++j)
            for (int i = 0; i < kN; ++i) {
                const double x = -reach + (i + 0.5) * step, y = -reach + (j + 0.5) * step;
                const double d = kernel.evaluate(x, y) - kernel.evaluate(x + ax, y + ay);
                sum += d * d;
            }
        return 0.5 * sum * step * step;
    };
    const auto& p = kernel.params();
    const bool isotropic = !kernel.is_grid() && p.aspect == 1.0 && !kernel.has_carrier();
    if (isotropic) return at(std::hypot(tx, ty), 0.0);
    if (!random_orientation) return at(tx, ty);
    // A kernel rotated by theta has gamma_theta(tau) = gamma_0(R_-theta tau); gamma_0 is even,
    // so the average over theta in [0, 2 pi) is the average over [0, pi).
    constexpr int kAngles = 36;
    double sum = 0.0;
    for (int m = 0; m < kAngles; ++m) {
        const double a = std::numbers::pi * (m + 0.5) / kAngles;
        const double c = std::cos(a), s = std::sin(a);
        sum += at(c * tx + s * ty, -s * tx + c * ty);
    }
    return sum / kAngles;
}

}  // namespace impulse::scenes::detail
