// SPDX-License-Identifier: Apache-2.0
// libFuzzer target for the image and video readers: arbitrary bytes, written to a file, read
// by what `impulse analyze` uses (output::probe_image and output::read_image through
// OpenImageIO, output::decode_video_luma through libav) and by the scene inputs that read
// images (exemplar kernel, mask region, image flow, orientation image, empirical marginal,
// exemplar ramp). Any file must read or fail with impulse::Error — never crash, hang, leak or
// trip a sanitizer.
//
// Input: byte 0 chooses the file's extension (low 3 bits) and the reader (the rest); the other
// bytes are the file. OpenImageIO's own limit on decoded image size (limits:imagesize_MB) is
// lowered to 64 MB so a small file cannot claim a huge image.
#include <unistd.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "output/output.h"
#include "output/video.h"
#include "scenes/scenes.h"
#include "numeric/errors.h"

namespace {

namespace fs = std::filesystem;
namespace R = impulse::output;

constexpr std::array<const char*, 8> kExtensions = {".exr", ".png", ".tif", ".jpg",
                                                     ".mp4", ".mkv", ".mov", ".webm"};

/// A scene that reads the image at %s (one per scene input that reads an image).
constexpr std::array<const char*, 6> kScenes = {
    "[[layer]]\n[layer.kernel]\ntype = \"exemplar\"\npath = \"%s\"\n",
    "[[layer]]\n[layer.kernel]\nradius = 8.0\n[layer.region]\ntype = \"image\"\npath = \"%s\"\n",
    "[[layer]]\n[[layer.flow]]\ntype = \"image\"\npath = \"%s\"\n",
    "[[layer]]\norientation = { type = \"image\", path = \"%s\" }\n",
    "[[layer]]\nmarginal = { type = \"empirical\", image = \"%s\" }\n",
    "[shading]\nramp = { exemplar = \"%s\", stops = 16 }\n[[layer]]\n",
};

std::string scene_reading(const char* format, const std::string& path) {
    std::string s(format);
    s.replace(s.find("%s"), 2, path);
    return "[output]\nsize = [64, 48]\n" + s;
}

int init() {
    OIIO::attribute("limits:imagesize_MB", 64);
    OIIO::attribute("threads", 1);
    R::quiet_video_logs();
    return 0;
}

void read(const std::string& path, unsigned reader, bool video) {
    if (video) {
        int width = 0, height = 0;
        (void)R::decode_video_luma(path, width, height);
    } else if (reader == 0) {
        (void)R::probe_image(path);
        (void)R::read_image(path);
    } else {
        const std::string text = scene_reading(kScenes[(reader - 1) % kScenes.size()], path);
        (void)impulse::scenes::load_scene_string(text, "fuzz.toml");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const int once = init();
    (void)once;
    if (size < 1) return 0;
    const unsigned ext = data[0] & 7u, reader = (data[0] >> 3) % (kScenes.size() + 1);
    static const std::string stem =
        (fs::temp_directory_path() / ("impulse-fuzz-image-" + std::to_string(::getpid()))).string();
    const std::string path = stem + kExtensions[ext];
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data + 1), size - 1);
    try {
        read(path, reader, ext >= 4);
    } catch (const impulse::Error&) {
    }
    fs::remove(path);
    return 0;
}
