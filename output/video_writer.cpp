// SPDX-License-Identifier: Apache-2.0
// video.h: names and paths are checked here; encoding and decoding forward to the image and
// video module (output/io_module.h), loaded when the first video is opened or read.

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <string_view>

#include "numeric/errors.h"
#include "output/io_module.h"

namespace impulse::output {

/// Parse a codec name; exact lower-case names only, so scene files stay greppable.
VideoCodec video_codec_from_string(const std::string& name) {
    static constexpr std::array<std::pair<std::string_view, VideoCodec>, 5> kNames = {{
        {"auto", VideoCodec::Auto},
        {"h264", VideoCodec::H264},
        {"prores", VideoCodec::ProRes},
        {"ffv1", VideoCodec::FFV1},
        {"vp9", VideoCodec::VP9},
    }};
    for (const auto& [n, codec] : kNames)
        if (name == n) return codec;
    throw ValueError("codec = \"" + name + "\": expected one of auto, h264, prores, ffv1, vp9");
}

/// True for .mp4 .mov .mkv .webm in any letter case.
bool is_video_path(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext == ".mp4" || ext == ".mov" || ext == ".mkv" || ext == ".webm";
}

VideoWriter::VideoWriter() = default;
VideoWriter::~VideoWriter() = default;  // the sink aborts if still open

void VideoWriter::open(const std::string& path, const VideoOptions& options) {
    if (!m_sink) m_sink = io_module().make_video_sink();
    m_sink->open(path, options);
}
void VideoWriter::write_frame(const float* rgb) {
    if (!m_sink) throw ValueError("write_frame: video writer is not open");
    m_sink->write_frame(rgb);
}
void VideoWriter::stage_frame(const RowSource& rows) {
    if (!m_sink) throw ValueError("stage_frame: video writer is not open");
    m_sink->stage_frame(rows);
}
void VideoWriter::encode_staged() {
    if (!m_sink) throw ValueError("encode_staged: video writer is not open");
    m_sink->encode_staged();
}
bool VideoWriter::takes_yuv420() const { return m_sink && m_sink->takes_yuv420(); }
void VideoWriter::stage_yuv420(const Yuv420Source& rows) {
    if (!m_sink) throw ValueError("stage_yuv420: video writer is not open");
    m_sink->stage_yuv420(rows);
}
void VideoWriter::stage_shaded(const Frame& field, const Shader& shader) {
    if (takes_yuv420()) {
        stage_yuv420([&](int y0, int y1, const Yuv420Planes& planes) {
            shader.rows_yuv420(field, y0, y1, planes);
        });
    } else {
        stage_frame([&](int y0, int y1, float* rgb) { shader.rows(field, y0, y1, rgb); });
    }
}
void VideoWriter::close() {
    if (m_sink) m_sink->close();
}
void VideoWriter::abort() {
    if (m_sink) m_sink->abort();
}
int VideoWriter::frames_written() const { return m_sink ? m_sink->frames_written() : 0; }
bool VideoWriter::is_open() const { return m_sink && m_sink->is_open(); }

void quiet_video_logs() { io_module().quiet_video_logs(); }
VideoInfo probe_video(const std::string& path) { return io_module().probe_video(path); }
std::vector<std::vector<float>> decode_video_luma(const std::string& path, int& width,
                                                  int& height) {
    return io_module().decode_video_luma(path, width, height);
}

}  // namespace impulse::output
