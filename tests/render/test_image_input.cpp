// SPDX-License-Identifier: Apache-2.0
// Image inputs are untrusted files: a header may claim any size, and the readers refuse one whose
// pixels as floats exceed OpenImageIO's limits:imagesize_MB before allocating them. OIIO checks
// the file's own sample size (an 8-bit image of 100000^2 pixels, 9537 MB, passes it); the float
// buffer of 37 GiB used to be allocated and zero-filled.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "output/detail/image_input.h"
#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"
#include "numeric/errors.h"

namespace {

using Catch::Matchers::Contains;

/// A little-endian TIFF of width x height 8-bit grey pixels whose strip holds one byte: only the
/// header is valid.
std::string tiff_header(uint32_t width, uint32_t height) {
    std::string t = "II";
    auto u16 = [&](uint32_t v) { t += char(v & 0xff), t += char(v >> 8 & 0xff); };
    auto u32 = [&](uint32_t v) { u16(v & 0xffff), u16(v >> 16); };
    u16(42), u32(8);
    const uint32_t entries[][3] = {{256, 4, width}, {257, 4, height}, {258, 3, 8}, {259, 3, 1},
                                   {262, 3, 1},     {273, 4, 0},      {277, 3, 1}, {278, 4, height},
                                   {279, 4, 1}};
    const uint32_t data = 8 + 2 + 9 * 12 + 4;  // the strip, after the directory
    u16(9);
    for (const auto& e : entries) u16(e[0]), u16(e[1]), u32(1), u32(e[0] == 273 ? data : e[2]);
    u32(0);
    t += '\0';
    return t;
}

/// An OpenEXR header (magic, version 2 single-part) with one attribute whose int32 size field
/// says `declared` while `actual` bytes of value follow, then the header's end.
std::string exr_header(uint32_t version, int32_t declared, size_t actual) {
    std::string e = "\x76\x2f\x31\x01";
    auto u32 = [&](uint32_t v) {
        for (int i = 0; i < 4; ++i) e += char(v >> (8 * i) & 0xff);
    };
    u32(version);
    e += std::string("comments") + '\0' + "string" + '\0';
    u32(uint32_t(declared));
    e += std::string(actual, 'x');
    e += '\0';
    return e;
}

/// A PNG: the signature, an IHDR chunk of a 6 x 5 grey image, then a text chunk whose length
/// field says `declared` while 16 bytes follow (CRCs not checked: the file is refused first).
std::string png_with_text_chunk(uint32_t declared) {
    std::string p = "\x89PNG\r\n\x1a\n";
    auto be32 = [&](uint32_t v) {
        for (int i = 3; i >= 0; --i) p += char(v >> (8 * i) & 0xff);
    };
    be32(13), p += "IHDR", be32(6), be32(5), p += std::string("\x08\x00\x00\x00\x00", 5), be32(0);
    be32(declared), p += "tEXt", p += std::string(16, 'x');
    return p;
}

}  // namespace

TEST_CASE("an image whose header claims more than the size limit is refused before reading",
          "[render][errors]") {
    impulse::test::TempDir dir;
    const std::string huge = dir / "huge.tif", small = dir / "small.tif";
    impulse::test::write_file(huge, tiff_header(100000, 100000));
    impulse::test::write_file(small, tiff_header(1, 1));
    CHECK_THROWS_AS(impulse::output::read_image(huge), impulse::IoError);
    CHECK_THROWS_WITH(impulse::output::read_image(huge),
                      Contains("huge.tif: the header claims 100000x100000 pixels of 1 channels") &&
                          Contains("over OpenImageIO's limits:imagesize_MB = 32768"));
    CHECK(impulse::output::read_image(small).width == 1);  // the same file at a size that fits
    CHECK(impulse::output::image_size_problem(4, 3, 1, 2).empty());
    CHECK_THAT(impulse::output::image_size_problem(4, 3, 2, 1), Contains("4x3x2 pixels"));
    CHECK_THAT(impulse::output::image_size_problem(0, 3, 1, 1), Contains("expected a 2-D image"));
}

// A fuzzing finding (fuzz_image, a mask image): OpenEXR 3.1 sizes a string attribute to its
// declared length before reading it, so a 748-byte file declaring 1836216126 bytes made the
// reader allocate 1.8 GB. The header is walked and refused before OpenImageIO sees it.
TEST_CASE("an EXR header declaring an attribute larger than the file is refused before reading",
          "[render][errors]") {
    impulse::test::TempDir dir;
    const std::string hostile = dir / "hostile.exr", exact = dir / "exact.exr",
                      negative = dir / "negative.exr", cut = dir / "cut.exr";
    impulse::test::write_file(hostile, exr_header(2, 1836216126, 16));
    impulse::test::write_file(exact, exr_header(2, 5, 5));  // consistent, if not a whole image
    impulse::test::write_file(negative, exr_header(2, -4, 16));
    impulse::test::write_file(cut, exr_header(2, 5, 5).substr(0, 20));
    using impulse::output::exr_header_problem;
    CHECK_THAT(exr_header_problem(hostile),
               Contains("attribute 'comments' declares 1836216126 bytes, more than the 17 left"));
    CHECK(exr_header_problem(exact).empty());
    CHECK_THAT(exr_header_problem(negative), Contains("declares -4 bytes"));
    CHECK_THAT(exr_header_problem(cut), Contains("OpenEXR header"));
    CHECK_THROWS_WITH(impulse::output::read_image(hostile),
                      Contains("hostile.exr: OpenEXR header attribute 'comments' declares"));
    CHECK_THROWS_AS(impulse::output::probe_image(hostile), impulse::IoError);
    // A real EXR, and a file that is not one, pass the walk untouched.
    impulse::numeric::Frame f;
    f.resize(4, 3);
    const std::string good = dir / "good.exr", text = dir / "text.exr";
    impulse::output::write_image(good, f, {}, {{"scene", "a long enough metadata value"}});
    impulse::test::write_file(text, "not an image");
    CHECK(exr_header_problem(good).empty());
    CHECK(exr_header_problem(text).empty());
    CHECK(impulse::output::read_image(good).width == 4);
}

// A fuzzing finding (fuzz_image, probe_image of a .png): libpng allocates a chunk's declared
// length before reading it; a 322-byte file asked for 1.97 GB. The chunks are walked first.
TEST_CASE("a PNG chunk declaring more bytes than the file holds is refused before reading",
          "[render][errors]") {
    impulse::test::TempDir dir;
    const std::string hostile = dir / "hostile.png", good = dir / "good.png";
    impulse::test::write_file(hostile, png_with_text_chunk(1970012254u));
    CHECK_THAT(impulse::output::png_chunk_problem(hostile),
               Contains("truncated or hostile PNG: chunk 'tEXt' declares 1970012254 bytes, "
                        "more than the 16 left"));
    CHECK_THROWS_WITH(impulse::output::probe_image(hostile),
                      Contains("hostile.png: truncated or hostile PNG: chunk 'tEXt' declares"));
    impulse::numeric::Frame f;
    f.resize(6, 5);
    impulse::output::write_image(good, f, {}, {{"scene", "metadata in a text chunk"}});
    CHECK(impulse::output::png_chunk_problem(good).empty());
    CHECK(impulse::output::read_image(good).width == 6);
}

namespace {

/// The markers of a JPEG's segments before its scan, in order.
std::vector<int> jpeg_markers(const std::vector<unsigned char>& b) {
    std::vector<int> markers;
    for (size_t i = 2; i + 4 <= b.size() && b[i] == 0xFF && b[i + 1] != 0xDA;
         i += 2 + (size_t(b[i + 2]) << 8 | b[i + 3]))
        markers.push_back(b[i + 1]);
    return markers;
}

}  // namespace

// Fuzzing findings (fuzz_image, probe_image of a .jpg): OpenImageIO 2.4 decodes a JPEG's
// metadata (IPTC records in a Photoshop APP13 segment, and then another reader) without holding
// every length against its segment, and read past its buffer. impulse reads only a JPEG's
// pixels, so OpenImageIO is given the file without its metadata segments.
// tests/render/hostile_iptc.jpg is the first reproducer (988 bytes): under ASan (sanitize.sh)
// reading it with its APP13 segment overflows.
TEST_CASE("a JPEG is read without its metadata segments", "[render][errors]") {
    const std::string hostile = std::string(IMPULSE_SOURCE_DIR) + "/tests/render/hostile_iptc.jpg";
    const auto all = impulse::test::read_file(hostile);
    const std::vector<unsigned char> all_bytes(all.begin(), all.end());
    const auto all_markers = jpeg_markers(all_bytes);
    CHECK(std::count(all_markers.begin(), all_markers.end(), 0xED) == 1);
    const auto kept = impulse::output::jpeg_pixels_only(hostile);
    REQUIRE(kept);
    const auto kept_markers = jpeg_markers(*kept);
    CHECK(std::count(kept_markers.begin(), kept_markers.end(), 0xED) == 0);
    CHECK(kept->size() < all_bytes.size());
    // Opening it is safe; whether its pixels decode is libjpeg's to say, in one line.
    try {
        (void)impulse::output::probe_image(hostile);
    } catch (const impulse::IoError& e) {
        CHECK(std::string(e.what()).find('\n') == std::string::npos);
    }

    // A JPEG with metadata (Exif, IPTC, a comment) reads the same pixels as OpenImageIO reads
    // from the whole file.
    impulse::test::TempDir dir;
    const std::string good = dir / "good.jpg";
    {
        OIIO::ImageSpec spec(6, 5, 3, OIIO::TypeDesc::UINT8);
        spec.attribute("Software", "impulse tests");
        spec.attribute("Exif:ImageHistory", "a JPEG with metadata");
        spec.attribute("ImageDescription", "a comment");
        std::vector<unsigned char> rgb(90);
        for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>(i * 37 % 256);
        auto out = OIIO::ImageOutput::create(good);
        REQUIRE(out);
        REQUIRE(out->open(good, spec));
        REQUIRE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
        REQUIRE(out->close());
    }
    const auto good_all = impulse::test::read_file(good);
    const auto good_kept = impulse::output::jpeg_pixels_only(good);
    REQUIRE(good_kept);
    CHECK(good_kept->size() < good_all.size());
    const auto markers = jpeg_markers(*good_kept);
    CHECK(std::none_of(markers.begin(), markers.end(),
                       [](int m) { return (m >= 0xE1 && m <= 0xED) || m == 0xEF || m == 0xFE; }));
    auto direct = OIIO::ImageInput::open(good);
    REQUIRE(direct);
    // OpenImageIO read the bytes given, not the file: the file's Exif is not in the spec.
    auto has_exif = [](const OIIO::ImageSpec& spec) {
        return std::any_of(spec.extra_attribs.begin(), spec.extra_attribs.end(),
                           [](const OIIO::ParamValue& p) { return p.name().string().rfind("Exif:", 0) == 0; });
    };
    CHECK(has_exif(direct->spec()));
    std::string error;
    const auto opened = impulse::output::open_image_input(good, error);
    REQUIRE(opened);
    CHECK_FALSE(has_exif(opened->spec()));
    std::vector<float> expected(30 * size_t(direct->spec().nchannels));
    REQUIRE(direct->read_image(0, 0, 0, direct->spec().nchannels, OIIO::TypeDesc::FLOAT,
                               expected.data()));
    const impulse::numeric::Frame read = impulse::output::read_image(good);
    REQUIRE(read.width == 6);
    for (size_t i = 0; i < 30; ++i) {
        const size_t nc = size_t(direct->spec().nchannels);
        const float luma = nc >= 3 ? 0.2126f * expected[i * nc] + 0.7152f * expected[i * nc + 1] +
                                         0.0722f * expected[i * nc + 2]
                                   : expected[i * nc];
        CHECK(read.data[i] == luma);
    }
    CHECK_FALSE(impulse::output::jpeg_pixels_only(dir / "good.jpg.png"));
}
