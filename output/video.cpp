// SPDX-License-Identifier: Apache-2.0
// Video files through FFmpeg's libav* (FFmpeg 5.1 API: send/receive, AVCodecParameters).
// Writing: for 8-bit YUV 4:2:0 codecs (h264, vp9) the picture is filled band by band in
// parallel, straight from the shading (Shader::rows_yuv420) or from float RGB
// (rgb_rows_to_yuv420): BT.709 limited range, centre-sited chroma, no swscale. For the others
// float RGB is quantised to 8- or 16-bit RGB, band by band, and converted by swscale to the
// codec's pixel format (BT.709, limited range for YUV targets). Then encoded and muxed into a
// temporary file beside the target, which close() renames into place. Reading: decode every
// frame, for probing and for luma analysis.

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/dict.h>
#include <libavutil/error.h>
#include <libavutil/mem.h>
#include <libavutil/opt.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include "output/detail/io_impl.h"
#include "output/files.h"
#include "output/video.h"
#include "numeric/errors.h"

namespace impulse::output {
namespace {

namespace fs = std::filesystem;

// --- libav plumbing --------------------------------------------------------------------------

std::string av_error_text(int err) {
    char buf[AV_ERROR_MAX_STRING_SIZE] = {};
    av_strerror(err, buf, sizeof buf);
    return buf;
}

/// Turn a libav return code into the house error shape: "<path>: <what>: <av_strerror text>".
[[noreturn]] void throw_av(const std::string& path, const std::string& what, int err) {
    throw IoError(path + ": " + what + ": " + av_error_text(err));
}

struct OutputFormatDeleter {
    void operator()(AVFormatContext* f) const {
        if (f->pb && !(f->oformat->flags & AVFMT_NOFILE)) avio_closep(&f->pb);
        avformat_free_context(f);
    }
};
struct InputFormatDeleter {
    void operator()(AVFormatContext* f) const { avformat_close_input(&f); }
};
struct CodecContextDeleter {
    void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct FrameDeleter {
    void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct PacketDeleter {
    void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct SwsDeleter {
    void operator()(SwsContext* s) const { sws_freeContext(s); }
};
struct AvFreeDeleter {
    void operator()(uint8_t* p) const { av_free(p); }
};

using OutputFormatPtr = std::unique_ptr<AVFormatContext, OutputFormatDeleter>;
using InputFormatPtr = std::unique_ptr<AVFormatContext, InputFormatDeleter>;
using CodecContextPtr = std::unique_ptr<AVCodecContext, CodecContextDeleter>;
using FramePtr = std::unique_ptr<AVFrame, FrameDeleter>;
using PacketPtr = std::unique_ptr<AVPacket, PacketDeleter>;
using SwsPtr = std::unique_ptr<SwsContext, SwsDeleter>;
using AvBuffer = std::unique_ptr<uint8_t, AvFreeDeleter>;

/// Local paths are handed to libav as "file:" URLs, so a name with a colon ("a:b.mp4") is never
/// taken for a protocol.
std::string file_url(const std::string& path) { return "file:" + path; }

/// Row stride padded to 64 bytes: swscale's SIMD paths want 16-byte aligned rows and warns
/// (and slows down) otherwise.
int aligned_stride(int bytes) { return (bytes + 63) / 64 * 64; }

AvBuffer alloc_buffer(size_t bytes) {
    AvBuffer buf(static_cast<uint8_t*>(av_malloc(bytes)));
    if (!buf) throw std::bad_alloc();
    return buf;
}

/// A swscale context with explicit ranges and BT.709 coefficients. The ranges are options set
/// before sws_init_context, so the path chosen at init (unscaled copies included) already knows
/// them; sws_setColorspaceDetails then installs the BT.709 tables.
SwsPtr make_sws(int width, int height, AVPixelFormat src, bool src_full_range, AVPixelFormat dst,
                bool dst_full_range, const std::string& path) {
    SwsPtr sws(sws_alloc_context());
    if (!sws) throw std::bad_alloc();
    // Same size in and out, so the filter only matters for 4:2:0 chroma; ACCURATE_RND keeps
    // the rounding exact (and avoids the approximate bgr24 -> yv12 fast path).
    const int64_t flags = SWS_BICUBIC | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP;
    av_opt_set_int(sws.get(), "srcw", width, 0);
    av_opt_set_int(sws.get(), "srch", height, 0);
    av_opt_set_int(sws.get(), "src_format", src, 0);
    av_opt_set_int(sws.get(), "dstw", width, 0);
    av_opt_set_int(sws.get(), "dsth", height, 0);
    av_opt_set_int(sws.get(), "dst_format", dst, 0);
    av_opt_set_int(sws.get(), "sws_flags", flags, 0);
    av_opt_set_int(sws.get(), "src_range", src_full_range ? 1 : 0, 0);
    av_opt_set_int(sws.get(), "dst_range", dst_full_range ? 1 : 0, 0);
    int err = sws_init_context(sws.get(), nullptr, nullptr);
    if (err < 0) throw_av(path, "cannot set up pixel conversion", err);

    const bool src_rgb = av_pix_fmt_desc_get(src)->flags & AV_PIX_FMT_FLAG_RGB;
    const bool dst_rgb = av_pix_fmt_desc_get(dst)->flags & AV_PIX_FMT_FLAG_RGB;
    if (!(src_rgb && dst_rgb)) {
        // The first table is used for YUV -> RGB, the second for RGB -> YUV/grey: BT.709 both.
        const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
        err = sws_setColorspaceDetails(sws.get(), bt709, src_full_range ? 1 : 0, bt709,
                                       dst_full_range ? 1 : 0, 0, 1 << 16, 1 << 16);
        if (err < 0) throw_av(path, "cannot set BT.709 conversion", AVERROR(EINVAL));
    }
    return sws;
}

// --- containers and codecs -------------------------------------------------------------------

struct CodecSpec {
    VideoCodec codec;
    const char* name;       ///< user-facing name, equal to libav's codec name
    const char* encoder;    ///< libav encoder
    AVPixelFormat pix_fmt;  ///< what the encoder is fed
    bool yuv;               ///< BT.709 limited-range YUV (else full-range RGB)
    bool deep;              ///< > 8 bits per sample: quantise the input to 16-bit RGB
    bool even_sizes;        ///< 4:2:0 chroma: width and height must be even
};

// FFV1 takes bgr0, not gbrp, for 8-bit RGB (libavcodec 59 offers gbrp only at 9+ bits): it is
// stored losslessly through FFV1's reversible colour transform.
constexpr CodecSpec kCodecs[] = {
    {VideoCodec::H264, "h264", "libx264", AV_PIX_FMT_YUV420P, true, false, true},
    {VideoCodec::ProRes, "prores", "prores_ks", AV_PIX_FMT_YUV444P10LE, true, true, false},
    {VideoCodec::FFV1, "ffv1", "ffv1", AV_PIX_FMT_BGR0, false, false, false},
    {VideoCodec::VP9, "vp9", "libvpx-vp9", AV_PIX_FMT_YUV420P, true, false, true},
};

struct ContainerSpec {
    std::string_view ext;              ///< lower case, with the dot
    const char* muxer;                 ///< libav muxer short name
    std::array<VideoCodec, 4> codecs;  ///< accepted codecs, the first is the default
    int n_codecs;
};

constexpr ContainerSpec kContainers[] = {
    {".mp4", "mp4", {VideoCodec::H264}, 1},
    {".mov", "mov", {VideoCodec::ProRes, VideoCodec::H264}, 2},
    {".mkv",
     "matroska",
     {VideoCodec::FFV1, VideoCodec::H264, VideoCodec::ProRes, VideoCodec::VP9},
     4},
    {".webm", "webm", {VideoCodec::VP9}, 1},
};

constexpr std::string_view kPresets[] = {"ultrafast", "superfast", "veryfast", "faster",
                                         "fast",      "medium",    "slow",     "slower",
                                         "veryslow",  "placebo"};

const CodecSpec& codec_spec(VideoCodec codec) {
    for (const CodecSpec& spec : kCodecs) {
        if (spec.codec == codec) return spec;
    }
    throw ValueError("video codec: no encoder for this codec value");
}

const ContainerSpec* find_container(const std::string& path) {
    const std::string ext = lower_extension(path);
    for (const ContainerSpec& spec : kContainers) {
        if (spec.ext == ext) return &spec;
    }
    return nullptr;
}

std::string valid_pairs() {
    std::string out;
    for (const ContainerSpec& c : kContainers) {
        if (!out.empty()) out += ", ";
        out += std::string(c.ext) + " ";
        for (int i = 0; i < c.n_codecs; ++i) {
            if (i > 0) out += "|";
            out += codec_spec(c.codecs[i]).name;
        }
    }
    return out;
}

std::string format_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

/// Best n/d with d <= 1001. av_d2q bounds numerator and denominator alike, so with max 1001 it
/// cannot produce 30000/1001 (NTSC); a search over the 1001 denominators can, and costs nothing.
/// Ties keep the smallest denominator (24 -> 24/1).
AVRational frame_rate(double fps) {
    AVRational best{0, 1};
    double best_err = INFINITY;
    for (int den = 1; den <= 1001; ++den) {
        const double num = std::round(fps * den);
        if (num < 1.0 || num > INT_MAX) continue;
        const double err = std::abs(num / den - fps);
        if (err < best_err - 1e-12 * fps) {
            best = AVRational{static_cast<int>(num), den};
            best_err = err;
        }
    }
    return best;
}

/// Options checked before anything touches the disk; returns the codec to use.
const CodecSpec& validate(const std::string& path, const VideoOptions& o) {
    const ContainerSpec* container = find_container(path);
    if (!container) {
        throw ValueError(path + ": unknown video container \"" + lower_extension(path) +
                         "\": expected one of .mp4, .mov, .mkv, .webm");
    }
    const VideoCodec codec = o.codec == VideoCodec::Auto ? container->codecs[0] : o.codec;
    const CodecSpec& spec = codec_spec(codec);
    bool allowed = false;
    for (int i = 0; i < container->n_codecs; ++i) allowed |= container->codecs[i] == codec;
    if (!allowed) {
        throw ValueError(path + ": codec " + spec.name + " cannot be written to " +
                         std::string(container->ext) + ": valid pairs are " + valid_pairs());
    }

    if (o.width <= 0) {
        throw ValueError(path + ": width = " + std::to_string(o.width) + ": must be > 0");
    }
    if (o.height <= 0) {
        throw ValueError(path + ": height = " + std::to_string(o.height) + ": must be > 0");
    }
    if (spec.even_sizes && (o.width % 2 != 0 || o.height % 2 != 0)) {
        throw ValueError(path + ": size = " + std::to_string(o.width) + "x" +
                         std::to_string(o.height) + ": " + spec.name +
                         " (4:2:0 chroma) needs even sizes: width and height must be even");
    }
    if (!(std::isfinite(o.fps) && o.fps > 0.0) || frame_rate(o.fps).num == 0) {
        throw ValueError(path + ": fps = " + format_number(o.fps) +
                         ": must be > 0 and at least 1/1001");
    }
    if (codec == VideoCodec::H264 && (o.crf < 0 || o.crf > 51)) {
        throw ValueError(path + ": crf = " + std::to_string(o.crf) + ": must be in 0..51 for h264");
    }
    if (codec == VideoCodec::VP9 && (o.crf < 0 || o.crf > 63)) {
        throw ValueError(path + ": crf = " + std::to_string(o.crf) + ": must be in 0..63 for vp9");
    }
    if (codec == VideoCodec::H264) {
        bool known = false;
        std::string names;
        for (std::string_view p : kPresets) {
            known |= p == o.preset;
            names += (names.empty() ? "" : ", ") + std::string(p);
        }
        if (!known) {
            throw ValueError(path + ": preset = \"" + o.preset + "\": expected one of " + names);
        }
    }
    if (o.threads < 0) {
        throw ValueError(path + ": threads = " + std::to_string(o.threads) + ": must be >= 0");
    }
    for (const auto& [key, value] : o.metadata) {
        if (key.empty()) throw ValueError(path + ": metadata key must not be empty");
    }
    return spec;
}

/// Clamp to [0,1] and map NaN to 0 (both comparisons are false for NaN).
inline float clamp01(float v) { return v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; }

}  // namespace

// --- VideoWriter -------------------------------------------------------------------------------

struct Encoder {
    std::string path;    ///< final path as given (used in messages)
    fs::path temp_path;  ///< where the muxer writes until close()
    bool temp_created = false;
    bool open = false;
    int frames = 0;
    int width = 0, height = 0;
    bool deep = false;  ///< 16-bit RGB input to swscale
    bool yuv420 = false;  ///< 8-bit YUV 4:2:0 input, filled without swscale

    OutputFormatPtr format;
    CodecContextPtr encoder;
    AVStream* stream = nullptr;  // owned by `format`
    FramePtr frame;
    PacketPtr packet;
    SwsPtr sws;
    // The input goes through in bands of kBandRows rows (stage_frame): float RGB from the
    // caller, quantised to 8- or 16-bit RGB in one of kBandSlots band buffers, converted by
    // swscale slice by slice, top to bottom, into `frame`. swscale gives the same bytes for any
    // slicing (it keeps the rows its vertical filters need), so no frame-sized RGB buffer is
    // needed: at 4K that saves 100 MiB of float RGB and 24 MiB of 8-bit RGB.
    static constexpr int kBandRows = 16;
    static constexpr int kBandSlots = 8;  ///< bands in flight: threads shading + one converting
    AvBuffer bands;       ///< kBandSlots quantised bands, kBandRows rows of rgb_stride bytes
    int rgb_stride = 0;   ///< bytes per row of a quantised band
    bool staged = false;  ///< `frame` holds a picture not yet encoded
    tbb::enumerable_thread_specific<std::vector<float>> float_band;  ///< per thread

    uint8_t* band_slot(int slot) const {
        return bands.get() + static_cast<size_t>(slot) * kBandRows * rgb_stride;
    }

    /// Clamp, round and store `rows` rows given as floats (3 per pixel) into `dst_rows`.
    void quantise_rows(int rows, const float* src, uint8_t* dst_rows) const {
        const size_t row_values = static_cast<size_t>(width) * 3;
        for (int r = 0; r < rows; ++r, src += row_values) {
            uint8_t* row = dst_rows + static_cast<size_t>(r) * rgb_stride;
            if (deep) {
                auto* dst = reinterpret_cast<uint16_t*>(row);
                for (size_t i = 0; i < row_values; ++i)
                    dst[i] = static_cast<uint16_t>(clamp01(src[i]) * 65535.0f + 0.5f);
            } else {
                for (size_t i = 0; i < row_values; ++i)
                    row[i] = static_cast<uint8_t>(clamp01(src[i]) * 255.0f + 0.5f);
            }
        }
    }

    void stage(const VideoWriter::RowSource& rows);
    void stage_yuv420(const VideoWriter::Yuv420Source& rows);
    void begin_stage();

    /// Free every libav object (closing the temporary file) without writing a trailer.
    void release() {
        sws.reset();
        packet.reset();
        frame.reset();
        encoder.reset();
        format.reset();
        stream = nullptr;
        bands.reset();
    }

    void remove_temp() {
        if (!temp_created) return;
        std::error_code ec;
        fs::remove(temp_path, ec);
        temp_created = false;
    }

    /// Move every packet the encoder has ready into the muxer.
    void drain() {
        for (;;) {
            int err = avcodec_receive_packet(encoder.get(), packet.get());
            if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return;
            if (err < 0) throw_av(path, "cannot encode frame", err);
            // One frame in the encoder time base: the mov muxer takes the last sample's duration
            // from it, and avg_frame_rate on probing is frames / total duration.
            if (packet->duration == 0) packet->duration = 1;
            av_packet_rescale_ts(packet.get(), encoder->time_base, stream->time_base);
            packet->stream_index = stream->index;
            // Takes the packet's reference and leaves `packet` blank for the next receive.
            err = av_interleaved_write_frame(format.get(), packet.get());
            if (err < 0) throw_av(path, "cannot write frame", err);
        }
    }

    void setup(const std::string& final_path, const VideoOptions& o, const CodecSpec& spec);
};

/// The encoder's private options for `spec` (preset and crf for H.264, the 4444 profile for
/// ProRes, FFV1 version 3, VP9 constant quality); some are fields of `c`.
AVDictionary* codec_options(const CodecSpec& spec, const VideoOptions& o, AVCodecContext* c) {
    AVDictionary* codec_opts = nullptr;
    switch (spec.codec) {
        case VideoCodec::H264:
            av_dict_set(&codec_opts, "preset", o.preset.c_str(), 0);
            av_dict_set_int(&codec_opts, "crf", o.crf, 0);
            break;
        case VideoCodec::ProRes:
            av_dict_set(&codec_opts, "profile", "4444", 0);
            break;
        case VideoCodec::FFV1:
            // Version 3: slices (so it can use threads) and per-slice CRCs, the archival setup.
            c->level = 3;
            break;
        case VideoCodec::VP9:
            // Constant quality: crf with b:v 0 (libvpx reads bit_rate 0 as "no target").
            av_dict_set_int(&codec_opts, "crf", o.crf, 0);
            c->bit_rate = 0;
            break;
        case VideoCodec::Auto:
            break;
    }
    return codec_opts;
}

void Encoder::setup(const std::string& final_path, const VideoOptions& o,
                              const CodecSpec& spec) {
    path = final_path;
    width = o.width;
    height = o.height;
    deep = spec.deep;
    yuv420 = spec.pix_fmt == AV_PIX_FMT_YUV420P;
    const ContainerSpec& container = *find_container(path);

    // The directory is checked first so a bad path fails before any libav object or file
    // exists, with the same text avio_open would give.
    const fs::path target(path);
    fs::path dir = target.parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    const fs::file_status dir_status = fs::status(dir, ec);
    if (!fs::exists(dir_status)) throw_av(path, "cannot open for writing", AVERROR(ENOENT));
    if (!fs::is_directory(dir_status)) throw_av(path, "cannot open for writing", AVERROR(ENOTDIR));

    // Same directory (so rename is atomic), hidden, pid-tagged, extension kept.
    temp_path = dir / ("." + target.stem().string() + ".partial-" + std::to_string(::getpid()) +
                       target.extension().string());
    const std::string url = file_url(temp_path.string());

    AVFormatContext* raw_format = nullptr;
    int err = avformat_alloc_output_context2(&raw_format, nullptr, container.muxer, url.c_str());
    if (err < 0) throw_av(path, std::string("cannot set up muxer ") + container.muxer, err);
    format.reset(raw_format);

    const AVCodec* codec = avcodec_find_encoder_by_name(spec.encoder);
    if (!codec) {
        throw_av(path, std::string("cannot use encoder ") + spec.encoder,
                 AVERROR_ENCODER_NOT_FOUND);
    }
    stream = avformat_new_stream(format.get(), nullptr);
    if (!stream) throw std::bad_alloc();
    encoder.reset(avcodec_alloc_context3(codec));
    if (!encoder) throw std::bad_alloc();

    const AVRational rate = frame_rate(o.fps);
    AVCodecContext* c = encoder.get();
    c->width = o.width;
    c->height = o.height;
    c->pix_fmt = spec.pix_fmt;
    c->time_base = av_inv_q(rate);  // pts = frame index
    c->framerate = rate;
    c->sample_aspect_ratio = AVRational{1, 1};
    c->thread_count = o.threads > 0 ? o.threads : kEncoderThreads;
    c->color_primaries = AVCOL_PRI_BT709;
    c->color_trc = AVCOL_TRC_BT709;
    c->colorspace = spec.yuv ? AVCOL_SPC_BT709 : AVCOL_SPC_RGB;
    c->color_range = spec.yuv ? AVCOL_RANGE_MPEG : AVCOL_RANGE_JPEG;
    // rgb_rows_to_yuv420 averages 2x2 blocks: chroma sits at their centre (x264 writes it into
    // the stream's VUI).
    if (yuv420) c->chroma_sample_location = AVCHROMA_LOC_CENTER;
    if (format->oformat->flags & AVFMT_GLOBALHEADER) c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;

    AVDictionary* codec_opts = codec_options(spec, o, c);
    err = avcodec_open2(c, codec, &codec_opts);
    av_dict_free(&codec_opts);
    if (err < 0) throw_av(path, std::string("cannot open encoder ") + spec.encoder, err);

    err = avcodec_parameters_from_context(stream->codecpar, c);
    if (err < 0) throw_av(path, "cannot set stream parameters", err);
    stream->time_base = c->time_base;  // a hint: the muxer may pick its own in write_header
    stream->avg_frame_rate = rate;

    for (const auto& [key, value] : o.metadata) {
        av_dict_set(&format->metadata, key.c_str(), value.c_str(), 0);
    }

    err = avio_open(&format->pb, url.c_str(), AVIO_FLAG_WRITE);
    if (err < 0) throw_av(path, "cannot open for writing", err);
    temp_created = true;

    AVDictionary* mux_opts = nullptr;
    if (container.ext == ".mp4" || container.ext == ".mov") {
        // faststart: moov before mdat so browsers can play while downloading.
        // use_metadata_tags: keep arbitrary keys (seed, scene hash); mov only writes known ones.
        av_dict_set(&mux_opts, "movflags", "+faststart+use_metadata_tags", 0);
    }
    err = avformat_write_header(format.get(), &mux_opts);
    av_dict_free(&mux_opts);
    if (err < 0) throw_av(path, "cannot write header", err);

    frame.reset(av_frame_alloc());
    packet.reset(av_packet_alloc());
    if (!frame || !packet) throw std::bad_alloc();
    frame->format = spec.pix_fmt;
    frame->width = o.width;
    frame->height = o.height;
    frame->color_primaries = c->color_primaries;
    frame->color_trc = c->color_trc;
    frame->colorspace = c->colorspace;
    frame->color_range = c->color_range;
    frame->chroma_location = c->chroma_sample_location;
    err = av_frame_get_buffer(frame.get(), 0);
    if (err < 0) throw_av(path, "cannot allocate frame", err);

    open = true;
    if (yuv420) return;  // no swscale, no quantised bands
    rgb_stride = aligned_stride(o.width * 3 * (deep ? 2 : 1));
    bands = alloc_buffer(static_cast<size_t>(rgb_stride) * kBandRows * kBandSlots);
    sws = make_sws(o.width, o.height, deep ? AV_PIX_FMT_RGB48 : AV_PIX_FMT_RGB24, true,
                   spec.pix_fmt, !spec.yuv, path);
}

/// The libav encoder behind output::VideoWriter.
class LibavSink final : public VideoSink {
public:
    ~LibavSink() override { abort(); }
    void open(const std::string& path, const VideoOptions& options) override;
    void write_frame(const float* rgb) override;
    void stage_frame(const VideoWriter::RowSource& rows) override;
    void encode_staged() override;
    bool takes_yuv420() const override { return is_open() && m_impl->yuv420; }
    void stage_yuv420(const VideoWriter::Yuv420Source& rows) override;
    void close() override;
    void abort() override;
    int frames_written() const override;
    bool is_open() const override;

private:
    std::unique_ptr<Encoder> m_impl;
};

/// Validate, create the temporary file and write the container header.
void LibavSink::open(const std::string& path, const VideoOptions& options) {
    if (is_open()) throw ValueError(path + ": video writer is already open on " + m_impl->path);
    const CodecSpec& spec = validate(path, options);
    auto impl = std::make_unique<Encoder>();
    try {
        impl->setup(path, options, spec);
    } catch (...) {
        impl->release();
        impl->remove_temp();
        throw;
    }
    m_impl = std::move(impl);
}

/// The band pipeline of stage_frame: band indices in order; each band fetched from `rows` and
/// quantised in parallel; converted by swscale in order. At most kBandSlots bands are in flight
/// and they leave the pipeline in order, so band b + kBandSlots reuses the slot of band b only
/// after band b has been converted.
void Encoder::stage(const VideoWriter::RowSource& rows) {
    if (yuv420) {
        // Float RGB converted band by band by rgb_rows_to_yuv420 (the writer's one conversion
        // to 4:2:0, so write_frame and stage_shaded agree within one code value).
        const size_t band_values = static_cast<size_t>(width) * 3 * kBandRows;
        stage_yuv420([&](int y0, int y1, const Yuv420Planes& planes) {
            std::vector<float>& buf = float_band.local();
            buf.resize(band_values);
            rows(y0, y1, buf.data());
            rgb_rows_to_yuv420(buf.data(), width, y1 - y0, planes);
        });
        return;
    }
    begin_stage();
    const int n_bands = (height + kBandRows - 1) / kBandRows;
    const size_t band_values = static_cast<size_t>(width) * 3 * kBandRows;
    int next = 0;
    tbb::parallel_pipeline(
        kBandSlots,
        tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                                    [&](tbb::flow_control& fc) {
                                        if (next == n_bands) fc.stop();
                                        return next++;
                                    }) &
            tbb::make_filter<int, int>(tbb::filter_mode::parallel,
                                       [&](int b) {
                                           std::vector<float>& buf = float_band.local();
                                           buf.resize(band_values);
                                           const int y0 = b * kBandRows;
                                           const int y1 = std::min(height, y0 + kBandRows);
                                           rows(y0, y1, buf.data());
                                           quantise_rows(y1 - y0, buf.data(),
                                                         band_slot(b % kBandSlots));
                                           return b;
                                       }) &
            tbb::make_filter<int, void>(tbb::filter_mode::serial_in_order, [&](int b) {
                const int y0 = b * kBandRows;
                const uint8_t* const src_planes[1] = {band_slot(b % kBandSlots)};
                const int src_strides[1] = {rgb_stride};
                sws_scale(sws.get(), src_planes, src_strides, y0,
                          std::min(kBandRows, height - y0), frame->data, frame->linesize);
            }));
    staged = true;
}

/// The encoder may still hold a reference to the previous frame's buffers: make_writable copies
/// only in that case.
void Encoder::begin_stage() {
    const int err = av_frame_make_writable(frame.get());
    if (err < 0) throw_av(path, "cannot allocate frame", err);
}

/// Bands of kBandRows rows (even: whole chroma rows) in parallel, each written by one task.
void Encoder::stage_yuv420(const VideoWriter::Yuv420Source& rows) {
    begin_stage();
    const int n_bands = (height + kBandRows - 1) / kBandRows;
    tbb::parallel_for(0, n_bands, [&](int b) {
        const int y0 = b * kBandRows, y1 = std::min(height, y0 + kBandRows);
        Yuv420Planes planes;
        planes.y = frame->data[0] + static_cast<ptrdiff_t>(y0) * frame->linesize[0];
        planes.cb = frame->data[1] + static_cast<ptrdiff_t>(y0 / 2) * frame->linesize[1];
        planes.cr = frame->data[2] + static_cast<ptrdiff_t>(y0 / 2) * frame->linesize[2];
        planes.y_stride = frame->linesize[0];
        planes.cb_stride = frame->linesize[1];
        planes.cr_stride = frame->linesize[2];
        rows(y0, y1, planes);
    });
    staged = true;
}

/// Quantise (clamp, round to nearest), convert with swscale and encode one frame.
void LibavSink::write_frame(const float* rgb) {
    if (!is_open()) throw ValueError("write_frame: video writer is not open");
    const size_t row_values = static_cast<size_t>(m_impl->width) * 3;
    m_impl->stage([&](int y0, int y1, float* band) {
        std::copy(rgb + y0 * row_values, rgb + y1 * row_values, band);
    });
    encode_staged();
}

void LibavSink::stage_frame(const VideoWriter::RowSource& rows) {
    if (!is_open()) throw ValueError("stage_frame: video writer is not open");
    m_impl->stage(rows);
}

void LibavSink::stage_yuv420(const VideoWriter::Yuv420Source& rows) {
    if (!is_open()) throw ValueError("stage_yuv420: video writer is not open");
    if (!m_impl->yuv420)
        throw ValueError(m_impl->path + ": stage_yuv420: the encoder does not take YUV 4:2:0");
    m_impl->stage_yuv420(rows);
}

/// Encode the staged frame.
void LibavSink::encode_staged() {
    if (!is_open()) throw ValueError("encode_staged: video writer is not open");
    Encoder& m = *m_impl;
    if (!m.staged) throw ValueError(m.path + ": encode_staged: no frame was staged");
    m.staged = false;
    m.frame->pts = m.frames;
    const int err = avcodec_send_frame(m.encoder.get(), m.frame.get());
    if (err < 0) throw_av(m.path, "cannot encode frame " + std::to_string(m.frames), err);
    m.drain();
    ++m.frames;
}

/// Flush the encoder, write the trailer, flush the file to the disk and rename; on any failure
/// the temporary file is removed and the error rethrown.
void LibavSink::close() {
    if (!is_open()) return;
    Encoder& m = *m_impl;
    if (m.frames == 0) {
        // A container with an empty stream does not even probe (mkv/webm: "End of file"), so
        // no file beats a broken one under the final name.
        abort();
        throw IoError(m.path + ": no frames were written: nothing to save");
    }
    try {
        int err = avcodec_send_frame(m.encoder.get(), nullptr);
        if (err < 0) throw_av(m.path, "cannot flush encoder", err);
        m.drain();
        // Reports the AVIOContext's write errors too (a full disk shows up here).
        err = av_write_trailer(m.format.get());
        if (err < 0) throw_av(m.path, "cannot write trailer", err);
        m.release();
        // Flushed to the disk, renamed, the folder flushed (output/files.h).
        commit_partial(m.temp_path.string(), m.path);
        m.temp_created = false;
        m.open = false;
    } catch (...) {
        abort();
        throw;
    }
}

/// Drop everything written so far; a no-op when not open.
void LibavSink::abort() {
    if (!m_impl) return;
    m_impl->release();
    m_impl->remove_temp();
    m_impl->open = false;
}

/// Frames encoded since the last open() (still valid after close()).
int LibavSink::frames_written() const { return m_impl ? m_impl->frames : 0; }

/// True between a successful open() and close()/abort().
bool LibavSink::is_open() const { return m_impl && m_impl->open; }

// --- reading -----------------------------------------------------------------------------------

namespace {

/// The best video stream of a file with an open decoder.
struct Decoder {
    std::string path;
    InputFormatPtr format;
    CodecContextPtr codec;
    AVStream* stream = nullptr;

    explicit Decoder(const std::string& file) : path(file) {
        AVFormatContext* raw = nullptr;
        const std::string url = file_url(path);
        int err = avformat_open_input(&raw, url.c_str(), nullptr, nullptr);
        if (err < 0) throw_av(path, "cannot open for reading", err);
        format.reset(raw);
        err = avformat_find_stream_info(raw, nullptr);
        if (err < 0) throw_av(path, "cannot read stream info", err);
        const AVCodec* decoder = nullptr;
        err = av_find_best_stream(raw, AVMEDIA_TYPE_VIDEO, -1, -1, &decoder, 0);
        if (err < 0) throw_av(path, "no video stream", err);
        stream = raw->streams[err];
        codec.reset(avcodec_alloc_context3(decoder));
        if (!codec) throw std::bad_alloc();
        err = avcodec_parameters_to_context(codec.get(), stream->codecpar);
        if (err < 0) throw_av(path, "cannot set up decoder", err);
        codec->pkt_timebase = stream->time_base;
        codec->thread_count = 0;  // auto
        err = avcodec_open2(codec.get(), decoder, nullptr);
        if (err < 0) throw_av(path, std::string("cannot open decoder ") + decoder->name, err);
    }

    /// Decode every frame in order, including the ones held back until the final flush.
    template <class OnFrame>
    void for_each_frame(OnFrame&& on_frame) {
        PacketPtr packet(av_packet_alloc());
        FramePtr frame(av_frame_alloc());
        if (!packet || !frame) throw std::bad_alloc();
        auto receive_all = [&] {
            for (;;) {
                const int err = avcodec_receive_frame(codec.get(), frame.get());
                if (err == AVERROR(EAGAIN) || err == AVERROR_EOF) return;
                if (err < 0) throw_av(path, "cannot decode", err);
                on_frame(*frame);
                av_frame_unref(frame.get());
            }
        };
        int err = 0;
        while ((err = av_read_frame(format.get(), packet.get())) >= 0) {
            if (packet->stream_index == stream->index) {
                err = avcodec_send_packet(codec.get(), packet.get());
                av_packet_unref(packet.get());
                if (err < 0) throw_av(path, "cannot decode", err);
                receive_all();
            } else {
                av_packet_unref(packet.get());
            }
        }
        if (err != AVERROR_EOF) throw_av(path, "cannot read", err);
        err = avcodec_send_packet(codec.get(), nullptr);
        if (err < 0) throw_av(path, "cannot flush decoder", err);
        receive_all();
    }
};

}  // namespace

namespace io {

std::unique_ptr<VideoSink> make_video_sink() { return std::make_unique<LibavSink>(); }

/// Decodes the whole file: frame_count is what a player would show, not the header's claim.
VideoInfo probe_video(const std::string& path) {
    Decoder dec(path);
    VideoInfo info;
    dec.for_each_frame([&](const AVFrame&) { ++info.frame_count; });
    info.width = dec.codec->width;
    info.height = dec.codec->height;
    AVRational rate = dec.stream->avg_frame_rate;
    if (rate.num <= 0 || rate.den <= 0) rate = dec.stream->r_frame_rate;
    info.fps = rate.num > 0 && rate.den > 0 ? av_q2d(rate) : 0.0;
    info.codec_name = avcodec_get_name(dec.stream->codecpar->codec_id);
    const char* pix = av_get_pix_fmt_name(static_cast<AVPixelFormat>(dec.stream->codecpar->format));
    info.pixel_format = pix ? pix : "";
    return info;
}

/// Luma through swscale: YUV sources give their Y plane expanded to full range; RGB sources
/// (FFV1) are reduced with BT.709 weights. Sources deeper than 8 bits go through GRAY16.
std::vector<std::vector<float>> decode_video_luma(const std::string& path, int& width,
                                                  int& height) {
    Decoder dec(path);
    std::vector<std::vector<float>> frames;
    width = dec.codec->width;
    height = dec.codec->height;

    SwsPtr sws;
    AVPixelFormat sws_src = AV_PIX_FMT_NONE;
    bool sws_full = false;
    AvBuffer grey;
    int grey_stride = 0;
    bool deep = false;

    dec.for_each_frame([&](const AVFrame& f) {
        if (f.width != width || f.height != height) {
            throw IoError(path + ": frame " + std::to_string(frames.size()) + " is " +
                          std::to_string(f.width) + "x" + std::to_string(f.height) + ", expected " +
                          std::to_string(width) + "x" + std::to_string(height));
        }
        const auto src = static_cast<AVPixelFormat>(f.format);
        const AVPixFmtDescriptor* desc = av_pix_fmt_desc_get(src);
        const bool rgb = desc->flags & AV_PIX_FMT_FLAG_RGB;
        // Unspecified range on YUV means limited (the MPEG convention); RGB is always full.
        const bool full = rgb || f.color_range == AVCOL_RANGE_JPEG;
        if (!sws || src != sws_src || full != sws_full) {
            deep = desc->comp[0].depth > 8;
            const AVPixelFormat dst = deep ? AV_PIX_FMT_GRAY16 : AV_PIX_FMT_GRAY8;
            sws = make_sws(width, height, src, full, dst, true, path);
            sws_src = src;
            sws_full = full;
            grey_stride = aligned_stride(width * (deep ? 2 : 1));
            grey = alloc_buffer(static_cast<size_t>(grey_stride) * height);
        }
        uint8_t* dst_planes[1] = {grey.get()};
        const int dst_strides[1] = {grey_stride};
        sws_scale(sws.get(), f.data, f.linesize, 0, height, dst_planes, dst_strides);

        std::vector<float> luma(static_cast<size_t>(width) * height);
        for (int y = 0; y < height; ++y) {
            const uint8_t* row = grey.get() + static_cast<size_t>(y) * grey_stride;
            float* out = luma.data() + static_cast<size_t>(y) * width;
            if (deep) {
                const auto* row16 = reinterpret_cast<const uint16_t*>(row);
                for (int x = 0; x < width; ++x) out[x] = row16[x] * (1.0f / 65535.0f);
            } else {
                for (int x = 0; x < width; ++x) out[x] = row[x] * (1.0f / 255.0f);
            }
        }
        frames.push_back(std::move(luma));
    });
    return frames;
}

void quiet_video_logs() { av_log_set_level(AV_LOG_QUIET); }

}  // namespace io
}  // namespace impulse::output
