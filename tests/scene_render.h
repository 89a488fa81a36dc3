// SPDX-License-Identifier: Apache-2.0
#pragma once
// Rendering scene text in tests: one frame of a scene given as a string, and bit equality of
// frames.

#include <cstring>
#include <string>

#include "render/render.h"
#include "scenes/scenes.h"

namespace impulse::test {

/// Frame `frame` of the scene `text` (`name` stands in for its file name in messages).
inline render::Frame render_scene_text(const std::string& text, int64_t frame = 0,
                                       const std::string& name = "scene.toml") {
    scenes::Renderer r(scenes::load_scene_string(text, name));
    render::Frame f;
    r.render(frame, f);
    return f;
}

/// Same size and the same bits in every pixel.
inline bool same_bits(const render::Frame& a, const render::Frame& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

}  // namespace impulse::test
