// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pieces of `impulse preview` (app/preview*.cpp): the files it watches, the keys it
// exposes as sliders, and the worker that renders preview frames off the server's threads.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "scenes/scenes.h"

namespace impulse::app::preview {

using scenes::Exposed;
using scenes::exposed_keys;
using scenes::reread_exposed;
using scenes::toml_line;
using scenes::toml_number;

/// A watched file's identity at one moment (missing files included: they may come back).
struct FileStamp {
    std::string path;
    bool exists = false;
    int64_t mtime_ns = 0;
    uint64_t size = 0;
    bool operator==(const FileStamp&) const = default;
};
/// The scene file and the files it includes, recursively (as far as they parse: a file that
/// does not is watched itself, and its includes once it parses again).
std::vector<FileStamp> scene_files(const std::string& path);

/// A JSON string literal of `s`.
std::string json_quote(const std::string& s);
/// An 8-bit RGB PNG in memory (output::encode_png). Throws IoError.
std::string encode_png(int width, int height, const std::vector<float>& rgb);

/// One rendered preview frame.
struct FrameImage {
    std::string png;
    double time_s = 0.0, mean = 0.0, variance = 0.0;  ///< measured on the float field
    double theory_mean = 0.0, theory_variance = 0.0;  ///< closed form at the frame's time
    double render_ms = 0.0;
};

struct PreviewConfig {
    std::string path;               ///< resolved scene file
    std::vector<std::string> sets;  ///< --set from the command line
    scenes::OutputSize size;        ///< preview size (same view)
    std::vector<Exposed> exposed;
};

/// Renders preview frames in a worker thread: the frame the page asks for first, then the
/// frames after it, into a bounded cache. Watches the scene's files (every 100 ms) and reloads
/// on a change or a slider; a scene that fails to load keeps the last good frames and states
/// the error. Every public call only takes a lock briefly: the server never waits for a render.
class Previewer {
public:
    explicit Previewer(PreviewConfig config);
    ~Previewer();
    Previewer(const Previewer&) = delete;
    Previewer& operator=(const Previewer&) = delete;

    /// The page's view of things, as JSON.
    std::string state_json() const;
    /// Frame `frame` of generation `generation` when rendered; marks it wanted either way.
    std::optional<FrameImage> frame(uint64_t generation, int64_t frame);
    /// A slider moved: "" when taken (the scene reloads), else the one-line reason.
    std::string set(const std::string& key, const std::string& value);

private:
    void run();
    void reload();
    bool render_next();
    std::optional<int64_t> next_frame() const;  ///< under m_mutex

    PreviewConfig m_config;
    mutable std::mutex m_mutex;
    std::condition_variable m_wake;
    bool m_stop = false;
    bool m_dirty = true;  ///< reload before the next frame (a slider moved)
    std::vector<FileStamp> m_stamps;
    std::unique_ptr<scenes::Renderer> m_renderer;  ///< of the last scene that loaded
    output::ValueMapping m_mapping;
    uint64_t m_generation = 0;  ///< counts successful loads: frames of older ones are stale
    std::string m_error;        ///< the last load's error ("" when it loaded)
    int64_t m_wanted = 0;
    std::map<int64_t, FrameImage> m_cache;
    size_t m_cache_bytes = 0;
    std::thread m_worker;
};

}  // namespace impulse::app::preview
