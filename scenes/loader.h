// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scene files and text turned into a Scene, with --set overrides and --size (docs/scenes.md).
// Part of impulse::scenes (scenes/scenes.h).

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scenes/scene.h"

namespace impulse::scenes {

/// Load a scene file, applying `--set key=value` overrides (dotted paths, array elements by
/// index: "layer.0.kernel.radius=8"). Throws SceneError with "file:line:col: key = value:
/// expected ..." on any problem, including unknown keys (with the nearest valid name).
///
/// `size` (the CLI's --size) renders the scene's own view at another resolution: the same
/// texture region, kernels, flows and regions in the same texture units, a picture with
/// size.width x size.height pixels. An orthographic camera's zoom (pixels per texture unit) is
/// scaled by size.height / output height, keeping the vertical extent as a perspective
/// camera's vertical fov does (another aspect ratio shows more or less at the sides); centres
/// that default to the middle of the frame stay where the scene's own size puts them. {0, 0} or
/// the scene's own size: nothing changes (same bits). `--set output.size` crops instead.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {},
                 OutputSize size = {});
/// Same for scene text; `name` stands in for the file name in messages.
Scene load_scene_string(std::string_view text, const std::string& name,
                        const std::vector<std::string>& overrides = {}, OutputSize size = {});

}  // namespace impulse::scenes
