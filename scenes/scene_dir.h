// SPDX-License-Identifier: Apache-2.0
#pragma once
// Where built-in scene names are looked up, for a program that carries its own copy of the
// built-in scenes (the Python package, README "Python"); part of impulse::scenes.

#include <string>

namespace impulse::scenes {

/// The directory builtin_scene_dir() returns when IMPULSE_SCENES_DIR is not set (before the
/// source tree's and the installed one); "" forgets it. Not thread-safe: call before loading
/// scenes.
void set_builtin_scene_dir(const std::string& dir);

}  // namespace impulse::scenes
