// SPDX-License-Identifier: Apache-2.0
#pragma once
// Typed, position-aware reading of a TOML table that records which keys were read and
// reports the rest as unknown (pbrt ReportUnused, Mitsuba's queried-key tracking).
// Internal to impulse::scenes.

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace impulse::scenes::detail {

/// Camera centres and positions lie within this distance of the origin on each axis (texture
/// units): doubles there still resolve points 2e-4 apart, and the seeding cells' indices stay
/// exact. Beyond, pixels would collapse onto the same texture point.
inline constexpr double kMaxPlaneCoordinate = 1e12;
inline bool on_plane(double v) { return std::abs(v) <= kMaxPlaneCoordinate; }
inline constexpr const char* kOnPlane = "a coordinate in texture units within +-1e12";

/// Where values came from: the file name and the `--set` overrides by key path.
struct Source {
    std::string file;
    std::map<std::string, std::string> overrides;  ///< "layer[0].kernel.radius" -> "layer.0...=8"
    std::vector<std::string>* warnings = nullptr;
};

/// Levenshtein distance (for "did you mean").
size_t edit_distance(std::string_view a, std::string_view b);
/// The nearest of `candidates` to `word`, if close enough to be a plausible typo.
std::optional<std::string> nearest(std::string_view word, const std::vector<std::string>& candidates);

class Reader {
public:
    Reader(const toml::table& table, std::string path, const Source& source,
           const toml::node* self = nullptr);

    /// "layer[0].kernel" + "." + key
    std::string key_path(std::string_view key) const;
    bool has(std::string_view key);
    const toml::node* node(std::string_view key);

    /// A number that cannot vary in time: a keyframe table given for it is refused with the
    /// reason (structural_reason), as for integer, pair and boolean.
    double number(std::string_view key, double fallback);
    /// Number constrained by `ok`; `expected` completes "expected ..." in the message.
    double number(std::string_view key, double fallback, const std::function<bool(double)>& ok,
                  const char* expected);
    int64_t integer(std::string_view key, int64_t fallback, int64_t lo, int64_t hi);
    bool boolean(std::string_view key, bool fallback);
    std::string string(std::string_view key, const std::string& fallback);
    /// String that must be one of `names`; returns its index.
    template <size_t N>
    size_t choice(std::string_view key, const std::array<std::string_view, N>& names, size_t fallback) {
        return choice_impl(key, std::vector<std::string_view>(names.begin(), names.end()), fallback);
    }
    size_t choice_impl(std::string_view key, const std::vector<std::string_view>& names, size_t fallback);
    /// Array of exactly two numbers.
    std::optional<std::array<double, 2>> pair(std::string_view key, const char* expected,
                                              const std::function<bool(double)>& ok = {});
    /// A number, or { keys = [[t, v], ...], ease = "linear" } with increasing times.
    numeric::Keyframed keyframed(std::string_view key, double fallback,
                             const std::function<bool(double)>& ok = {}, const char* expected = "");
    /// Reason given when a keyframe table is written for a structural key of this table (for
    /// tables whose numbers are all structural, e.g. a designed kernel); overrides the list in
    /// structural_reason.
    void set_structural_reason(std::string reason) { m_structural = std::move(reason); }
    /// Fails at `key` with "cannot vary in time: <reason>" when its node is a keyframe table
    /// ({ keys = ... }): this table's reason, else structural_reason of the key's path.
    void refuse_keyframes(std::string_view key);
    /// Sub-table (inline or standard); nullopt when absent.
    std::optional<Reader> table(std::string_view key);
    /// Array of tables ([[layer]]); empty when absent.
    std::vector<Reader> tables(std::string_view key);

    /// Throws for every key present but never read.
    void finish() const;
    /// "file:line:column: key.path = value" of `n` (or the table) for `key`: what fail prints
    /// before its reason, for errors found later (a sequence frame read while rendering).
    std::string describe(const toml::node* n, std::string_view key) const;
    /// One-line error at `n` (or the table) for `key`.
    [[noreturn]] void fail(const toml::node* n, std::string_view key, const std::string& what) const;
    void warn(std::string_view key, const std::string& what) const;
    const Source& source() const { return m_source; }

private:
    std::string location(const toml::node* n, std::string_view key) const;

    std::string m_structural;
    const toml::table& m_table;
    std::string m_path;
    const Source& m_source;
    const toml::node* m_self;
    std::set<std::string, std::less<>> m_known;
};

/// The [shading] table (scenes/language/shading_config.cpp); `base` resolves relative paths. Keyframed
/// numbers go to `keys` (their values at t = 0 into the result).
output::Shading read_shading(std::optional<Reader> r, const std::filesystem::path& base,
                             ShadingKeys& keys);

/// Times at which combinations of keyframed values are checked: t = 0, every key, and 65
/// times evenly over the keys' span (each value is monotone between its keys, but a
/// combination of two need not be).
std::vector<double> key_check_times(const std::vector<const numeric::Keyframed*>& keyframed);

/// Why the key at `path` (a key path with the array indices removed: "layer.lifetime") cannot
/// vary in time; completes "cannot vary in time: ...".
std::string structural_reason(std::string_view path);

/// A path value `rel` of node `n`: absolute as it is, else relative to the directory of the file
/// the node was written in (an included file's own directory), or to `base` for values without
/// a file (--set overrides).
std::filesystem::path resolve_path(const toml::node* n, const std::string& rel,
                                   const std::filesystem::path& base);

/// [shading.transform] (scenes/language/transform_config.cpp): marble or wood; refused for perspective
/// cameras. `width`, `height`: the output size (wood's default centre).
output::FieldTransform read_transform(std::optional<Reader> r, const CameraConfig& camera,
                                      int width, int height, uint64_t scene_seed);

/// layer.region: the birth region of a layer (scenes/language/region_config.cpp); `base` resolves a mask
/// image's path.
void read_region(Reader& layer, sim::ProcessConfig& process, const std::filesystem::path& base);
/// [layer.dispersion] of a Gabor layer (scenes/language/dispersion_config.cpp): adds the group
/// velocity to its flow (`flows` reads the layer's own flows afresh), sets its carrier rate
/// and appends its quadrature twin to `twins`.
void read_dispersion(Reader& layer, LayerConfig& L, std::vector<LayerConfig>& twins,
                     const std::function<std::shared_ptr<sim::Flow>()>& flows);

/// Text of a node's value as written (for messages).
std::string value_text(const toml::node& n);
/// TOML type name of a node ("string", "integer", ...).
std::string type_name(const toml::node& n);

}  // namespace impulse::scenes::detail
