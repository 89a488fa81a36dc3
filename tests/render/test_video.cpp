// SPDX-License-Identifier: Apache-2.0
// Video writer and reader: container/codec round trips, pixel content through the encoders,
// temporary-file handling and error messages. Small frames (64x48, 12-20 frames) keep it fast.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tests/support.h"
#include "output/video.h"
#include "numeric/errors.h"

namespace {

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using Catch::Matchers::EndsWith;
using Catch::Matchers::StartsWith;
using impulse::output::decode_video_luma;
using impulse::output::is_video_path;
using impulse::output::probe_video;
using impulse::output::video_codec_from_string;
using impulse::output::VideoCodec;
using impulse::output::VideoOptions;
using impulse::output::VideoWriter;

constexpr int kWidth = 64;
constexpr int kHeight = 48;
constexpr double kNtsc = 30000.0 / 1001.0;

using impulse::test::TempDir;

/// Smooth colour gradient moving 3 px right and 2 px down per frame: R varies with x, G with y,
/// B along the diagonal. Smooth so lossy codecs have no edges to ring on; distinct channels so a
/// wrong luma matrix or a channel swap shows up.
std::vector<float> gradient_frame(int w, int h, int t) {
    constexpr float kTwoPi = 6.28318530718f;
    std::vector<float> rgb(static_cast<size_t>(w) * h * 3);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            float* p = &rgb[(static_cast<size_t>(y) * w + x) * 3];
            p[0] = 0.5f + 0.45f * std::sin(kTwoPi * static_cast<float>(x + 3 * t) / w);
            p[1] = 0.5f + 0.45f * std::cos(kTwoPi * static_cast<float>(y + 2 * t) / h);
            p[2] = 0.5f + 0.45f * std::sin(kTwoPi * static_cast<float>(x + y + 5 * t) / (w + h));
        }
    }
    return rgb;
}

/// Luma of an RGB frame with the given weights (BT.709: 0.2126, 0.7152, 0.0722).
std::vector<float> luma_of(const std::vector<float>& rgb, double kr, double kg, double kb) {
    std::vector<float> y(rgb.size() / 3);
    for (size_t i = 0; i < y.size(); ++i) {
        y[i] = static_cast<float>(kr * rgb[3 * i] + kg * rgb[3 * i + 1] + kb * rgb[3 * i + 2]);
    }
    return y;
}
std::vector<float> bt709_luma(const std::vector<float>& rgb) {
    return luma_of(rgb, 0.2126, 0.7152, 0.0722);
}

float max_abs_diff(const std::vector<float>& a, const std::vector<float>& b) {
    float m = 0.0f;
    for (size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

VideoOptions small_options(VideoCodec codec = VideoCodec::Auto, double fps = 24.0) {
    VideoOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.fps = fps;
    o.codec = codec;
    return o;
}

/// Write `n` gradient frames to `path` and close.
void write_gradient(const std::string& path, const VideoOptions& o, int n) {
    VideoWriter writer;
    writer.open(path, o);
    for (int t = 0; t < n; ++t) writer.write_frame(gradient_frame(o.width, o.height, t).data());
    writer.close();
}

/// Run `f`, require it to throw E, return the message.
template <class E, class F>
std::string thrown_message(F&& f) {
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    FAIL("expected an exception, none was thrown");
    return {};
}

}  // namespace

TEST_CASE("video_codec_from_string parses the names and lists them on failure", "[render][video]") {
    CHECK(video_codec_from_string("auto") == VideoCodec::Auto);
    CHECK(video_codec_from_string("h264") == VideoCodec::H264);
    CHECK(video_codec_from_string("prores") == VideoCodec::ProRes);
    CHECK(video_codec_from_string("ffv1") == VideoCodec::FFV1);
    CHECK(video_codec_from_string("vp9") == VideoCodec::VP9);
    const std::string msg =
        thrown_message<impulse::ValueError>([] { video_codec_from_string("xvid"); });
    CHECK(msg == "codec = \"xvid\": expected one of auto, h264, prores, ffv1, vp9");
}

TEST_CASE("is_video_path recognises the four containers in any case", "[render][video]") {
    CHECK(is_video_path("out/a.mp4"));
    CHECK(is_video_path("a.MOV"));
    CHECK(is_video_path("dir.x/a.mkv"));
    CHECK(is_video_path("a.WebM"));
    CHECK_FALSE(is_video_path("a.png"));
    CHECK_FALSE(is_video_path("mp4"));
    CHECK_FALSE(is_video_path("a.mp4.exr"));
}

TEST_CASE("each container round-trips size, frame count, fps and codec", "[render][video]") {
    struct Case {
        const char* ext;
        double fps;
        const char* codec;
        const char* pixel_format;
    };
    const Case c =
        GENERATE(Case{"mp4", 24.0, "h264", "yuv420p"}, Case{"mov", kNtsc, "prores", "yuv444p12le"},
                 Case{"mkv", 24.0, "ffv1", "bgr0"}, Case{"webm", kNtsc, "vp9", "yuv420p"});
    DYNAMIC_SECTION(c.ext << " / " << c.codec) {
        TempDir dir;
        const std::string path = dir.file(std::string("clip.") + c.ext);
        constexpr int kFrames = 12;
        write_gradient(path, small_options(VideoCodec::Auto, c.fps), kFrames);

        const auto info = probe_video(path);
        CHECK(info.width == kWidth);
        CHECK(info.height == kHeight);
        CHECK(info.frame_count == kFrames);
        // Matroska stores the frame duration in whole ns (33366666 for NTSC): 3e-7 fps off.
        // epsilon(0): Approx's default relative slack (3.6e-4 here) would accept 989/33, the
        // best fraction with numerator and denominator <= 1001.
        CHECK(info.fps == Approx(c.fps).epsilon(0).margin(1e-5));
        CHECK(info.codec_name == c.codec);
        CHECK(info.pixel_format == c.pixel_format);
    }
}

TEST_CASE("the other accepted container/codec pairs also work", "[render][video]") {
    struct Case {
        const char* ext;
        VideoCodec codec;
        const char* name;
    };
    const Case c =
        GENERATE(Case{"mov", VideoCodec::H264, "h264"}, Case{"mkv", VideoCodec::H264, "h264"},
                 Case{"mkv", VideoCodec::ProRes, "prores"}, Case{"mkv", VideoCodec::VP9, "vp9"});
    DYNAMIC_SECTION(c.ext << " / " << c.name) {
        TempDir dir;
        const std::string path = dir.file(std::string("clip.") + c.ext);
        write_gradient(path, small_options(c.codec), 6);
        const auto info = probe_video(path);
        CHECK(info.frame_count == 6);
        CHECK(info.codec_name == c.name);
    }
}

TEST_CASE("decoded luma matches the BT.709 luma of the input", "[render][video]") {
    struct Case {
        const char* ext;
        VideoCodec codec;
        int crf;
        float tolerance;
    };
    // FFV1 stores the 8-bit RGB losslessly. Error budget, in units of 1/255: quantising each
    // input channel to 8 bits moves the weighted sum by <= 0.5 (the weights sum to 1); swscale's
    // RGB -> GRAY8 rounds its output, <= 0.5; its 15-bit fixed-point weights add well under 0.1.
    // Total 1.1/255; tolerance 1.5/255.
    //
    // H.264 at crf 0 is lossless in yuv420p, and luma is computed per pixel before chroma
    // subsampling, so only quantisation remains: input 0.5/255, Y to 8-bit limited range
    // 0.5/219, expanding Y back to full-range GRAY8 0.5/255, fixed-point slack 0.1/255.
    // Total 1.68/255; tolerance 2.5/255.
    //
    // ProRes 4444 is lossy (10-bit DCT; input quantised to 16 bits, read back through GRAY16).
    // Empirical, not derived: the max error measured on this smooth content is 0.44/255;
    // tolerance 1.5/255 leaves 3x room and stays far below the frame-to-frame change and the
    // BT.601/BT.709 difference (both checked below).
    const Case c = GENERATE(Case{"mkv", VideoCodec::FFV1, 18, 1.5f / 255.0f},
                            Case{"mp4", VideoCodec::H264, 0, 2.5f / 255.0f},
                            Case{"mov", VideoCodec::ProRes, 18, 1.5f / 255.0f});
    constexpr int kFrames = 20;

    DYNAMIC_SECTION(c.ext) {
        TempDir dir;
        const std::string path = dir.file(std::string("content.") + c.ext);
        VideoOptions o = small_options(c.codec);
        o.crf = c.crf;
        write_gradient(path, o, kFrames);

        int w = 0, h = 0;
        const auto frames = decode_video_luma(path, w, h);
        REQUIRE(w == kWidth);
        REQUIRE(h == kHeight);
        REQUIRE(frames.size() == static_cast<size_t>(kFrames));

        for (int t = 0; t < kFrames; ++t) {
            const auto rgb = gradient_frame(kWidth, kHeight, t);
            const auto expected = bt709_luma(rgb);
            REQUIRE(frames[t].size() == expected.size());
            INFO("frame " << t);
            CHECK(max_abs_diff(frames[t], expected) <= c.tolerance);
            // The test can fail: a dropped, repeated or reordered frame, or a BT.601 matrix,
            // moves luma by much more than the tolerance.
            if (t + 1 < kFrames) {
                const auto next = bt709_luma(gradient_frame(kWidth, kHeight, t + 1));
                CHECK(max_abs_diff(next, expected) > 4 * c.tolerance);
            }
            CHECK(max_abs_diff(luma_of(rgb, 0.299, 0.587, 0.114), expected) > 4 * c.tolerance);
        }
    }
}

TEST_CASE("stage_frame + encode_staged write what write_frame writes, band by band",
          "[render][video]") {
    // The writer converts a frame in bands of rows (16 at present); heights that are not a
    // multiple of the band and odd sizes exercise the last, short band. Each staged frame must
    // ask for every row exactly once and decode to exactly what write_frame gives; FFV1 and
    // H.264 at crf 0 are lossless, so the decoded luma is also held to the bound derived in
    // "decoded luma matches the BT.709 luma of the input" (a band written to the wrong rows
    // would be off by far more).
    struct Case {
        const char* ext;
        VideoCodec codec;
        int width, height;
        float tolerance;
    };
    const Case c = GENERATE(Case{"mkv", VideoCodec::FFV1, 63, 37, 1.5f / 255.0f},
                            Case{"mp4", VideoCodec::H264, 64, 38, 2.5f / 255.0f},
                            Case{"mov", VideoCodec::ProRes, 65, 17, 1.5f / 255.0f});
    DYNAMIC_SECTION(c.ext << " " << c.width << "x" << c.height) {
        TempDir dir;
        VideoOptions o = small_options(c.codec);
        o.width = c.width, o.height = c.height, o.crf = 0;
        constexpr int kFrames = 5;
        write_gradient(dir.file(std::string("whole.") + c.ext), o, kFrames);
        {
            VideoWriter writer;
            writer.open(dir.file(std::string("staged.") + c.ext), o);
            for (int t = 0; t < kFrames; ++t) {
                const auto rgb = gradient_frame(c.width, c.height, t);
                std::vector<std::atomic<int>> asked(static_cast<size_t>(c.height));
                const size_t row = static_cast<size_t>(c.width) * 3;
                writer.stage_frame([&](int y0, int y1, float* band) {
                    for (int y = y0; y < y1; ++y) ++asked[static_cast<size_t>(y)];
                    std::copy(rgb.begin() + y0 * row, rgb.begin() + y1 * row, band);
                });
                CHECK(std::all_of(asked.begin(), asked.end(), [](const auto& a) { return a == 1; }));
                writer.encode_staged();
            }
            writer.close();
        }
        int w = 0, h = 0;
        const auto whole = decode_video_luma(dir.file(std::string("whole.") + c.ext), w, h);
        const auto staged = decode_video_luma(dir.file(std::string("staged.") + c.ext), w, h);
        REQUIRE(w == c.width);
        REQUIRE(h == c.height);
        REQUIRE(staged.size() == static_cast<size_t>(kFrames));
        REQUIRE(whole.size() == staged.size());
        for (int t = 0; t < kFrames; ++t) {
            INFO("frame " << t);
            CHECK(staged[t] == whole[t]);
            CHECK(max_abs_diff(staged[t], bt709_luma(gradient_frame(c.width, c.height, t))) <=
                  c.tolerance);
        }
    }
}

TEST_CASE("encode_staged without a staged frame is a ValueError", "[render][video]") {
    TempDir dir;
    VideoWriter writer;
    writer.open(dir.file("none.mp4"), small_options());
    const std::string msg = thrown_message<impulse::ValueError>([&] { writer.encode_staged(); });
    CHECK_THAT(msg, Contains("no frame was staged"));
    writer.abort();
}

TEST_CASE("input is clamped to [0,1] and rounded to the nearest 8-bit level", "[render][video]") {
    // FFV1 keeps the 8-bit RGB exactly and grey input reduces to the same grey level (the
    // BT.709 weights sum to 1 within 1/32768), so the decoded level is exact: 0.25/255 only
    // absorbs float printing. (k + 0.4)/255 and (k + 0.6)/255 separate rounding from truncation.
    TempDir dir;
    const std::string path = dir.file("levels.mkv");
    const float values[] = {1.7f, -0.3f, std::numeric_limits<float>::quiet_NaN(), 100.4f / 255.0f,
                            100.6f / 255.0f};
    const float expected[] = {1.0f, 0.0f, 0.0f, 100.0f / 255.0f, 101.0f / 255.0f};
    {
        VideoWriter writer;
        writer.open(path, small_options(VideoCodec::FFV1));
        for (float v : values) {
            std::vector<float> rgb(static_cast<size_t>(kWidth) * kHeight * 3, v);
            writer.write_frame(rgb.data());
        }
        writer.close();
    }
    int w = 0, h = 0;
    const auto frames = decode_video_luma(path, w, h);
    REQUIRE(frames.size() == std::size(values));
    for (size_t i = 0; i < frames.size(); ++i) {
        INFO("frame " << i << ", expected " << expected[i] * 255.0f << "/255");
        const auto [lo, hi] = std::minmax_element(frames[i].begin(), frames[i].end());
        CHECK(*lo >= expected[i] - 0.25f / 255.0f);
        CHECK(*hi <= expected[i] + 0.25f / 255.0f);
    }
}

TEST_CASE("frames go to a hidden temporary file that close() renames", "[render][video]") {
    TempDir dir;
    const std::string path = dir.file("clip.mp4");
    VideoWriter writer;
    CHECK_FALSE(writer.is_open());
    writer.open(path, small_options());
    CHECK(writer.is_open());
    for (int t = 0; t < 3; ++t) writer.write_frame(gradient_frame(kWidth, kHeight, t).data());
    CHECK(writer.frames_written() == 3);

    const auto during = dir.entries();
    REQUIRE(during.size() == 1);
    CHECK_THAT(during[0], StartsWith(".clip.partial-" + std::to_string(::getpid())));
    CHECK_THAT(during[0], EndsWith(".mp4"));

    writer.close();
    CHECK_FALSE(writer.is_open());
    CHECK(writer.frames_written() == 3);
    CHECK(dir.entries() == std::vector<std::string>{"clip.mp4"});
    CHECK(probe_video(path).frame_count == 3);
    writer.close();  // a second close is a no-op
    CHECK(dir.entries() == std::vector<std::string>{"clip.mp4"});
}

TEST_CASE("abort and the destructor leave nothing behind", "[render][video]") {
    TempDir dir;
    SECTION("abort") {
        VideoWriter writer;
        writer.open(dir.file("clip.mkv"), small_options());
        writer.write_frame(gradient_frame(kWidth, kHeight, 0).data());
        REQUIRE(dir.entries().size() == 1);
        writer.abort();
        CHECK_FALSE(writer.is_open());
        CHECK(dir.entries().empty());
        writer.close();  // no-op after abort
        CHECK(dir.entries().empty());
    }
    SECTION("destructor without close") {
        {
            VideoWriter writer;
            writer.open(dir.file("clip.mp4"), small_options());
            writer.write_frame(gradient_frame(kWidth, kHeight, 0).data());
            REQUIRE(dir.entries().size() == 1);
        }
        CHECK(dir.entries().empty());
    }
}

TEST_CASE("finish_partial leaves a playable file with the frames written so far",
          "[render][video]") {
    const char* ext = GENERATE("mp4", "mkv", "webm");
    DYNAMIC_SECTION(ext) {
        TempDir dir;
        const std::string path = dir.file(std::string("interrupted.") + ext);
        VideoWriter writer;
        writer.open(path, small_options());
        for (int t = 0; t < 5; ++t) writer.write_frame(gradient_frame(kWidth, kHeight, t).data());
        writer.finish_partial();
        CHECK(dir.entries() == std::vector<std::string>{std::string("interrupted.") + ext});
        CHECK(probe_video(path).frame_count == 5);
    }
}

TEST_CASE("closing without frames saves nothing and says so", "[render][video]") {
    TempDir dir;
    VideoWriter writer;
    writer.open(dir.file("empty.mp4"), small_options());
    const std::string msg = thrown_message<impulse::IoError>([&] { writer.close(); });
    CHECK_THAT(msg, Contains("empty.mp4: no frames were written"));
    CHECK_FALSE(writer.is_open());
    CHECK(dir.entries().empty());
}

TEST_CASE("a missing output directory is an IoError naming the path", "[render][video]") {
    TempDir dir;
    const std::string path = dir.file("missing/clip.mp4");
    VideoWriter writer;
    const std::string msg =
        thrown_message<impulse::IoError>([&] { writer.open(path, small_options()); });
    CHECK(msg == path + ": cannot open for writing: No such file or directory");
    CHECK_FALSE(writer.is_open());
    CHECK(dir.entries().empty());
}

TEST_CASE("odd sizes are refused for 4:2:0 codecs", "[render][video]") {
    TempDir dir;
    VideoWriter writer;
    VideoOptions o = small_options();
    o.width = 63;
    const std::string msg =
        thrown_message<impulse::ValueError>([&] { writer.open(dir.file("odd.mp4"), o); });
    CHECK_THAT(msg, Contains("63x48") && Contains("must be even"));

    o.width = 64;
    o.height = 47;
    CHECK_THROWS_AS(writer.open(dir.file("odd.webm"), o), impulse::ValueError);
    CHECK(dir.entries().empty());

    SECTION("4:4:4 and RGB codecs take odd sizes") {
        o.width = 63;
        o.height = 47;
        write_gradient(dir.file("odd.mkv"), o, 3);
        write_gradient(dir.file("odd.mov"), o, 3);
        for (const char* name : {"odd.mkv", "odd.mov"}) {
            const auto info = probe_video(dir.file(name));
            CHECK(info.width == 63);
            CHECK(info.height == 47);
            CHECK(info.frame_count == 3);
        }
    }
}

TEST_CASE("invalid options are ValueErrors naming the value", "[render][video]") {
    TempDir dir;
    VideoWriter writer;
    const std::string mp4 = dir.file("clip.mp4");
    VideoOptions o = small_options();

    SECTION("incompatible container and codec") {
        o.codec = VideoCodec::ProRes;
        const std::string msg =
            thrown_message<impulse::ValueError>([&] { writer.open(dir.file("clip.webm"), o); });
        CHECK_THAT(msg, Contains("clip.webm: codec prores cannot be written to .webm"));
        CHECK_THAT(msg, Contains(".mp4 h264, .mov prores|h264, .mkv ffv1|h264|prores|vp9, "
                                 ".webm vp9"));
    }
    SECTION("unknown container") {
        const std::string msg =
            thrown_message<impulse::ValueError>([&] { writer.open(dir.file("clip.avi"), o); });
        CHECK_THAT(msg, Contains("\".avi\": expected one of .mp4, .mov, .mkv, .webm"));
    }
    SECTION("zero width") {
        o.width = 0;
        const std::string msg = thrown_message<impulse::ValueError>([&] { writer.open(mp4, o); });
        CHECK_THAT(msg, Contains("width = 0: must be > 0"));
    }
    SECTION("fps") {
        o.fps = 0.0;
        CHECK_THROWS_AS(writer.open(mp4, o), impulse::ValueError);
        o.fps = std::numeric_limits<double>::quiet_NaN();
        CHECK_THROWS_AS(writer.open(mp4, o), impulse::ValueError);
    }
    SECTION("crf out of range for h264") {
        o.crf = 52;
        const std::string msg = thrown_message<impulse::ValueError>([&] { writer.open(mp4, o); });
        CHECK_THAT(msg, Contains("crf = 52: must be in 0..51 for h264"));
    }
    SECTION("unknown preset") {
        o.preset = "fastest";
        const std::string msg = thrown_message<impulse::ValueError>([&] { writer.open(mp4, o); });
        CHECK_THAT(msg, Contains("preset = \"fastest\": expected one of ultrafast,"));
    }
    SECTION("write_frame before open") {
        std::vector<float> rgb(static_cast<size_t>(kWidth) * kHeight * 3, 0.5f);
        CHECK_THROWS_AS(writer.write_frame(rgb.data()), impulse::ValueError);
    }
    CHECK_FALSE(writer.is_open());
    CHECK(dir.entries().empty());
}

TEST_CASE("probing a missing file is an IoError naming the path", "[render][video]") {
    TempDir dir;
    const std::string path = dir.file("nothing.mp4");
    const std::string msg = thrown_message<impulse::IoError>([&] { probe_video(path); });
    CHECK_THAT(msg, StartsWith(path + ": ") && Contains("No such file or directory"));
    int w = 0, h = 0;
    CHECK_THROWS_AS(decode_video_luma(path, w, h), impulse::IoError);
}
