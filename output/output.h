// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::output — from float fields to what users keep: shading and procedural transforms,
// images (OpenImageIO), video (libav) and volumes (OpenEXR stacks, OpenVDB). Depends on numeric only; knows nothing of impulses,
// scene files or the CLI.

#include "output/image.h"      // EXR, PNG, TIFF in and out
#include "output/shading.h"    // colour ramps, relief, alpha over a sky
#include "output/transform.h"  // marble and wood (Lewis 1989 §5.1)
#include "output/video.h"      // H.264, ProRes, FFV1, VP9
#include "output/display.h"    // the display mapping as text in a frame's metadata
#include "output/files.h"      // whole files written atomically
#include "output/volume.h"     // EXR stacks and OpenVDB grids
#include "output/atlas.h"      // flipbook atlases of frames, with their sidecar
#include "output/io_module.h"  // the image and video module, loaded at run time
