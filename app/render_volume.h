// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse render` of a volume scene (internal to app/): OpenVDB frames or a ray-marched preview.

#include <string>

namespace impulse::scenes {
struct Scene;
}

namespace impulse::app {

struct VolumeJob {
    std::string output;              ///< .vdb (a pattern for several frames), an image or a video
    long long first = 0, last = 0;   ///< inclusive frame range
    bool quiet = false, resume = false;
};

/// Renders frames [first, last] of a volume scene: `cloud_####.vdb` writes one OpenVDB file per
/// frame holding the float grid "density" (fog volume, sparse: zero voxels inactive); an image,
/// image pattern or video gets the ray-marched preview at the scene's output size. Every file is
/// written atomically. With `resume`, frames already present in a sequence are kept (a present
/// file is whole: it was renamed into place). Throws ValueError for an output it cannot write.
int run_volume_render(const scenes::Scene& scene, const VolumeJob& job);

}  // namespace impulse::app
