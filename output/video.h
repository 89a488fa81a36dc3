// SPDX-License-Identifier: Apache-2.0
#pragma once
// Video output through FFmpeg's libav*: H.264/MP4 (default), ProRes 4444/MOV, FFV1/MKV, VP9/WebM.
// Part of impulse::output; included by output/output.h. The encoder lives in the image and video
// module, loaded when the first video is opened (io_module.h).

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "output/shading.h"

namespace impulse::output {

/// Codec choices. `Auto` picks from the container: .mp4 -> h264, .mov -> prores,
/// .mkv -> ffv1, .webm -> vp9.
enum class VideoCodec { Auto, H264, ProRes, FFV1, VP9 };

/// Options for a video file. Validated by `VideoWriter::open`, which throws `IoError`
/// or `ValueError` with a one-line message.
struct VideoOptions {
    int width = 0;             ///< frame width in pixels, > 0 (h264/vp9 need even sizes: odd sizes are refused)
    int height = 0;            ///< frame height in pixels, > 0
    double fps = 30.0;         ///< frames per second, > 0 (rational approximation with denominator <= 1001)
    VideoCodec codec = VideoCodec::Auto;
    int crf = 18;              ///< constant rate factor for h264 (0..51) and vp9 (0..63)
    std::string preset = "medium";  ///< x264 preset: ultrafast .. veryslow
    /// Encoder threads, 0 = kEncoderThreads. Never "as many as the machine has": x264 and libvpx
    /// write different bytes for different thread counts, so a fixed count keeps a scene's video
    /// the same on every machine.
    int threads = 0;
    std::vector<std::pair<std::string, std::string>> metadata;  ///< container metadata (seed, scene hash ...)
};

/// The encoder threads when VideoOptions::threads is 0. x264 (frame threads, its default) writes
/// the same bytes run after run for a given count; 2 is measured in bench/README.md ("drift
/// end to end") on 2 cores: more threads only add CPU time and lookahead memory.
constexpr int kEncoderThreads = 2;

/// Parse a codec name ("auto", "h264", "prores", "ffv1", "vp9"); throws ValueError listing the
/// valid names.
VideoCodec video_codec_from_string(const std::string& name);
/// True when `path` ends in a video container extension (.mp4 .mov .mkv .webm), case-insensitive.
bool is_video_path(const std::string& path);

class VideoSink;

/// Writes frames of RGB float data (linear [0,1] values, 3 floats per pixel, row-major, top row
/// first) to a video file. 8-bit YUV 4:2:0 codecs (h264, vp9) get rgb_rows_to_yuv420's BT.709
/// limited-range, centre-sited conversion (declared in the stream); the others go through
/// swscale. The file is written to a temporary name beside `path` and renamed
/// on `close()`, so an interrupted run never leaves a half-written file under the final name,
/// but `close()` is also called by `finish_partial()` for Ctrl-C: it flushes the encoder and
/// writes the trailer so what was encoded stays playable, then renames.
class VideoWriter {
public:
    VideoWriter();
    ~VideoWriter();  ///< if open and not closed: aborts (removes the temporary file)
    VideoWriter(const VideoWriter&) = delete;
    VideoWriter& operator=(const VideoWriter&) = delete;

    /// Open `path` for writing. Throws IoError (with av_strerror text) if the directory does not
    /// exist or is not writable, ValueError for an unknown container/codec combination.
    void open(const std::string& path, const VideoOptions& options);
    /// Encode one frame: `rgb` has width*height*3 floats, clamped to [0,1] and quantised with
    /// rounding (the documented display mapping); throws IoError on encoder failure.
    void write_frame(const float* rgb);

    /// Fills rows [y0, y1) of a frame as RGB floats (3 per pixel, width * 3 per row, row y0
    /// first) into its third argument. Called in parallel for disjoint bands of rows.
    using RowSource = std::function<void(int y0, int y1, float* rgb)>;
    /// The first half of write_frame, without a frame-sized buffer: take the frame from `rows`
    /// a band of rows at a time (bands in parallel), quantise each band as write_frame does and
    /// convert it into the encoder's input picture (same bytes as write_frame). `encode_staged`
    /// then encodes it. Must not run while `encode_staged` runs; throws IoError.
    void stage_frame(const RowSource& rows);
    /// The second half: encode the staged picture. A caller may run it on another thread while
    /// it renders the next frame. Throws IoError on encoder failure, ValueError if no frame was
    /// staged.
    void encode_staged();
    /// True when the encoder takes 8-bit YUV 4:2:0 (h264, vp9): stage_yuv420 then fills its
    /// input picture directly. False before open().
    bool takes_yuv420() const;
    /// Fills rows [y0, y1) of the encoder's 8-bit YUV 4:2:0 picture (y0 even, y1 even or the
    /// height) through the planes given, which point at row y0 (chroma row y0 / 2). Called in
    /// parallel for disjoint bands of rows.
    using Yuv420Source = std::function<void(int y0, int y1, const Yuv420Planes& planes)>;
    /// stage_frame for an encoder that takes YUV 4:2:0: `rows` writes the encoder's input planes
    /// band by band (in parallel) with no conversion after it. Throws ValueError when
    /// takes_yuv420() is false.
    void stage_yuv420(const Yuv420Source& rows);
    /// Stage `field` shaded by `shader`: straight into the planes (Shader::rows_yuv420) when
    /// the encoder takes YUV 4:2:0, else through stage_frame (Shader::rows). What `impulse
    /// render` and `impulse encode` both call, so they write the same video.
    void stage_shaded(const Frame& field, const Shader& shader);
    /// Flush, write the trailer, rename the temporary file to the final path.
    void close();
    /// Close what was written so far into a playable file (used on interruption).
    void finish_partial() { close(); }
    /// Remove the temporary file without producing output.
    void abort();
    int frames_written() const;
    bool is_open() const;

private:
    std::unique_ptr<VideoSink> m_sink;  ///< the module's encoder (io_module.h)
};

/// Silence libav's console logging (x264 and the muxers are chatty at info level, and its own
/// error lines would come before ours): its failures reach the user as our one-line errors, with
/// av_strerror's text. Process-wide; the CLI calls it once at start.
void quiet_video_logs();

/// What `probe_video` found in a file (used by tests and `impulse analyze`).
struct VideoInfo {
    int width = 0, height = 0;
    int frame_count = 0;      ///< frames actually decoded
    double fps = 0.0;         ///< average frame rate from the stream
    std::string codec_name;   ///< libav codec name, e.g. "h264"
    std::string pixel_format; ///< e.g. "yuv420p"
};

/// Decode a whole video and report its properties; throws IoError on failure.
VideoInfo probe_video(const std::string& path);

/// Decode every frame of a video to grey (luma, [0,1] floats); one vector per frame.
/// Used by `impulse analyze` on videos and by tests.
std::vector<std::vector<float>> decode_video_luma(const std::string& path, int& width, int& height);

}  // namespace impulse::output
