// SPDX-License-Identifier: Apache-2.0
#pragma once
// The numeric keys of a scene file given sliders: `impulse preview --expose` (README "Preview in
// the browser") and the Blender add-on's panel through the Python module (docs/blender.md "Use")
// take them from here, so both have the same keys, values and ranges. Part of impulse::scenes
// (scenes/scenes.h): it reads the scene language's files, includes as the loader does.

#include <string>
#include <vector>

namespace impulse::scenes {

/// A numeric key of the scene with a slider: `--expose key` or `key=lo:hi`.
struct Exposed {
    std::string key;     ///< dotted path as for --set: layer.0.kernel.radius
    double value = 0.0;  ///< current value (the file's, then the slider's)
    double lo = 0.0, hi = 1.0, step = 0.01;  ///< the slider's range (given, or 0 to twice the value)
    bool integer = false;  ///< the file holds an integer: the slider moves in whole steps
    bool moved = false;    ///< the slider moved since the file was read: an override applies
};
/// The exposed keys looked up in the scene file (then its includes). Throws ValueError naming a
/// key that is not a number there.
std::vector<Exposed> exposed_keys(const std::string& path, const std::vector<std::string>& specs);
/// Takes the exposed keys' values from the scene file again (after it changed: the file wins
/// over the sliders, so a pasted line shows and its errors point into the file). Keys the file
/// no longer holds as numbers keep their values.
void reread_exposed(const std::string& path, std::vector<Exposed>& exposed);
/// The value as TOML text (a float keeps a decimal point).
std::string toml_number(double v, bool integer);
/// The TOML line to paste back into the scene: "radius = 8.5  # in [layer.kernel] (layer 0)".
std::string toml_line(const Exposed& e);
/// The files scene file `path` names in `include`, resolved as the loader resolves them
/// (relative to the including file's folder); not recursive. Throws what toml++ throws for a
/// file that does not parse.
std::vector<std::string> scene_includes(const std::string& path);

}  // namespace impulse::scenes
