// SPDX-License-Identifier: Apache-2.0
// `impulse preview`: the worker that loads the scene, follows its files and renders preview
// frames into a bounded cache, off the server's threads.


#include <chrono>
#include <cmath>
#include <sstream>

#include "app/detail/preview.h"
#include "numeric/errors.h"
#include "output/io_module.h"

namespace impulse::app::preview {
namespace {

/// Frames kept: a few hundred preview PNGs (~50 KiB each at 640x360), the rest re-rendered.
constexpr size_t kCacheBytes = size_t(96) << 20;
/// Frames rendered ahead of the one the page shows.
constexpr int64_t kLookahead = 48;
/// How often the scene's files are looked at.
constexpr auto kPoll = std::chrono::milliseconds(100);

double elapsed_ms(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// Mean and population variance of a frame, accumulated in double.
std::pair<double, double> moments(const std::vector<float>& v) {
    double s = 0, s2 = 0;
    for (const float x : v) s += x;
    const double mean = v.empty() ? 0.0 : s / double(v.size());
    for (const float x : v) s2 += (x - mean) * (x - mean);
    return {mean, v.empty() ? 0.0 : s2 / double(v.size())};
}

}  // namespace

std::string encode_png(int width, int height, const std::vector<float>& rgb) {
    return output::encode_png(width, height, rgb);
}

Previewer::Previewer(PreviewConfig config) : m_config(std::move(config)) {
    m_worker = std::thread([this] { run(); });
}

Previewer::~Previewer() {
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_stop = true;
    }
    m_wake.notify_all();
    m_worker.join();
}

void Previewer::run() {
    auto last_poll = std::chrono::steady_clock::now() - kPoll;
    while (true) {
        {
            const std::lock_guard<std::mutex> lock(m_mutex);
            if (m_stop) return;
        }
        if (std::chrono::steady_clock::now() - last_poll >= kPoll) {
            last_poll = std::chrono::steady_clock::now();
            const std::vector<FileStamp> stamps = scene_files(m_config.path);
            bool dirty;
            {
                const std::lock_guard<std::mutex> lock(m_mutex);
                if (stamps != m_stamps) reread_exposed(m_config.path, m_config.exposed);
                dirty = m_dirty || stamps != m_stamps;
                m_stamps = stamps, m_dirty = false;
            }
            if (dirty) reload();
        }
        if (render_next()) continue;
        std::unique_lock<std::mutex> lock(m_mutex);
        m_wake.wait_for(lock, kPoll, [&] { return m_stop || m_dirty || next_frame(); });
    }
}

void Previewer::reload() {
    std::vector<std::string> sets = m_config.sets;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        for (const Exposed& e : m_config.exposed)
            if (e.moved) sets.push_back(e.key + "=" + toml_number(e.value, e.integer));
    }
    try {
        auto r = std::make_unique<scenes::Renderer>(
            scenes::load_scene(m_config.path, sets, m_config.size));
        const output::ValueMapping mapping = r->mapping();
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_renderer = std::move(r);
        m_mapping = mapping;
        ++m_generation;
        m_error.clear();
        m_cache.clear();
        m_cache_bytes = 0;
        m_wanted = std::min<int64_t>(m_wanted, m_renderer->scene().output.frames - 1);
    } catch (const std::exception& e) {
        // The last good frames stay; the page shows the line.
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_error = e.what();
    }
}

std::optional<int64_t> Previewer::next_frame() const {
    if (!m_renderer || !m_error.empty()) return std::nullopt;
    const int64_t n = m_renderer->scene().output.frames;
    for (int64_t d = 0; d <= std::min(kLookahead, n - 1); ++d) {
        const int64_t f = (m_wanted + d) % n;
        if (!m_cache.count(f))
            return m_cache_bytes < kCacheBytes || d == 0 ? std::optional(f) : std::nullopt;
    }
    return std::nullopt;
}

bool Previewer::render_next() {
    int64_t f;
    uint64_t generation;
    scenes::Renderer* r;
    output::ValueMapping mapping;
    {
        const std::lock_guard<std::mutex> lock(m_mutex);
        const auto next = next_frame();
        if (!next) return false;
        f = *next, generation = m_generation, r = m_renderer.get(), mapping = m_mapping;
    }
    // Only this thread replaces the renderer (reload), so it stays valid while it renders.
    const auto t0 = std::chrono::steady_clock::now();
    FrameImage im;
    try {
        const scenes::Scene& sc = r->scene();
        render::Frame field;
        r->render(f, field);
        im.time_s = sc.frame_time(f);
        std::vector<float> rgb;
        output::shade(field, mapping, sc.shading_at(im.time_s), rgb);
        im.png = encode_png(field.width, field.height, rgb);
        std::tie(im.mean, im.variance) = moments(field.data);
        const scenes::Theory th = scenes::scene_theory(sc, im.time_s);
        im.theory_mean = th.mean, im.theory_variance = th.variance;
    } catch (const std::exception& e) {
        const std::lock_guard<std::mutex> lock(m_mutex);
        m_error = "frame " + std::to_string(f) + ": " + e.what();  // a budget refused, say
        return false;
    }
    im.render_ms = elapsed_ms(t0);
    const std::lock_guard<std::mutex> lock(m_mutex);
    if (generation != m_generation) return true;
    // Over the budget, the frame furthest behind the page's goes (the cache is a window).
    while (m_cache_bytes + im.png.size() > kCacheBytes && !m_cache.empty()) {
        auto far = m_cache.begin();
        if (far->first >= m_wanted) far = std::prev(m_cache.end());
        m_cache_bytes -= far->second.png.size();
        m_cache.erase(far);
    }
    m_cache_bytes += im.png.size();
    m_cache.emplace(f, std::move(im));
    return true;
}

std::optional<FrameImage> Previewer::frame(uint64_t generation, int64_t f) {
    const std::lock_guard<std::mutex> lock(m_mutex);
    if (m_renderer && f >= 0 && f < m_renderer->scene().output.frames && f != m_wanted) {
        m_wanted = f;
        m_wake.notify_all();
    }
    const auto it = m_cache.find(f);
    if (generation != m_generation || it == m_cache.end()) return std::nullopt;
    return it->second;
}

std::string Previewer::set(const std::string& key, const std::string& value) {
    const std::lock_guard<std::mutex> lock(m_mutex);
    for (Exposed& e : m_config.exposed) {
        if (e.key != key) continue;
        double v = 0;
        std::istringstream in(value);
        in >> v;
        if (value.empty() || !in.eof() || in.fail() || !std::isfinite(v) ||
            (e.integer && v != std::round(v)))
            return key + " = " + value.substr(0, 40) + ": expected " +
                   (e.integer ? "an integer" : "a finite number");
        e.value = v, e.moved = true;
        m_dirty = true;
        m_wake.notify_all();
        return "";
    }
    std::string keys;
    for (const Exposed& e : m_config.exposed) keys += (keys.empty() ? "" : ", ") + e.key;
    return "unknown key \"" + key.substr(0, 80) + "\": the exposed keys are " +
           (keys.empty() ? "none (impulse preview --expose KEY)" : keys);
}

std::string Previewer::state_json() const {
    const std::lock_guard<std::mutex> lock(m_mutex);
    std::ostringstream s;
    s.precision(17);
    s << "{\"generation\":" << m_generation << ",\"error\":" << json_quote(m_error)
      << ",\"path\":" << json_quote(m_config.path) << ",\"cached\":" << m_cache.size();
    if (m_renderer) {
        const scenes::Scene& sc = m_renderer->scene();
        s << ",\"width\":" << sc.output.width << ",\"height\":" << sc.output.height
          << ",\"frames\":" << sc.output.frames << ",\"fps\":" << sc.output.fps;
    }
    s << ",\"exposed\":[";
    for (size_t i = 0; i < m_config.exposed.size(); ++i) {
        const Exposed& e = m_config.exposed[i];
        s << (i ? "," : "") << "{\"key\":" << json_quote(e.key) << ",\"value\":" << e.value
          << ",\"min\":" << e.lo << ",\"max\":" << e.hi << ",\"step\":" << e.step
          << ",\"line\":" << json_quote(toml_line(e)) << "}";
    }
    s << "]}";
    return s.str();
}

}  // namespace impulse::app::preview
