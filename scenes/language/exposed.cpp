// SPDX-License-Identifier: Apache-2.0
// The numeric keys a scene exposes as sliders (scenes/exposed.h), read from the scene file and
// the files it includes with toml++.

#include "scenes/exposed.h"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>

#include "numeric/errors.h"

namespace impulse::scenes {
namespace {

namespace fs = std::filesystem;

/// The files `root` (the document of `file`) names in `include`, resolved as the loader does:
/// relative to the including file's directory.
std::vector<fs::path> includes_of(const toml::table& root, const fs::path& file) {
    std::vector<fs::path> out;
    const auto add = [&](const toml::node& n) {
        if (const auto s = n.value<std::string>()) {
            const fs::path p(*s);
            out.push_back(p.is_absolute() ? p : (file.parent_path() / p).lexically_normal());
        }
    };
    if (const toml::node* n = root.get("include")) {
        if (const toml::array* a = n->as_array())
            for (const auto& e : *a) add(e);
        else
            add(*n);
    }
    return out;
}

/// The node at `key` (dotted, array elements by index: layer.0.kernel.radius) in `root`, or
/// null.
const toml::node* find_key(const toml::table& root, const std::string& key) {
    const toml::node* n = &root;
    size_t start = 0;
    while (n) {
        const size_t dot = std::min(key.find('.', start), key.size());
        const std::string part = key.substr(start, dot - start);
        size_t index = 0;
        const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), index);
        const bool is_index = ec == std::errc() && end == part.data() + part.size();
        if (const toml::array* a = n->as_array())
            n = is_index ? a->get(index) : nullptr;
        else if (const toml::table* t = n->as_table())
            n = t->get(part);
        else
            n = nullptr;
        if (dot == key.size()) return n;
        start = dot + 1;
    }
    return nullptr;
}

/// The node at `key` in the scene file or, failing that, in the files it includes (the later
/// ones first: they override the earlier). `doc` keeps the document holding it.
const toml::node* lookup(const fs::path& file, const std::string& key, toml::table& doc,
                         int depth = 0) {
    doc = toml::parse_file(file.string());
    if (const toml::node* n = find_key(doc, key)) return n;
    if (depth >= 16) return nullptr;
    const std::vector<fs::path> inc = includes_of(doc, file);
    for (size_t i = inc.size(); i-- > 0;) {
        toml::table sub;
        if (lookup(inc[i], key, sub, depth + 1)) {
            doc = std::move(sub);
            return find_key(doc, key);
        }
    }
    return nullptr;
}

double parse_bound(const std::string& spec, const std::string& text) {
    double v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v))
        throw ValueError("--expose " + spec + ": expected KEY or KEY=LO:HI with numbers LO < HI");
    return v;
}

Exposed exposed_key(const fs::path& file, const std::string& spec) {
    Exposed e;
    const size_t eq = spec.find('=');
    e.key = spec.substr(0, eq);
    toml::table doc;
    const toml::node* n = nullptr;
    try {
        n = lookup(file, e.key, doc);
    } catch (const toml::parse_error& err) {
        throw ValueError("--expose " + e.key + ": " + file.string() +
                         " does not parse: " + std::string(err.description()));
    }
    if (!n || !(n->is_integer() || n->is_floating_point()))
        throw ValueError("--expose " + e.key + ": " +
                         (n ? "not a number in the scene file" : "not set in the scene file") +
                         ": expected a numeric key written in the scene (e.g. "
                         "layer.0.kernel.radius)");
    e.integer = n->is_integer();
    e.value = n->value<double>().value_or(0.0);
    if (eq != std::string::npos) {
        const std::string range = spec.substr(eq + 1);
        const size_t colon = range.find(':');
        if (colon == std::string::npos) parse_bound(spec, "");
        e.lo = parse_bound(spec, range.substr(0, colon));
        e.hi = parse_bound(spec, range.substr(colon + 1));
        if (!(e.lo < e.hi)) parse_bound(spec, "");
    } else {
        // From 0 to twice the value (or from twice a negative value to 0); around 0, [-1, 1].
        e.lo = e.value == 0 ? -1.0 : e.value > 0 ? 0.0 : 2 * e.value;
        e.hi = e.value == 0 ? 1.0 : e.value > 0 ? 2 * e.value : 0.0;
    }
    e.step = e.integer ? 1.0 : (e.hi - e.lo) / 200.0;
    return e;
}

}  // namespace

std::vector<Exposed> exposed_keys(const std::string& path, const std::vector<std::string>& specs) {
    std::vector<Exposed> out;
    for (const std::string& s : specs) out.push_back(exposed_key(path, s));
    return out;
}

void reread_exposed(const std::string& path, std::vector<Exposed>& exposed) {
    for (Exposed& e : exposed) {
        try {
            toml::table doc;
            const toml::node* n = lookup(path, e.key, doc);
            if (n && (n->is_integer() || n->is_floating_point()))
                e.value = n->value<double>().value_or(e.value), e.moved = false;
        } catch (const std::exception&) {
            // Malformed or gone: the loader reports it; the slider keeps its value.
        }
    }
}

std::string toml_number(double v, bool integer) {
    if (integer) return std::to_string(std::llround(v));
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, v);
    std::string s(buf, r.ptr);
    if (s.find_first_of(".eni") == std::string::npos) s += ".0";
    return s;
}

std::string toml_line(const Exposed& e) {
    // layer.0.kernel.radius -> "radius = 8.5  # in [layer.kernel] of [[layer]] 0";
    // layer.0.density -> "density = 12.0  # in [[layer]] 0"; output.fps -> "... # in [output]".
    std::vector<std::string> parts;
    for (size_t start = 0;;) {
        const size_t dot = e.key.find('.', start);
        parts.push_back(e.key.substr(start, dot == std::string::npos ? dot : dot - start));
        if (dot == std::string::npos) break;
        start = dot + 1;
    }
    const auto is_index = [](const std::string& p) {
        return !p.empty() && std::all_of(p.begin(), p.end(), ::isdigit);
    };
    std::string prefix, header;
    std::vector<std::string> arrays;  // "[[layer]] 0", outermost first
    for (size_t i = 0; i + 1 < parts.size(); ++i) {
        if (is_index(parts[i])) continue;
        prefix += (prefix.empty() ? "" : ".") + parts[i];
        if (i + 2 < parts.size() && is_index(parts[i + 1]))
            arrays.push_back("[[" + prefix + "]] " + parts[i + 1]);
        header =
            i + 2 < parts.size() && is_index(parts[i + 1]) ? arrays.back() : "[" + prefix + "]";
    }
    std::string line = parts.back() + " = " + toml_number(e.value, e.integer);
    if (header.empty()) return line;
    line += "  # in " + header;
    for (size_t i = arrays.size(); i-- > 0;)
        if (arrays[i] != header) line += " of " + arrays[i];
    return line;
}

std::vector<std::string> scene_includes(const std::string& path) {
    std::vector<std::string> out;
    const toml::table root = toml::parse_file(path);
    for (const fs::path& p : includes_of(root, fs::path(path))) out.push_back(p.string());
    return out;
}

}  // namespace impulse::scenes
