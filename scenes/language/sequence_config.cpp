// SPDX-License-Identifier: Apache-2.0
// [[layer.flow]] type = "sequence": a velocity sequence read from OpenVDB files or images with
// named channels (EXR), laid on texture space (docs/scenes.md "Velocity sequences"). The files
// are found and every frame checked as the scene loads; while rendering, sim's sequence flow
// asks the FrameSource below for the frames it needs.

#include <algorithm>
#include <cmath>
#include <climits>
#include <filesystem>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "numeric/errors.h"
#include "output/files.h"
#include "output/io_module.h"
#include "scenes/detail/loader.h"
#include "volume/flow.h"

namespace impulse::scenes::detail {
namespace {

namespace fs = std::filesystem;

/// The frame number's place in a file name: a run of '#' (one '#' is 4 digits) or %0Nd / %d.
struct FramePattern {
    std::string prefix, suffix;
    size_t digits = 4;
    bool found = false;
};

FramePattern parse_pattern(const std::string& name) {
    FramePattern p;
    const size_t hash = name.find('#');
    if (hash != std::string::npos) {
        size_t end = hash;
        while (end < name.size() && name[end] == '#') ++end;
        p = {name.substr(0, hash), name.substr(end), end - hash == 1 ? 4 : end - hash, true};
        return p;
    }
    const size_t pct = name.find('%');
    if (pct == std::string::npos) return p;
    size_t end = pct + 1, digits = 1;
    if (end < name.size() && name[end] == '0') {
        size_t w = end + 1;
        while (w < name.size() && std::isdigit(static_cast<unsigned char>(name[w]))) ++w;
        if (w > end + 1) digits = std::stoul(name.substr(end + 1, w - end - 1));
        end = w;
    }
    if (end < name.size() && name[end] == 'd') p = {name.substr(0, pct), name.substr(end + 1), digits, true};
    return p;
}

std::string frame_name(const FramePattern& p, int64_t n) {
    std::string d = std::to_string(n);
    if (d.size() < p.digits) d.insert(0, p.digits - d.size(), '0');
    return p.prefix + d + p.suffix;
}

/// The frame numbers whose files exist in `dir` for `p`, ascending.
std::vector<int64_t> frames_present(const fs::path& dir, const FramePattern& p) {
    std::vector<int64_t> out;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir.empty() ? fs::path(".") : dir, ec)) {
        const std::string name = e.path().filename().string();
        if (name.size() <= p.prefix.size() + p.suffix.size() || name.rfind(p.prefix, 0) != 0 ||
            name.compare(name.size() - p.suffix.size(), p.suffix.size(), p.suffix) != 0)
            continue;
        const std::string mid = name.substr(p.prefix.size(), name.size() - p.prefix.size() - p.suffix.size());
        if (mid.size() > 12 || !std::all_of(mid.begin(), mid.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
            continue;
        const int64_t n = std::stoll(mid);
        if (frame_name(p, n) == name) out.push_back(n);
    }
    std::sort(out.begin(), out.end());
    return out;
}

/// "1-11, 13-24": runs of consecutive frame numbers.
std::string runs_text(const std::vector<int64_t>& f) {
    std::ostringstream s;
    for (size_t i = 0; i < f.size();) {
        size_t j = i;
        while (j + 1 < f.size() && f[j + 1] == f[j] + 1) ++j;
        s << (i ? ", " : "") << f[i];
        if (j > i) s << "-" << f[j];
        i = j + 1;
    }
    return s.str();
}

/// How a 3-D field becomes a plane (docs/scenes.md "Velocity sequences").
enum class PlaneMode { Slice, Average, Project };
constexpr std::array<std::string_view, 3> kPlaneModeNames = {"slice", "average", "project"};
constexpr std::array<std::string_view, 3> kAxisNames = {"x", "y", "z"};

using Vec3 = std::array<double, 3>;
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross(const Vec3& a, const Vec3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 normalized(Vec3 a) {
    const double n = std::sqrt(dot(a, a));
    for (double& c : a) c /= n;
    return a;
}

/// Where the plane lies in the simulation's world and the grid it is sampled on: sample (i, j)
/// of the plane grid at world point origin + (a0 + i da) u + (b0 + j db) w (+ each depth in
/// `depths` along n, averaged).
struct PlaneGeometry {
    Vec3 u{1, 0, 0}, w{0, 1, 0}, n{0, 0, 1}, origin{0, 0, 0};
    double a0 = 0.5, b0 = 0.5, da = 1.0, db = 1.0;
    int width = 0, height = 0;
    std::vector<double> depths{0.0};
};

/// The geometry a frame of the sequence must share with the first.
struct FrameHeader {
    std::array<int, 3> size{}, origin{};
    std::array<double, 9> linear{};
    std::array<double, 3> translation{};
    bool operator==(const FrameHeader&) const = default;
};

/// The sequence's files and how to read each into a plane frame in texture units per second.
struct SequenceFiles {
    fs::path dir;
    FramePattern pattern;
    bool vdb = false;
    std::string grid;              ///< VDB grid
    std::array<int, 2> channel{};  ///< image channels (vx, vy)
    FrameHeader header;            ///< the first frame's
    std::string first_name;
    PlaneMode mode = PlaneMode::Slice;
    PlaneGeometry plane;
    std::array<double, 4> velocity{1, 0, 0, 1};  ///< plane (va, vb) to texture units per second
    std::string context;           ///< "scene:line:col: layer[0].flow[0].path = ...", for messages
    double max_divergence = 0.0;   ///< > 0: refuse a frame whose interpolant diverges more
    std::array<double, 4> to_index{};
    std::string divergence_context;

    [[noreturn]] void fail(const std::string& file, const std::string& what) const {
        throw SceneError(context + ": " + file + ": " + what);
    }
    /// Slice planes while rendering: the voxel layers the plane reads (and the next, for a
    /// staggered grid's averages), read alone; every frame was read whole and checked at load.
    std::optional<output::VdbIndexBox> slab;
    /// The box every frame is read over: the union of the frames' active voxels. A cache is
    /// sparse where its simulation is empty (Mantaflow's velocity is active where there is
    /// smoke), so its frames' boxes differ; the samples outside a frame's own are the
    /// background (docs/scenes.md "A Blender cache").
    output::VdbIndexBox whole;
    std::array<double, 3> velocity3{1, 1, 1};     ///< 3-D: per axis, to volume voxels per second
    std::array<double, 3> index_scale3{1, 1, 1};  ///< 3-D: d index / d voxel, per axis
    /// Refuses a frame whose interpolant's largest |div v|, `d`, is over max_divergence.
    void check_divergence(const std::string& file, double d) const;
    sim::PlaneFrame load(int64_t n) const;
    volume::VolumeFrame load_volume(int64_t n) const;
    output::VdbVectorGrid read_checked(const std::string& file) const;
    FrameHeader vdb_header(const output::VdbVectorGrid& g) const {
        return {g.size, g.origin, g.linear, g.translation};
    }
    sim::PlaneFrame plane_from_volume(output::VdbVectorGrid g) const;
    sim::PlaneFrame plane_from_image(const std::string& file) const;
};

/// An IoError's reason without the path it starts with (the message names the file itself).
std::string reason(const IoError& e, const fs::path& path) {
    const std::string what = e.what(), full = path.string() + ": ";
    return what.rfind(full, 0) == 0 ? what.substr(full.size()) : what;
}

/// The finite check of a frame's samples: fails naming the first that is not.
void check_finite(const SequenceFiles& s, const std::string& file, const std::vector<float>& v,
                  size_t stride, const std::array<int, 3>& size, const char* what) {
    for (size_t k = 0; k < v.size(); ++k)
        if (!std::isfinite(v[k])) {
            const size_t p = k / stride;
            std::ostringstream m;
            m << "found " << v[k] << " at " << what << " (" << p % size_t(size[0]) << ", "
              << (p / size_t(size[0])) % size_t(size[1]);
            if (size[2] > 1) m << ", " << p / (size_t(size[0]) * size_t(size[1]));
            m << "): expected finite velocities";
            s.fail(file, m.str());
        }
}

/// A staggered grid's components sit on the faces below each voxel (component c of voxel p at
/// p - e_c / 2): averaged to the voxel centres (the last voxel along c keeps its face value).
void stagger_to_centres(output::VdbVectorGrid& g) {
    const auto& n = g.size;
    auto at = [&](int i, int j, int k) { return (size_t(k) * n[1] + j) * n[0] + i; };
    std::vector<float> out = g.values;
    for (int k = 0; k < n[2]; ++k)
        for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
                const int next[3][3] = {{std::min(i + 1, n[0] - 1), j, k},
                                        {i, std::min(j + 1, n[1] - 1), k},
                                        {i, j, std::min(k + 1, n[2] - 1)}};
                for (int c = 0; c < 3; ++c) {
                    const size_t q = at(next[c][0], next[c][1], next[c][2]);
                    out[3 * at(i, j, k) + c] = 0.5f * (g.values[3 * at(i, j, k) + c] + g.values[3 * q + c]);
                }
            }
    g.values = std::move(out);
}

output::VdbVectorGrid SequenceFiles::read_checked(const std::string& file) const {
    output::VdbVectorGrid g;
    try {
        g = output::read_vdb_vectors((dir / file).string(), grid, slab ? &*slab : &whole);
    } catch (const IoError& e) {
        fail(file, reason(e, dir / file));
    }
    if (!slab && !(vdb_header(g) == header)) {
        std::ostringstream m;
        m << "grid \"" << grid << "\" covers " << g.size[0] << "x" << g.size[1] << "x" << g.size[2]
          << " voxels from (" << g.origin[0] << ", " << g.origin[1] << ", " << g.origin[2]
          << ") in its transform; the first frame " << first_name << " " << header.size[0] << "x"
          << header.size[1] << "x" << header.size[2] << " from (" << header.origin[0] << ", "
          << header.origin[1] << ", " << header.origin[2]
          << "): expected the same grid and transform in every frame";
        fail(file, m.str());
    }
    check_finite(*this, file, g.values, 3, g.size, "voxel");
    if (g.staggered) stagger_to_centres(g);
    return g;
}

sim::PlaneFrame SequenceFiles::plane_from_volume(output::VdbVectorGrid g) const {
    // The transform is axis-aligned (checked on the first frame): world_c = s_c index_c + t_c.
    const Vec3 s{g.linear[0], g.linear[4], g.linear[8]};
    const Vec3 t{g.translation[0], g.translation[1], g.translation[2]};
    // Coordinates are the whole grid's (header), samples g's, which may be a slab of it
    // (SequenceFiles::slab): the same arithmetic either way, so the same bits.
    const auto& N = header.size;
    const std::array<int, 3> from{g.origin[0] - header.origin[0], g.origin[1] - header.origin[1],
                                  g.origin[2] - header.origin[2]};
    auto sample = [&](const Vec3& X, Vec3& v) {  // trilinear; 0 outside the voxels' centres
        double f[3];
        int i0[3];
        for (int c = 0; c < 3; ++c) {
            const double q = (X[size_t(c)] - t[size_t(c)]) / s[size_t(c)] - header.origin[size_t(c)];
            if (!(q >= -1e-9 && q <= N[size_t(c)] - 1 + 1e-9)) return false;
            const double qc = std::clamp(q, 0.0, N[size_t(c)] - 1.0);
            i0[c] = std::min(static_cast<int>(qc), std::max(N[size_t(c)] - 2, 0));
            f[c] = qc - i0[c];
        }
        v = {0, 0, 0};
        for (int corner = 0; corner < 8; ++corner) {
            double wgt = 1.0;
            int idx[3];
            for (int c = 0; c < 3; ++c) {
                const int bit = (corner >> c) & 1;
                idx[c] = std::min(i0[c] + bit, N[size_t(c)] - 1);
                wgt *= bit ? f[c] : 1.0 - f[c];
            }
            if (wgt == 0.0) continue;
            const size_t k = 3 * ((size_t(idx[2] - from[2]) * g.size[1] + size_t(idx[1] - from[1])) * g.size[0] +
                                  size_t(idx[0] - from[0]));
            for (int c = 0; c < 3; ++c) v[size_t(c)] += wgt * g.values[k + size_t(c)];
        }
        return true;
    };
    const PlaneGeometry& P = plane;
    sim::PlaneFrame out;
    out.width = P.width, out.height = P.height;
    out.vx.resize(size_t(P.width) * P.height), out.vy.resize(out.vx.size());
    for (int j = 0; j < P.height; ++j)
        for (int i = 0; i < P.width; ++i) {
            const double a = P.a0 + i * P.da, b = P.b0 + j * P.db;
            double va = 0.0, vb = 0.0;
            for (double d : P.depths) {
                Vec3 X, v;
                for (int c = 0; c < 3; ++c)
                    X[size_t(c)] = P.origin[size_t(c)] + a * P.u[size_t(c)] + b * P.w[size_t(c)] + d * P.n[size_t(c)];
                if (!sample(X, v)) continue;
                va += dot(v, P.u), vb += dot(v, P.w);
            }
            va /= double(P.depths.size()), vb /= double(P.depths.size());
            const size_t k = size_t(j) * P.width + i;
            out.vx[k] = static_cast<float>(velocity[0] * va + velocity[1] * vb);
            out.vy[k] = static_cast<float>(velocity[2] * va + velocity[3] * vb);
        }
    return out;
}

sim::PlaneFrame SequenceFiles::plane_from_image(const std::string& file) const {
    output::Pixels px;
    std::string error;
    if (!output::read_pixels((dir / file).string(), px, error)) fail(file, error);
    if (px.width != header.size[0] || px.height != header.size[1] ||
        px.channels <= std::max(channel[0], channel[1])) {
        std::ostringstream m;
        m << "holds " << px.width << "x" << px.height << " pixels of " << px.channels
          << " channels; the first frame " << first_name << " " << header.size[0] << "x"
          << header.size[1] << ": expected the same size in every frame";
        fail(file, m.str());
    }
    sim::PlaneFrame out;
    out.width = px.width, out.height = px.height;
    const size_t n = size_t(px.width) * px.height, nc = size_t(px.channels);
    std::vector<float> ab(2 * n);
    for (size_t k = 0; k < n; ++k)
        ab[2 * k] = px.values[k * nc + size_t(channel[0])], ab[2 * k + 1] = px.values[k * nc + size_t(channel[1])];
    check_finite(*this, file, ab, 2, {px.width, px.height, 1}, "pixel");
    out.vx.resize(n), out.vy.resize(n);
    for (size_t k = 0; k < n; ++k) {
        out.vx[k] = static_cast<float>(velocity[0] * ab[2 * k] + velocity[1] * ab[2 * k + 1]);
        out.vy[k] = static_cast<float>(velocity[2] * ab[2 * k] + velocity[3] * ab[2 * k + 1]);
    }
    return out;
}

void SequenceFiles::check_divergence(const std::string& file, double d) const {
    if (d > max_divergence)
        throw SceneError(divergence_context + ": the velocity sequence diverges: |div v| reaches " +
                         num(d) + "/s in " + file + ", over the " + num(max_divergence) +
                         "/s that changes the variance by 1 % in a lifetime without sqrt(J): "
                         "expected jacobian = true");
}

sim::PlaneFrame SequenceFiles::load(int64_t n) const {
    const std::string file = frame_name(pattern, n);
    sim::PlaneFrame f;
    if (vdb) {
        f = plane_from_volume(read_checked(file));
    } else {
        f = plane_from_image(file);
    }
    if (max_divergence > 0.0) check_divergence(file, sim::max_interpolated_divergence(f, to_index));
    return f;
}

volume::VolumeFrame SequenceFiles::load_volume(int64_t n) const {
    const std::string file = frame_name(pattern, n);
    output::VdbVectorGrid g = read_checked(file);
    volume::VolumeFrame f;
    f.size = g.size;
    f.v = std::move(g.values);
    for (size_t k = 0; k < f.v.size(); ++k) f.v[k] = static_cast<float>(velocity3[k % 3] * f.v[k]);
    if (max_divergence > 0.0) check_divergence(file, volume::max_interpolated_divergence3(f, index_scale3));
    return f;
}

class FileFrames final : public sim::FrameSource {
public:
    explicit FileFrames(std::shared_ptr<const SequenceFiles> s) : m_s(std::move(s)) {}
    sim::PlaneFrame load(int64_t n) const override { return m_s->load(n); }

private:
    std::shared_ptr<const SequenceFiles> m_s;
};

/// The vector grids of a VDB file, and the one the scene names or the only one there is.
std::string choose_vdb_grid(Reader& f, const SequenceFiles& s, const std::string& file) {
    std::vector<output::VdbGridHeader> grids;
    try {
        grids = output::list_vdb_grids((s.dir / file).string());
    } catch (const IoError& e) {
        s.fail(file, reason(e, s.dir / file));
    }
    std::vector<std::string> vectors, names;
    for (const auto& g : grids) {
        names.push_back(g.name);
        if (g.type == "vec3s" || g.type == "vec3d") vectors.push_back(g.name);
    }
    if (f.has("grid")) {
        const std::string want = f.string("grid", "");
        for (const auto& g : grids)
            if (g.name == want) {
                if (g.type != "vec3s" && g.type != "vec3d")
                    f.fail(f.node("grid"), "grid", file + ": grid \"" + want + "\" holds " + g.type +
                                                       " values: expected a vector grid (vec3s)");
                return want;
            }
        std::string hint = "no such grid";
        if (auto near = nearest(want, names)) hint += " (did you mean \"" + *near + "\"?)";
        f.fail(f.node("grid"), "grid", file + ": " + hint + "; its vector grids: " +
                                           (vectors.empty() ? std::string("none") : [&] {
                                               std::string l;
                                               for (const auto& v : vectors) l += (l.empty() ? "" : ", ") + v;
                                               return l;
                                           }()));
    }
    if (vectors.size() == 1) return vectors[0];
    for (const char* usual : {"velocity", "vel", "v"})
        if (std::count(vectors.begin(), vectors.end(), usual)) return usual;
    std::string l;
    for (const auto& v : vectors) l += (l.empty() ? "" : ", ") + v;
    s.fail(file, vectors.empty() ? "no vector grid (vec3s) in the file: expected a velocity grid"
                                 : "several vector grids (" + l + "): set grid to one of them");
}

/// The (vx, vy) channels of an image: `channels = [x, y]`, or the layer `grid` (grid.x,
/// grid.y), or the only layer with .x and .y channels.
std::array<int, 2> choose_channels(Reader& f, const SequenceFiles& s, const std::string& file,
                                   const std::vector<std::string>& names) {
    auto index = [&](const std::string& c) {
        const auto it = std::find(names.begin(), names.end(), c);
        return it == names.end() ? -1 : int(it - names.begin());
    };
    auto list = [&] {
        std::string l;
        for (const auto& n : names) l += (l.empty() ? "" : ", ") + n;
        return l;
    };
    if (const toml::node* n = f.node("channels")) {
        const auto* a = n->as_array();
        if (!a || a->size() != 2 || !(*a)[0].is_string() || !(*a)[1].is_string())
            f.fail(n, "channels", "expected two channel names [vx, vy]");
        std::array<int, 2> out{};
        for (size_t c = 0; c < 2; ++c) {
            const std::string name = *(*a)[c].value<std::string>();
            out[c] = index(name);
            if (out[c] < 0) {
                std::string hint;
                if (auto near = nearest(name, names)) hint = " (did you mean \"" + *near + "\"?)";
                f.fail(n, "channels", file + ": no channel \"" + name + "\"" + hint + "; its channels: " + list());
            }
        }
        return out;
    }
    std::vector<std::string> layers;
    for (const auto& c : names)
        if (c.size() > 2 && c.compare(c.size() - 2, 2, ".x") == 0 &&
            index(c.substr(0, c.size() - 2) + ".y") >= 0)
            layers.push_back(c.substr(0, c.size() - 2));
    std::string layer;
    if (f.has("grid")) {
        layer = f.string("grid", "");
        if (!std::count(layers.begin(), layers.end(), layer)) {
            std::string hint;
            if (auto near = nearest(layer, layers)) hint = " (did you mean \"" + *near + "\"?)";
            f.fail(f.node("grid"), "grid", file + ": no channels " + layer + ".x, " + layer + ".y" +
                                               hint + "; its channels: " + list());
        }
    } else if (layers.size() == 1) {
        layer = layers[0];
    } else {
        for (const char* usual : {"velocity", "vel", "v"})
            if (std::count(layers.begin(), layers.end(), usual)) layer = usual;
        if (layer.empty())
            s.fail(file, (layers.empty() ? std::string("no channels NAME.x, NAME.y")
                                         : "several vector layers") +
                             " among " + list() + ": set grid = NAME or channels = [vx, vy]");
    }
    return {index(layer + ".x"), index(layer + ".y")};
}

/// The plane of a 3-D field: the mode, axis or normal and height read from `f`, the grid laid
/// on the first frame's voxels.
PlaneGeometry read_plane(Reader& f, const SequenceFiles& s, const output::VdbVectorGrid& g,
                         PlaneMode mode) {
    const Vec3 sc{g.linear[0], g.linear[4], g.linear[8]};
    const Vec3 lo{sc[0] * g.origin[0] + g.translation[0], sc[1] * g.origin[1] + g.translation[1],
                  sc[2] * g.origin[2] + g.translation[2]};
    const Vec3 hi{lo[0] + sc[0] * (g.size[0] - 1), lo[1] + sc[1] * (g.size[1] - 1),
                  lo[2] + sc[2] * (g.size[2] - 1)};
    PlaneGeometry P;
    P.origin = {0, 0, 0};
    if (mode != PlaneMode::Project) {
        const size_t axis = f.choice("axis", kAxisNames, 2);
        // in-plane axes (a, b): (x, y) across z, (x, z) across y (the view from -y, Blender's
        // front view), (y, z) across x: z stays up
        const size_t a = axis == 0 ? 1 : 0, b = axis == 2 ? 1 : 2;
        P.u = {0, 0, 0}, P.w = {0, 0, 0}, P.n = {0, 0, 0};
        P.u[a] = 1, P.w[b] = 1, P.n[axis] = 1;
        P.a0 = lo[a], P.b0 = lo[b], P.da = sc[a], P.db = sc[b];
        P.width = g.size[a], P.height = g.size[b];
        const double z0 = std::min(lo[axis], hi[axis]), z1 = std::max(lo[axis], hi[axis]);
        if (mode == PlaneMode::Average) {
            P.depths.clear();
            for (int k = 0; k < g.size[axis]; ++k) P.depths.push_back(lo[axis] + sc[axis] * k);
        } else {
            const double h = f.number("height", 0.5 * (z0 + z1));
            if (!(h >= z0 && h <= z1))
                f.fail(f.node("height"), "height",
                       "expected a height within the grid's voxel centres along " +
                           std::string(kAxisNames[axis]) + ", [" + num(z0) + ", " + num(z1) + "]");
            P.depths = {h};
        }
        return P;
    }
    const toml::node* nn = f.node("normal");
    const auto* arr = nn ? nn->as_array() : nullptr;
    if (!arr || arr->size() != 3 || !std::all_of(arr->begin(), arr->end(), [](const toml::node& x) { return x.is_number(); }))
        f.fail(nn, "normal", "expected the plane's normal [nx, ny, nz] (plane = \"project\")");
    Vec3 n;
    for (size_t c = 0; c < 3; ++c) n[c] = *(*arr)[c].value<double>();
    if (!(dot(n, n) > 0.0) || !std::isfinite(dot(n, n))) f.fail(nn, "normal", "expected a non-zero finite normal");
    P.n = normalized(n);
    const Vec3 ex{1, 0, 0}, ey{0, 1, 0};
    const Vec3 e = std::abs(P.n[0]) > 0.9 ? ey : ex;
    const double en = dot(e, P.n);
    P.u = normalized({e[0] - en * P.n[0], e[1] - en * P.n[1], e[2] - en * P.n[2]});
    P.w = cross(P.n, P.u);
    // the plane at `height` along n (default: through the grid's centre)
    const Vec3 mid{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double h = f.number("height", dot(mid, P.n));
    P.depths = {h};
    double a0 = INFINITY, a1 = -INFINITY, b0 = INFINITY, b1 = -INFINITY;
    for (int c = 0; c < 8; ++c) {
        const Vec3 X{(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
        a0 = std::min(a0, dot(X, P.u)), a1 = std::max(a1, dot(X, P.u));
        b0 = std::min(b0, dot(X, P.w)), b1 = std::max(b1, dot(X, P.w));
    }
    const double step = std::min({std::abs(sc[0]), std::abs(sc[1]), std::abs(sc[2])});
    P.a0 = a0, P.b0 = b0, P.da = step, P.db = step;
    P.width = std::max(2, int(std::floor((a1 - a0) / step)) + 1);
    P.height = std::max(2, int(std::floor((b1 - b0) / step)) + 1);
    if (double(P.width) * P.height > 1e8) s.fail(s.first_name, "the projected plane would hold over 1e8 samples");
    return P;
}

/// The frames of `path` in `f`: the pattern, the files found (none missing in the middle).
std::vector<int64_t> read_frames(Reader& f, SequenceFiles& s, const fs::path& base) {
    const toml::node* pn = f.node("path");
    const std::string rel = f.string("path", "");
    if (rel.empty()) f.fail(pn, "path", "expected a frame pattern (cache/fluid_data_####.vdb or v_####.exr)");
    s.context = f.describe(pn, "path");
    const fs::path p = detail::resolve_path(pn, rel, base);
    s.dir = p.parent_path();
    s.pattern = parse_pattern(p.filename().string());
    if (!s.pattern.found)
        f.fail(pn, "path", "expected a frame pattern in the file name: #### or %04d for the frame number");
    s.vdb = output::lower_extension(p.string()) == ".vdb";
    const std::vector<int64_t> frames = frames_present(s.dir, s.pattern);
    if (frames.empty()) f.fail(pn, "path", "no file matches the pattern");
    for (size_t i = 1; i < frames.size(); ++i)
        if (frames[i] != frames[i - 1] + 1)
            f.fail(pn, "path", "frame " + std::to_string(frames[i - 1] + 1) + " (" +
                                   frame_name(s.pattern, frames[i - 1] + 1) +
                                   ") is missing: found frames " + runs_text(frames));
    s.first_name = frame_name(s.pattern, frames.front());
    return frames;
}

/// The time keys: scene time t reads frame start + rate t; velocities scale by `velocity`.
struct SequenceTime {
    double start = 0.0, rate = 24.0, velocity = 1.0;
};
SequenceTime read_time(Reader& f, int64_t first) {
    const double fps = f.number("fps", 24.0, kPositive, "simulation frames per second > 0");
    const double time_scale = f.number("time_scale", 1.0, kPositive, "simulation seconds per scene second, > 0");
    SequenceTime t;
    t.start = f.number("start", double(first));
    t.rate = fps * time_scale;
    t.velocity = f.number("velocity_scale", 1.0) * time_scale;
    return t;
}

/// The first frame's vector grid, checked: a grid found, voxels, an axis-aligned non-singular
/// transform; sets the header every frame must share.
output::VdbVectorGrid read_first_vdb(Reader& f, SequenceFiles& s, const std::vector<int64_t>& frames) {
    s.grid = choose_vdb_grid(f, s, s.first_name);
    // the union of the frames' active boxes (from each file's statistics: no voxel read)
    auto& box = s.whole;
    box = {{INT_MAX, INT_MAX, INT_MAX}, {INT_MIN, INT_MIN, INT_MIN}};
    for (int64_t n : frames) {
        const std::string file = frame_name(s.pattern, n);
        output::VdbIndexBox b;
        try {
            b = output::read_vdb_active_box((s.dir / file).string(), s.grid);
        } catch (const IoError& e) {
            s.fail(file, reason(e, s.dir / file));
        }
        if (b.min[0] > b.max[0]) continue;  // an empty frame: all background
        for (size_t c = 0; c < 3; ++c)
            box.min[c] = std::min(box.min[c], b.min[c]), box.max[c] = std::max(box.max[c], b.max[c]);
    }
    if (box.min[0] > box.max[0])
        s.fail(s.first_name, "grid \"" + s.grid + "\" has no active voxel in any frame");
    output::VdbVectorGrid g;
    try {
        g = output::read_vdb_vectors((s.dir / s.first_name).string(), s.grid, &box);
    } catch (const IoError& e) {
        s.fail(s.first_name, reason(e, s.dir / s.first_name));
    }
    const auto& M = g.linear;
    if (!g.affine || M[1] != 0 || M[2] != 0 || M[3] != 0 || M[5] != 0 || M[6] != 0 || M[7] != 0)
        s.fail(s.first_name, "grid \"" + s.grid + "\"'s transform is not a scale and a "
                             "translation: expected axis-aligned voxels");
    if (!(M[0] != 0 && M[4] != 0 && M[8] != 0))
        s.fail(s.first_name, "grid \"" + s.grid + "\"'s transform is singular (a voxel size of 0)");
    s.header = s.vdb_header(g);
    return g;
}

/// The voxels a slice reads: its two layers across the axis, one below and two above.
output::VdbIndexBox slice_slab(const SequenceFiles& s) {
    const PlaneGeometry& P = s.plane;
    const size_t axis = P.n[0] != 0 ? 0 : P.n[1] != 0 ? 1 : 2;
    const double sc = s.header.linear[4 * axis], t = s.header.translation[axis];
    const double q = (P.depths[0] - t) / sc - s.header.origin[axis];
    const int k = static_cast<int>(std::floor(q)), top = s.header.size[axis] - 1;
    output::VdbIndexBox box;
    for (size_t c = 0; c < 3; ++c)
        box.min[c] = s.header.origin[c], box.max[c] = s.header.origin[c] + s.header.size[c] - 1;
    box.min[axis] = s.header.origin[axis] + std::clamp(k - 1, 0, top);
    box.max[axis] = s.header.origin[axis] + std::clamp(k + 3, 0, top);
    return box;
}

/// With outside = "zero", a field that moves at the grid's edge jumps to 0 beyond it: say so.
void warn_outside_zero(Reader& f, sim::Outside outside, double edge_max, double vmax, const char* unit) {
    if (outside == sim::Outside::Zero && edge_max > 1e-3 * vmax)
        // docs/scenes.md "A Blender cache": the jump at the edge is a surface of divergence the
        // interpolant does not hold, so sqrt(J) misses it and impulses pile up along it
        f.warn("outside", "\"zero\" (the default) makes the field jump from up to " + num(edge_max) +
                              " " + unit + " at the grid's edge to 0 beyond it, a divergence sqrt(J) "
                              "does not see (the variance grows along the edge): \"clamp\" or "
                              "\"nearest\" keeps the field continuous there");
}

/// The largest sample speed of every frame, each read once (its checks fail here, before
/// anything renders).
template <class Speed>
double scan_frames(const std::vector<int64_t>& frames, const Speed& max_speed_of) {
    double vmax = 0.0;
    for (int64_t n : frames) vmax = std::max(vmax, max_speed_of(n));
    return vmax;
}

}  // namespace

void read_sequence_flow(Reader& f, const sim::ProcessConfig& process, Reader& layer,
                        const fs::path& base, sim::FlowSum& sum) {
    auto s = std::make_shared<SequenceFiles>();
    const std::vector<int64_t> frames = read_frames(f, *s, base);
    const SequenceTime time = read_time(f, frames.front());
    // simulation plane to texture: x = R(rotation) diag(scale) (a, b) + offset
    std::array<double, 2> scale{1.0, 1.0};
    if (const toml::node* n = f.node("scale")) {
        if (n->is_number()) scale[0] = scale[1] = f.number("scale", 1.0);
        else if (auto sp = f.pair("scale", "a number or [sx, sy]: texture units per simulation unit")) scale = *sp;
        if (!(scale[0] != 0.0 && scale[1] != 0.0))
            f.fail(n, "scale", "expected non-zero scales: the transform to texture space is singular");
    }
    std::array<double, 2> offset{0.0, 0.0};
    if (auto o = f.pair("offset", "[x, y] in texture units")) offset = *o;
    const double rot = f.number("rotation", 0.0);
    const double c = std::cos(rot), sn = std::sin(rot);
    const std::array<double, 4> L{c * scale[0], -sn * scale[1], sn * scale[0], c * scale[1]};
    for (size_t k = 0; k < 4; ++k) s->velocity[k] = L[k] * time.velocity;

    // the first frame: the grid or channels, the plane and the size every frame must have
    const toml::node* plane_node = f.node("plane");
    PlaneMode mode = PlaneMode::Slice;
    if (s->vdb) {
        const output::VdbVectorGrid g = read_first_vdb(f, *s, frames);
        if (plane_node) mode = static_cast<PlaneMode>(f.choice("plane", kPlaneModeNames, 0));
        s->mode = mode;
        s->plane = read_plane(f, *s, g, mode);
    } else {
        if (plane_node) f.fail(plane_node, "plane", "an image sequence is already a plane: plane is for 3-D (VDB) grids");
        output::Pixels px;
        std::string error;
        if (!output::read_pixels((s->dir / s->first_name).string(), px, error)) s->fail(s->first_name, error);
        s->channel = choose_channels(f, *s, s->first_name, px.channel_names);
        s->header.size = {px.width, px.height, 1};
        s->plane.width = px.width, s->plane.height = px.height;
    }
    if (s->plane.width < 2 || s->plane.height < 2)
        s->fail(s->first_name, "the plane holds " + std::to_string(s->plane.width) + "x" +
                                   std::to_string(s->plane.height) + " samples: expected 2x2 or more");

    // texture point -> plane grid index: (i, j) = G^-1 (x - offset - L (a0, b0)), G = L diag(da, db)
    const PlaneGeometry& P = s->plane;
    const std::array<double, 4> G{L[0] * P.da, L[1] * P.db, L[2] * P.da, L[3] * P.db};
    const double det = G[0] * G[3] - G[1] * G[2];
    if (!(std::abs(det) > 0.0) || !std::isfinite(det))
        f.fail(f.node("scale"), "scale", "the transform from the simulation to texture space is singular");
    sim::SequenceConfig cfg;
    cfg.to_index = {G[3] / det, -G[1] / det, -G[2] / det, G[0] / det};
    const double ox = offset[0] + L[0] * P.a0 + L[1] * P.b0, oy = offset[1] + L[2] * P.a0 + L[3] * P.b0;
    cfg.index_offset = {-(cfg.to_index[0] * ox + cfg.to_index[1] * oy),
                        -(cfg.to_index[2] * ox + cfg.to_index[3] * oy)};
    s->to_index = cfg.to_index;
    if (!process.jacobian) {
        // Without sqrt(J) the local variance goes as 1/J (design.md §1): a divergence over
        // 0.01 / lifetime could move it by over 1 % within one lifetime.
        s->max_divergence = 0.01 / process.lifetime_s;
        s->divergence_context = layer.describe(layer.node("jacobian"), "jacobian");
    }
    cfg.time = static_cast<sim::TimeInterpolation>(f.choice("interpolation", sim::kTimeInterpolationNames, 0));
    cfg.outside = static_cast<sim::Outside>(f.choice("outside", sim::kOutsideNames, 0));
    f.finish();

    // every frame read once now: its checks fail here, before anything renders, and the speed
    // bound covers the whole sequence
    double edge_max = 0.0;  // the largest speed on the plane grid's outer samples
    const double vmax = scan_frames(frames, [&](int64_t n) {
        const sim::PlaneFrame fr = s->load(n);
        double m = 0.0;
        for (size_t k = 0; k < fr.vx.size(); ++k) {
            const double speed = std::hypot(double(fr.vx[k]), double(fr.vy[k]));
            m = std::max(m, speed);
            const size_t i = k % size_t(fr.width), j = k / size_t(fr.width);
            if (i == 0 || j == 0 || i + 1 == size_t(fr.width) || j + 1 == size_t(fr.height))
                edge_max = std::max(edge_max, speed);
        }
        return m;
    });
    warn_outside_zero(f, cfg.outside, edge_max, vmax, "texture units/s");
    if (s->vdb && mode == PlaneMode::Slice) s->slab = slice_slab(*s);
    cfg.source = std::make_shared<FileFrames>(s);
    cfg.first = frames.front(), cfg.last = frames.back();
    cfg.width = P.width, cfg.height = P.height;
    cfg.start = time.start, cfg.rate = time.rate;
    cfg.max_sample_speed = vmax;
    cfg.span_s = process.lifetime_s;
    sum.push(sim::make_sequence_flow(std::move(cfg)));
}

void read_volume_sequence_flow(Reader& f, double lifetime_s, bool jacobian, Reader& volume,
                               const fs::path& base, volume::FlowSum3& sum) {
    auto s = std::make_shared<SequenceFiles>();
    const std::vector<int64_t> frames = read_frames(f, *s, base);
    if (!s->vdb)
        f.fail(f.node("path"), "path", "a volume is carried by a 3-D field: expected OpenVDB files (.vdb)");
    const SequenceTime time = read_time(f, frames.front());
    // simulation world to volume voxels, axis by axis: X_c = scale_c world_c + offset_c
    std::array<double, 3> scale{1, 1, 1}, offset{0, 0, 0};
    auto three = [&](const char* key, std::array<double, 3>& v, const char* expected) {
        const toml::node* n = f.node(key);
        if (!n) return;
        if (n->is_number()) {
            v.fill(f.number(key, 1.0));
            return;
        }
        const auto* a = n->as_array();
        if (!a || a->size() != 3) f.fail(n, key, expected);
        for (size_t c = 0; c < 3; ++c) {
            const auto x = (*a)[c].value<double>();
            if (!x || !std::isfinite(*x)) f.fail(n, key, expected);
            v[c] = *x;
        }
    };
    three("scale", scale, "expected a number or [sx, sy, sz]: voxels per simulation unit");
    if (!(scale[0] != 0 && scale[1] != 0 && scale[2] != 0))
        f.fail(f.node("scale"), "scale", "expected non-zero scales: the transform to the volume is singular");
    three("offset", offset, "expected [x, y, z] in voxels");
    const output::VdbVectorGrid g = read_first_vdb(f, *s, frames);
    volume::Sequence3Config cfg;
    for (size_t c = 0; c < 3; ++c) {
        // index = (world - t) / s - origin, world = (X - offset) / scale
        const double vs = g.linear[4 * c], t = g.translation[c];
        cfg.scale[c] = 1.0 / (scale[c] * vs);
        cfg.offset[c] = -(offset[c] / scale[c] + t) / vs - g.origin[c];
        if (!std::isfinite(cfg.scale[c]) || !std::isfinite(cfg.offset[c]) || cfg.scale[c] == 0.0)
            f.fail(f.node("scale"), "scale", "the transform from the simulation to the volume is singular");
        s->velocity3[c] = scale[c] * time.velocity;
        if (g.size[c] < 2)
            s->fail(s->first_name, "grid \"" + s->grid + "\" is " + std::to_string(g.size[c]) +
                                       " voxels across an axis: expected 2 or more");
    }
    s->index_scale3 = cfg.scale;
    if (!jacobian) {  // as for a layer (read_sequence_flow)
        s->max_divergence = 0.01 / lifetime_s;
        s->divergence_context = volume.describe(volume.node("jacobian"), "jacobian");
    }
    cfg.time = static_cast<sim::TimeInterpolation>(f.choice("interpolation", sim::kTimeInterpolationNames, 0));
    cfg.outside = static_cast<sim::Outside>(f.choice("outside", sim::kOutsideNames, 0));
    f.finish();
    double edge_max = 0.0;  // the largest speed on the grid's outer samples (as for a layer)
    cfg.max_sample_speed = scan_frames(frames, [&](int64_t n) {
        const volume::VolumeFrame fr = s->load_volume(n);
        const size_t W = size_t(fr.size[0]), H = size_t(fr.size[1]), D = size_t(fr.size[2]);
        double m = 0.0;
        for (size_t k = 0; k < fr.v.size(); k += 3) {
            const double speed = std::sqrt(double(fr.v[k]) * fr.v[k] + double(fr.v[k + 1]) * fr.v[k + 1] +
                                           double(fr.v[k + 2]) * fr.v[k + 2]);
            m = std::max(m, speed);
            const size_t i = k / 3 % W, j = k / 3 / W % H, l = k / 3 / (W * H);
            if (i == 0 || j == 0 || l == 0 || i + 1 == W || j + 1 == H || l + 1 == D)
                edge_max = std::max(edge_max, speed);
        }
        return m;
    });
    warn_outside_zero(f, cfg.outside, edge_max, cfg.max_sample_speed, "voxels/s");
    cfg.load = [s](int64_t n) { return s->load_volume(n); };
    cfg.first = frames.front(), cfg.last = frames.back();
    cfg.start = time.start, cfg.rate = time.rate;
    cfg.size = g.size;
    cfg.span_s = lifetime_s;
    sum.push(volume::make_sequence_flow3(std::move(cfg)));
}

}  // namespace impulse::scenes::detail
