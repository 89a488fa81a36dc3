// SPDX-License-Identifier: Apache-2.0
#pragma once
// A volume scene's content (part of impulse::scenes; docs/volume.md): what Scene::volume points
// to.

#include "scenes/scene.h"
#include "volume/volume.h"

namespace impulse::scenes {

/// A volume scene ([volume] instead of [[layer]], docs/volume.md): impulses in 3-D, written as
/// an OpenVDB sequence or as a ray-marched preview (scenes/language/volume_config.cpp).
struct VolumeSceneConfig {
    volume::CloudConfig cloud;    ///< [volume], its kernel, shape and flows (fps from [output])
    volume::MarchOptions march;   ///< [preview] (width and height from [output].size)
    double voxel_size = 1.0;      ///< [volume].voxel_size: world units per voxel in the VDB
};

}  // namespace impulse::scenes
