// SPDX-License-Identifier: Apache-2.0
#pragma once
// The frames of a sampled sequence that a flow holds (sim/sequence.cpp in 2-D, volume/'s
// sequence flow in 3-D): scene time to sequence frame, the frames a time reads and their
// weights (linear over two, Catmull-Rom over four), and the cache of the frames in use with the
// next one read ahead in the background (docs/scenes.md "Velocity sequences").

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include "sim/velocity_sequence.h"

namespace impulse::sim {

/// The sequence frames that time t reads and their weights (two for linear, four for cubic).
struct TimeWeights {
    int64_t frame[4] = {0, 0, 0, 0};
    double weight[4] = {0.0, 0.0, 0.0, 0.0};
    int count = 0;
};

/// Catmull-Rom weights of frames f - 1, f, f + 1, f + 2 at fraction s of [f, f + 1]; their
/// absolute values sum to at most 1.25 (at s = 1/2), which bounds the overshoot.
inline void catmull_rom(double s, double w[4]) {
    const double s2 = s * s, s3 = s2 * s;
    w[0] = 0.5 * (-s3 + 2.0 * s2 - s);
    w[1] = 0.5 * (3.0 * s3 - 5.0 * s2 + 2.0);
    w[2] = 0.5 * (-3.0 * s3 + 4.0 * s2 + s);
    w[3] = 0.5 * (s3 - s2);
}

/// How scene time maps onto a sequence: u(t) = start + rate t, held to [first, last].
struct FrameTiming {
    int64_t first = 0, last = 0;
    double start = 0.0, rate = 24.0;
    TimeInterpolation time = TimeInterpolation::Linear;

    double coordinate(double t) const {
        return std::clamp(start + rate * t, double(first), double(last));
    }
    int64_t clamp(int64_t k) const { return std::clamp(k, first, last); }
    TimeWeights weights_at(double t) const {
        const double u = coordinate(t);
        const int64_t f = static_cast<int64_t>(std::floor(u));
        const double s = u - double(f);
        TimeWeights tw;
        if (time == TimeInterpolation::Linear) {
            tw.count = 2;
            tw.frame[0] = f, tw.frame[1] = clamp(f + 1);
            tw.weight[0] = 1.0 - s, tw.weight[1] = s;
        } else {
            tw.count = 4;
            catmull_rom(s, tw.weight);
            for (int q = 0; q < 4; ++q) tw.frame[q] = clamp(f - 1 + q);
        }
        return tw;
    }
    /// The frames times [t0, t1] read.
    std::pair<int64_t, int64_t> frames_for(double t0, double t1) const {
        const double a = std::min(coordinate(t0), coordinate(t1));
        const double b = std::max(coordinate(t0), coordinate(t1));
        const int64_t reach = time == TimeInterpolation::Cubic ? 1 : 0;
        return {clamp(int64_t(std::floor(a)) - reach), clamp(int64_t(std::floor(b)) + 1 + reach)};
    }
    /// |weights| sum to at most this: 1 (linear, convex), 1.25 (Catmull-Rom).
    double overshoot() const { return time == TimeInterpolation::Cubic ? 1.25 : 1.0; }
    /// Frames held at most for spans of `span_s` (a lifetime): the span's frames, one more for
    /// the step before it, the interpolation's neighbours and the one read ahead.
    double frames_held(double span_s, bool read_ahead) const {
        const double extra = time == TimeInterpolation::Cubic ? 5.0 : 3.0;
        const double span = std::ceil(std::max(0.0, span_s) * std::abs(rate)) + extra;
        return std::min(span, double(last - first + 1)) + (read_ahead ? 1.0 : 0.0);
    }
};

/// The frames in use of a sequence, loaded by `load(k)` (thread-safe; throws on bad input).
template <class Frame>
class FrameWindow {
public:
    using Loader = std::function<Frame(int64_t)>;
    FrameWindow(FrameTiming timing, Loader load, bool read_ahead)
        : m_timing(timing), m_load(std::move(load)), m_read_ahead(read_ahead) {}
    ~FrameWindow() {
        if (m_ahead.valid()) m_ahead.wait();
    }
    const FrameTiming& timing() const { return m_timing; }

    /// Frame k, loaded now (under the lock) when it is not held.
    std::shared_ptr<const Frame> get(int64_t k) const {
        std::lock_guard lock(m_mutex);
        auto it = m_frames.find(k);
        if (it != m_frames.end()) return it->second;
        auto f = std::make_shared<const Frame>(m_load(k));
        m_frames.emplace(k, f);
        return f;
    }

    /// Holds exactly the frames times [t0, t1] read (single-threaded), taking the one read
    /// ahead when it is among them, then starts reading the next.
    void prepare_span(double t0, double t1) {
        const auto [lo, hi] = m_timing.frames_for(t0, t1);
        if (m_ahead.valid() && (m_ahead_frame < lo || m_ahead_frame > hi + 1)) {
            m_ahead.wait();  // read for a span not taken (a jump in time): dropped
            m_ahead = {};
        }
        std::map<int64_t, std::shared_ptr<const Frame>> keep;
        {
            std::lock_guard lock(m_mutex);
            for (auto& [k, f] : m_frames)
                if (k >= lo && k <= hi) keep.emplace(k, f);
        }
        for (int64_t k = lo; k <= hi; ++k)
            if (!keep.count(k)) {
                if (m_ahead.valid() && m_ahead_frame == k) keep.emplace(k, m_ahead.get());
                else keep.emplace(k, std::make_shared<const Frame>(m_load(k)));
            }
        {
            std::lock_guard lock(m_mutex);
            m_frames = std::move(keep);
        }
        if (m_read_ahead && hi < m_timing.last && !m_ahead.valid()) {
            m_ahead_frame = hi + 1;
            m_ahead = std::async(std::launch::async, [load = m_load, k = m_ahead_frame] {
                return std::make_shared<const Frame>(load(k));
            });
        }
    }

    /// Bytes held at most for spans of `span_s`, `frame_bytes` a frame.
    double bytes(double span_s, double frame_bytes) const {
        return frame_bytes * m_timing.frames_held(span_s, m_read_ahead);
    }

private:
    FrameTiming m_timing;
    Loader m_load;
    bool m_read_ahead = true;
    mutable std::mutex m_mutex;
    mutable std::map<int64_t, std::shared_ptr<const Frame>> m_frames;
    std::future<std::shared_ptr<const Frame>> m_ahead;
    int64_t m_ahead_frame = 0;
};

}  // namespace impulse::sim
