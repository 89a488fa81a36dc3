// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::scenes — scene files (TOML) turned into typed configuration, and the scene
// renderer: the C++ API a program uses to render frame f of a scene into a float buffer.
// The schema is documented in docs/scenes.md.

#include "scenes/channels.h"     // the channels a frame carries (value, dx, dy, motion)
#include "scenes/closed_form.h"  // a scene's theory as analysis/ judges it (spectra, blur)
#include "scenes/exposed.h"      // the numeric keys a scene gives sliders (preview, Blender)
#include "scenes/loader.h"       // scene files and text to a Scene
#include "scenes/renderer.h"     // Renderer: frame f of a scene
#include "scenes/scene.h"        // the Scene and its configuration types
#include "scenes/scene_dir.h"    // where the built-in scenes are
#include "scenes/source.h"       // the source seam: layers drawn by other synthesizers
#include "scenes/theory.h"       // Campbell's theorem per layer, blur, dispersion
#include "scenes/volume_scene.h"  // a volume scene's configuration
