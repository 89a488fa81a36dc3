// SPDX-License-Identifier: Apache-2.0
#include "scenes/detail/reader.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <map>
#include <sstream>

#include "numeric/errors.h"

namespace impulse::scenes::detail {

size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::optional<std::string> nearest(std::string_view word, const std::vector<std::string>& cands) {
    std::optional<std::string> best;
    size_t best_d = std::max<size_t>(2, word.size() / 3) + 1;
    for (const auto& c : cands) {
        const size_t d = edit_distance(word, c);
        if (d < best_d) best_d = d, best = c;
    }
    return best;
}

std::string value_text(const toml::node& n) {
    // Compact, as a person would write it: 0.2 not 0.20000000000000001, [0, 64] not [ 0, 64 ].
    std::ostringstream s;
    if (auto v = n.as_string()) {
        s << '"' << v->get() << '"';
    } else if (auto f = n.as_floating_point()) {
        s << f->get();
    } else if (auto a = n.as_array()) {
        s << '[';
        for (size_t i = 0; i < a->size(); ++i) s << (i ? ", " : "") << value_text((*a)[i]);
        s << ']';
    } else if (n.is_table()) {
        s << "{...}";
    } else {
        n.visit([&](auto&& x) { s << x; });
    }
    std::string t = s.str();
    std::replace(t.begin(), t.end(), '\n', ' ');
    return t;
}

std::string type_name(const toml::node& n) {
    switch (n.type()) {
        case toml::node_type::table: return "table";
        case toml::node_type::array: return "array";
        case toml::node_type::string: return "string";
        case toml::node_type::integer: return "integer";
        case toml::node_type::floating_point: return "float";
        case toml::node_type::boolean: return "boolean";
        default: return "date/time";
    }
}

namespace {

/// The file a node or key was written in: its own (an included file), else the scene's.
std::string file_of(const toml::source_region& src, const Source& source) {
    return src.path && !src.path->empty() ? *src.path : source.file;
}

/// A table of the form { keys = ..., ease = ... } (a keyframe table).
bool is_keyframe_table(const toml::node* n) {
    const toml::table* t = n ? n->as_table() : nullptr;
    return t && t->contains("keys");
}

/// "layer[0].flow[1].scale" -> "layer.flow.scale"
std::string without_indices(std::string_view path) {
    std::string out;
    bool in_index = false;
    for (char c : path) {
        if (c == '[') in_index = true;
        if (!in_index) out += c;
        if (c == ']') in_index = false;
    }
    return out;
}

}  // namespace

std::string structural_reason(std::string_view path) {
    // Keys that cannot vary in time, and why (docs/scenes.md "Keyframes"). Keys not listed are
    // refused with the generic reason at the end.
    static const std::map<std::string, std::string, std::less<>> reasons = {
        {"seed", "the seed picks every impulse once, for the whole animation"},
        {"output.size", "the frame size is the same in every frame of an output"},
        {"output.frames", "it is the length of the output"},
        {"output.fps", "it sets the time of every frame"},
        {"output.start", "it sets the time of every frame"},
        {"output.crf", "the video is encoded at one quality"},
        {"output.bits", "the files of an output have one format"},
        {"output.range", "the display mapping is the same in every frame"},
        {"shading.toe", "the tone curve is the same in every frame"},
        {"shading.shoulder", "the tone curve is the same in every frame"},
        {"limits.max_impulses", "a limit is checked once, when the scene loads"},
        {"limits.max_memory_mib", "a limit is checked once, when the scene loads"},
        {"limits.max_pixel_evaluations", "a limit holds for the whole render"},
        {"limits.max_flow_steps", "a limit is checked once, when the scene loads"},
        {"camera.center", "a pair is fixed: keyframe center_x and center_y"},
        {"camera.position", "a pair is fixed: keyframe position_x and position_y"},
        {"camera.filter", "the anti-aliasing pyramid and its fade are set up once per scene"},
        {"camera.cutoff", "the anti-aliasing pyramid and its fade are set up once per scene"},
        {"camera.anisotropic", "the anti-aliasing pyramid and its fade are set up once per scene"},
        {"layer.seed", "the seed picks every impulse once, for the whole animation"},
        {"layer.period", "the domain is periodic with one period (its seeding cells wrap)"},
        {"layer.lifetime",
         "every impulse lives this long; the births' time cells and envelope are built on it"},
        {"layer.loop", "the births repeat with one period"},
        {"layer.substeps",
         "the flow is integrated on one global time grid, so frames do not depend on the "
         "order they are rendered in"},
        {"layer.max_travel", "a limit is checked once, when the scene loads"},
        {"layer.flow.center", "a pair is fixed: keyframe center_x and center_y"},
        {"layer.flow.velocity", "a pair is fixed: keyframe vx and vy"},
        {"layer.flow.scale", "the curl noise's potential lattice is built on it"},
        {"layer.flow.seed", "the seed picks the flow's impulses once, for the whole animation"},
        {"layer.flow.spacing", "the image is placed once: its pixels are the field's samples"},
        {"layer.flow.origin", "the image is placed once: its pixels are the field's samples"},
        {"layer.orientation.center", "a pair is fixed: keyframe center_x and center_y"},
        {"layer.orientation.spacing",
         "the image is placed once: its pixels are the field's samples"},
        {"layer.orientation.origin",
         "the field is placed once (to move sine waves along, keyframe phase)"},
        {"shading.light", "a pair is fixed: keyframe light_azimuth and light_elevation"},
        {"shading.ramp.stops", "the ramp is built once from the image"},
    };
    const auto it = reasons.find(without_indices(path));
    if (it != reasons.end()) return it->second;
    return "it is structural (docs/scenes.md lists the keys that can vary)";
}

std::filesystem::path resolve_path(const toml::node* n, const std::string& rel,
                                   const std::filesystem::path& base) {
    namespace fs = std::filesystem;
    if (fs::path(rel).is_absolute()) return rel;
    if (n && n->source().path && !n->source().path->empty())
        return fs::path(*n->source().path).parent_path() / rel;
    return base / rel;
}

void Reader::refuse_keyframes(std::string_view key) {
    const toml::node* n = node(key);
    if (!is_keyframe_table(n)) return;
    fail(n, key,
         "cannot vary in time: " + (!m_structural.empty() ? m_structural : structural_reason(key_path(key))));
}

Reader::Reader(const toml::table& table, std::string path, const Source& source,
               const toml::node* self)
    : m_table(table), m_path(std::move(path)), m_source(source), m_self(self ? self : &table) {}

std::string Reader::key_path(std::string_view key) const {
    return m_path.empty() ? std::string(key) : m_path + "." + std::string(key);
}

bool Reader::has(std::string_view key) {
    m_known.insert(std::string(key));
    return m_table.contains(key);
}

const toml::node* Reader::node(std::string_view key) {
    m_known.insert(std::string(key));
    return m_table.get(key);
}

std::string Reader::location(const toml::node* n, std::string_view key) const {
    // The value, or a table containing it, may come from a --set override.
    for (std::string path = key_path(key);;) {
        auto it = m_source.overrides.find(path);
        if (it != m_source.overrides.end()) return "--set " + it->second;
        const size_t dot = path.rfind('.');
        if (dot == std::string::npos) break;
        path.resize(dot);
    }
    const toml::node* at = n ? n : m_self;
    const auto& src = at->source();
    std::ostringstream s;
    s << file_of(src, m_source);
    if (src.begin.line) s << ':' << src.begin.line << ':' << src.begin.column;
    return s.str();
}

std::string Reader::describe(const toml::node* n, std::string_view key) const {
    std::ostringstream s;
    s << location(n, key) << ": " << key_path(key);
    // Tables and lists of tables are pointed at, not printed.
    const bool composite = n && (n->is_table() || (n->is_array() && n->as_array()->is_array_of_tables()));
    if (n && !composite) s << " = " << value_text(*n);
    return s.str();
}

void Reader::fail(const toml::node* n, std::string_view key, const std::string& what) const {
    throw SceneError(describe(n, key) + ": " + what);
}

void Reader::warn(std::string_view key, const std::string& what) const {
    if (!m_source.warnings) return;
    const toml::node* n = m_table.get(key);
    m_source.warnings->push_back(location(n, key) + ": warning: " + key_path(key) + ": " + what);
}

double Reader::number(std::string_view key, double fallback) {
    refuse_keyframes(key);
    const toml::node* n = node(key);
    if (!n) return fallback;
    if (!n->is_number()) fail(n, key, "expected a number, found " + type_name(*n));
    const double v = n->value<double>().value_or(0.0);
    if (!std::isfinite(v)) fail(n, key, "expected a finite number");
    return v;
}

double Reader::number(std::string_view key, double fallback, const std::function<bool(double)>& ok,
                      const char* expected) {
    const double v = number(key, fallback);
    if (m_table.contains(key) && ok && !ok(v)) fail(node(key), key, std::string("expected ") + expected);
    return v;
}

int64_t Reader::integer(std::string_view key, int64_t fallback, int64_t lo, int64_t hi) {
    refuse_keyframes(key);
    const toml::node* n = node(key);
    if (!n) return fallback;
    if (!n->is_integer()) fail(n, key, "expected an integer, found " + type_name(*n));
    const int64_t v = n->value<int64_t>().value_or(0);
    if (v < lo || v > hi)
        fail(n, key, hi == INT64_MAX ? "expected an integer >= " + std::to_string(lo)
                                     : "expected an integer in [" + std::to_string(lo) + ", " +
                                           std::to_string(hi) + "]");
    return v;
}

bool Reader::boolean(std::string_view key, bool fallback) {
    refuse_keyframes(key);
    const toml::node* n = node(key);
    if (!n) return fallback;
    if (!n->is_boolean()) fail(n, key, "expected true or false, found " + type_name(*n));
    return n->value<bool>().value_or(fallback);
}

std::string Reader::string(std::string_view key, const std::string& fallback) {
    const toml::node* n = node(key);
    if (!n) return fallback;
    if (!n->is_string()) fail(n, key, "expected a string, found " + type_name(*n));
    return std::string(n->value<std::string_view>().value_or(""));
}

size_t Reader::choice_impl(std::string_view key, const std::vector<std::string_view>& names,
                           size_t fallback) {
    const toml::node* n = node(key);
    if (!n) return fallback;
    if (!n->is_string()) fail(n, key, "expected a string, found " + type_name(*n));
    const std::string v = string(key, "");
    for (size_t i = 0; i < names.size(); ++i)
        if (names[i] == v) return i;
    std::string list;
    for (size_t i = 0; i < names.size(); ++i) list += (i ? ", " : "") + std::string(names[i]);
    fail(n, key, "expected one of " + list);
}

std::optional<std::array<double, 2>> Reader::pair(std::string_view key, const char* expected,
                                                  const std::function<bool(double)>& ok) {
    refuse_keyframes(key);
    const toml::node* n = node(key);
    if (!n) return std::nullopt;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number())
        fail(n, key, std::string("expected ") + expected);
    std::array<double, 2> v{(*a)[0].value<double>().value_or(0), (*a)[1].value<double>().value_or(0)};
    for (double x : v)
        if (!std::isfinite(x) || (ok && !ok(x))) fail(n, key, std::string("expected ") + expected);
    return v;
}

numeric::Keyframed Reader::keyframed(std::string_view key, double fallback,
                                 const std::function<bool(double)>& ok, const char* expected) {
    const toml::node* n = node(key);
    if (!n) return numeric::Keyframed(fallback);
    // A bad value is reported at itself: the number, or the [t, v] key holding it.
    auto check = [&](double v, const Reader& at, const toml::node* where, std::string_view k) {
        if (!std::isfinite(v)) at.fail(where, k, "expected a finite number");
        if (ok && !ok(v)) at.fail(where, k, std::string("expected ") + expected);
    };
    if (n->is_number()) {
        const double v = n->value<double>().value_or(0);
        check(v, *this, n, key);
        return numeric::Keyframed(v);
    }
    const toml::table* t = n->as_table();
    if (!t)
        fail(n, key, "expected a number or keyframes { keys = [[t, v], ...] }, found " +
                         type_name(*n));
    Reader r(*t, key_path(key), m_source, n);
    numeric::Keyframed k;
    k.ease = static_cast<numeric::Ease>(r.choice("ease", numeric::kEaseNames, 0));
    const toml::node* kn = r.node("keys");
    const toml::array* ka = kn ? kn->as_array() : nullptr;
    if (!ka || ka->empty()) r.fail(kn, "keys", "expected a non-empty array of [time_s, value] pairs");
    for (const auto& e : *ka) {
        const toml::array* p = e.as_array();
        if (!p || p->size() != 2 || !(*p)[0].is_number() || !(*p)[1].is_number())
            r.fail(&e, "keys", "expected [time_s, value] pairs of numbers");
        const double t_s = (*p)[0].value<double>().value_or(0), v = (*p)[1].value<double>().value_or(0);
        if (!std::isfinite(t_s)) r.fail(&e, "keys", "expected finite key times");
        check(v, r, &e, "keys");
        if (!k.keys.empty() && !(t_s > k.keys.back().first)) {
            std::ostringstream s;
            s << "keyframes out of order: time " << t_s << " follows " << k.keys.back().first
              << " (times must increase)";
            r.fail(&e, "keys", s.str());
        }
        k.keys.emplace_back(t_s, v);
    }
    r.finish();
    return k;
}

std::optional<Reader> Reader::table(std::string_view key) {
    const toml::node* n = node(key);
    if (!n) return std::nullopt;
    const toml::table* t = n->as_table();
    if (!t) fail(n, key, "expected a table, found " + type_name(*n));
    return Reader(*t, key_path(key), m_source, n);
}

std::vector<Reader> Reader::tables(std::string_view key) {
    std::vector<Reader> out;
    const toml::node* n = node(key);
    if (!n) return out;
    if (const toml::table* t = n->as_table()) {  // a single [layer] table is one layer
        out.emplace_back(*t, key_path(key) + "[0]", m_source, n);
        return out;
    }
    const toml::array* a = n->as_array();
    if (!a) fail(n, key, "expected an array of tables ([[" + std::string(key) + "]]), found " + type_name(*n));
    for (size_t i = 0; i < a->size(); ++i) {
        const toml::table* t = (*a)[i].as_table();
        if (!t) fail(&(*a)[i], key, "expected tables in [[" + std::string(key) + "]]");
        out.emplace_back(*t, key_path(key) + "[" + std::to_string(i) + "]", m_source, &(*a)[i]);
    }
    return out;
}

std::vector<double> key_check_times(const std::vector<const numeric::Keyframed*>& ks) {
    std::set<double> t = {0.0};
    double lo = 0.0, hi = 0.0;
    for (const auto* k : ks)
        for (const auto& key : k->keys) {
            t.insert(key.first);
            lo = std::min(lo, key.first), hi = std::max(hi, key.first);
        }
    for (int i = 0; i <= 64 && hi > lo; ++i) t.insert(lo + (hi - lo) * i / 64.0);
    return {t.begin(), t.end()};
}

void Reader::finish() const {
    std::vector<std::string> known(m_known.begin(), m_known.end());
    for (auto&& [k, v] : m_table) {
        if (m_known.count(k.str())) continue;
        std::ostringstream s;
        const auto& src = k.source().begin.line ? k.source() : v.source();
        auto it = m_source.overrides.find(key_path(k.str()));
        if (it != m_source.overrides.end())
            s << "--set " << it->second;
        else {
            s << file_of(src, m_source);
            if (src.begin.line) s << ':' << src.begin.line << ':' << src.begin.column;
        }
        s << ": unknown key \"" << k.str() << "\"" << (m_path.empty() ? "" : " in " + m_path);
        if (auto near = nearest(k.str(), known)) s << " (did you mean \"" << *near << "\"?)";
        else if (!known.empty()) {
            s << " (valid keys:";
            for (const auto& c : known) s << ' ' << c;
            s << ")";
        }
        throw SceneError(s.str());
    }
}

}  // namespace impulse::scenes::detail
