// SPDX-License-Identifier: Apache-2.0
// OBJ vertex for vertex (docs/mesh.md "Formats"): the reader keeps the `v` lines' order and
// number, the writer writes the Mesh's vertices in order.

#include "mesh/detail/obj_format.h"

#include <charconv>
#include <cstdio>
#include <string_view>
#include <vector>

#include "numeric/errors.h"

namespace impulse::mesh {
namespace {

constexpr int64_t kNone = -1;      // a vertex no corner gave this attribute
constexpr int64_t kConflict = -2;  // corners of one vertex gave two different ones

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> tokens;
    size_t at = 0;
    while (at < line.size()) {
        const size_t start = line.find_first_not_of(" \t\r", at);
        if (start == std::string_view::npos) break;
        const size_t end = std::min(line.find_first_of(" \t\r", start), line.size());
        tokens.push_back(line.substr(start, end - start));
        at = end;
    }
    return tokens;
}

/// One corner of an `f`, `l` or `p` record: 0-based indices, kNone where absent.
struct Corner {
    int64_t v = kNone, vt = kNone, vn = kNone;
};

class ObjReader {
public:
    explicit ObjReader(const std::string& path) : m_path(path) {}

    Mesh read(const std::string& text) {
        size_t at = 0;
        while (at < text.size()) {
            const size_t end = std::min(text.find('\n', at), text.size());
            ++m_line;
            record(split(std::string_view(text).substr(at, end - at)));
            at = end + 1;
        }
        return finish();
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw ValueError(m_path + ":" + std::to_string(m_line) + ": " + what);
    }

    void record(const std::vector<std::string_view>& t) {
        if (t.empty()) return;
        if (t[0] == "v") vertex(t);
        else if (t[0] == "vt") m_uvs.push_back(numbers(t, 1, 3, "vt: expected u [v [w]]").head<2>());
        else if (t[0] == "vn") m_normals.push_back(numbers(t, 3, 3, "vn: expected x y z"));
        else if (t[0] == "f") polygon(t);
        else if (t[0] == "l") polyline(t);
        else if (t[0] == "p") points(t);
        // Comments, groups, materials, smoothing and free-form records carry no vertex.
    }

    /// Up to `most` numbers after the keyword, at least `least`; missing ones are 0.
    Eigen::Vector3f numbers(const std::vector<std::string_view>& t, size_t least, size_t most,
                            const char* expected) const {
        if (t.size() < least + 1 || t.size() > most + 1) fail(expected);
        Eigen::Vector3f v = Eigen::Vector3f::Zero();
        for (size_t k = 1; k < t.size(); ++k) v[int(k - 1)] = number(t[k], expected);
        return v;
    }

    float number(std::string_view s, const char* expected) const {
        float x = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
        if (ec != std::errc() || end != s.data() + s.size())
            fail(std::string(s) + ": " + expected);
        return x;
    }

    /// `v x y z`, `v x y z w` (w ignored) or `v x y z r g b` (a vertex colour).
    void vertex(const std::vector<std::string_view>& t) {
        const char* expected = "v: expected x y z [w] or x y z r g b";
        if (t.size() != 4 && t.size() != 5 && t.size() != 7) fail(expected);
        const std::vector<std::string_view> xyz(t.begin(), t.begin() + 4);
        m_positions.push_back(numbers(xyz, 3, 3, expected));
        if (t.size() == 7) {
            const std::vector<std::string_view> rgb = {t[0], t[4], t[5], t[6]};
            m_colors.push_back(numbers(rgb, 3, 3, expected));
        }
        m_vertex_vt.push_back(kNone);
        m_vertex_vn.push_back(kNone);
    }

    /// A 1-based index, or negative counting back from the last one read; 0-based result.
    int64_t index(std::string_view s, size_t count, const char* what) const {
        long long i = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
        const auto n = static_cast<long long>(count);
        if (ec == std::errc() && end == s.data() + s.size()) {
            if (i >= 1 && i <= n) return i - 1;
            if (i < 0 && i >= -n) return n + i;
        }
        const std::string bad = std::string(what) + " index " + std::string(s);
        if (n == 0) fail(bad + ": no " + what + " line above it");
        fail(bad + ": expected 1.." + std::to_string(n) + " or -" + std::to_string(n) + "..-1 (the " + what +
             " lines above it)");
    }

    Corner corner(std::string_view token) {
        Corner c;
        const size_t s1 = token.find('/');
        c.v = index(token.substr(0, s1), m_positions.size(), "v");
        if (s1 == std::string_view::npos) return c;
        const size_t s2 = token.find('/', s1 + 1);
        const std::string_view vt = token.substr(s1 + 1, s2 == std::string_view::npos ? s2 : s2 - s1 - 1);
        if (!vt.empty()) c.vt = index(vt, m_uvs.size(), "vt");
        if (s2 != std::string_view::npos) c.vn = index(token.substr(s2 + 1), m_normals.size(), "vn");
        note(m_vertex_vt[size_t(c.v)], c.vt);
        note(m_vertex_vn[size_t(c.v)], c.vn);
        return c;
    }

    /// A vertex keeps one attribute index; a second, different one (a UV seam, a hard edge)
    /// means the file's attribute is per corner, not per vertex.
    static void note(int64_t& held, int64_t seen) {
        if (held == kNone) held = seen == kNone ? kConflict : seen;
        else if (held != seen) held = kConflict;
    }

    std::vector<uint32_t> corners(const std::vector<std::string_view>& t, size_t least, const char* expected) {
        if (t.size() < least + 1) fail(expected);
        std::vector<uint32_t> v;
        for (size_t k = 1; k < t.size(); ++k) v.push_back(uint32_t(corner(t[k]).v));
        return v;
    }

    void polygon(const std::vector<std::string_view>& t) {
        const std::vector<uint32_t> v = corners(t, 3, "f: expected at least 3 vertices");
        m_mesh.indices.insert(m_mesh.indices.end(), v.begin(), v.end());
        m_mesh.face_sizes.push_back(uint32_t(v.size()));
    }

    void polyline(const std::vector<std::string_view>& t) {
        const std::vector<uint32_t> v = corners(t, 2, "l: expected at least 2 vertices");
        for (size_t k = 0; k + 1 < v.size(); ++k) m_mesh.add_face({v[k], v[k + 1]});
    }

    void points(const std::vector<std::string_view>& t) {
        for (const uint32_t v : corners(t, 1, "p: expected at least 1 vertex")) m_mesh.add_face({v});
    }

    /// The attribute per vertex when every vertex has exactly one, else none.
    template <class T>
    static std::vector<T> per_vertex(const std::vector<T>& values, const std::vector<int64_t>& held) {
        std::vector<T> out;
        for (const int64_t i : held)
            if (i < 0) return {};
        for (const int64_t i : held) out.push_back(values[size_t(i)]);
        return out;
    }

    Mesh finish() {
        m_mesh.positions = std::move(m_positions);
        m_mesh.normals = per_vertex(m_normals, m_vertex_vn);
        m_mesh.uvs = per_vertex(m_uvs, m_vertex_vt);
        if (m_colors.size() == m_mesh.positions.size()) m_mesh.colors = std::move(m_colors);
        return std::move(m_mesh);
    }

    std::string m_path;
    size_t m_line = 0;
    std::vector<Vec3> m_positions, m_colors, m_normals;
    std::vector<Vec2> m_uvs;
    std::vector<int64_t> m_vertex_vt, m_vertex_vn;
    Mesh m_mesh;
};

void append_numbers(std::string& out, const char* keyword, std::initializer_list<float> values) {
    char buffer[32];
    out += keyword;
    for (const float x : values) {
        std::snprintf(buffer, sizeof buffer, " %.9g", double(x));  // 9 digits: floats round-trip
        out += buffer;
    }
    out += '\n';
}

std::string corner_token(uint32_t v, bool uvs, bool normals) {
    const std::string i = std::to_string(v + 1);
    if (normals) return i + "/" + (uvs ? i : "") + "/" + i;
    return uvs ? i + "/" + i : i;
}

void append_faces(std::string& out, const Mesh& m) {
    const bool uvs = !m.uvs.empty(), normals = !m.normals.empty();
    size_t at = 0;
    for (const uint32_t size : m.face_sizes) {
        out += size == 1 ? "p" : size == 2 ? "l" : "f";
        for (uint32_t k = 0; k < size; ++k)
            out += " " + (size < 3 ? std::to_string(m.indices[at + k] + 1) : corner_token(m.indices[at + k], uvs, normals));
        out += '\n';
        at += size;
    }
}

}  // namespace

Mesh parse_obj(const std::string& text, const std::string& path) { return ObjReader(path).read(text); }

std::string encode_obj(const Mesh& m) {
    std::string out = "# impulse: " + std::to_string(m.vertex_count()) + " vertices, " +
                      std::to_string(m.face_count()) + " faces\n";
    for (size_t v = 0; v < m.vertex_count(); ++v) {
        const Vec3& p = m.positions[v];
        if (m.colors.empty()) append_numbers(out, "v", {p.x(), p.y(), p.z()});
        else append_numbers(out, "v", {p.x(), p.y(), p.z(), m.colors[v].x(), m.colors[v].y(), m.colors[v].z()});
    }
    for (const Vec2& t : m.uvs) append_numbers(out, "vt", {t.x(), t.y()});
    for (const Vec3& n : m.normals) append_numbers(out, "vn", {n.x(), n.y(), n.z()});
    append_faces(out, m);
    return out;
}

}  // namespace impulse::mesh
