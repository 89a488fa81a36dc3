// SPDX-License-Identifier: Apache-2.0
#include "output/detail/image_input.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace impulse::output {
namespace {

constexpr std::array<unsigned char, 4> kExrMagic = {0x76, 0x2f, 0x31, 0x01};
constexpr std::array<unsigned char, 8> kPngMagic = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a};
constexpr uint32_t kLongNames = 0x400, kMultiPart = 0x1000;

/// A null-terminated header string of at most `max` characters; false when the file ends or
/// the string is longer.
bool read_name(std::istream& in, size_t max, std::string& out) {
    out.clear();
    for (char c; in.get(c);) {
        if (c == '\0') return true;
        if (out.size() == max) return false;
        out.push_back(c);
    }
    return false;
}

uint32_t read_u32(std::istream& in) {
    std::array<unsigned char, 4> b{};
    in.read(reinterpret_cast<char*>(b.data()), 4);
    return uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
}

/// Walks one part's attributes up to its terminating empty name. Sets `empty` when the part
/// has no attribute at all (the end of a multi-part file's header list).
std::string walk_part(std::istream& in, uint64_t file_size, size_t max_name, bool& empty) {
    std::string name, type;
    empty = true;
    for (;;) {
        if (!read_name(in, max_name, name)) return "header attribute name unterminated or too long";
        if (name.empty()) return "";
        empty = false;
        if (!read_name(in, max_name, type))
            return "header attribute '" + name + "' has an unterminated or too long type name";
        const uint32_t declared = read_u32(in);
        if (!in) return "header ends inside attribute '" + name + "'";
        const uint64_t left = file_size - uint64_t(in.tellg());
        if (int32_t(declared) < 0 || declared > left)
            return "header attribute '" + name + "' declares " + std::to_string(int32_t(declared)) +
                   " bytes, more than the " + std::to_string(left) + " left in the file";
        in.seekg(std::streamoff(declared), std::ios::cur);
    }
}

}  // namespace

std::string exr_header_problem(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return "";  // OpenImageIO says why it cannot open it
    const uint64_t file_size = uint64_t(in.tellg());
    in.seekg(0);
    std::array<unsigned char, 4> magic{};
    in.read(reinterpret_cast<char*>(magic.data()), 4);
    if (!in || magic != kExrMagic) return "";
    const uint32_t version = read_u32(in);
    if (!in) return "OpenEXR header cut short";
    const size_t max_name = (version & kLongNames) ? 255 : 31;
    const bool multipart = version & kMultiPart;
    // A multi-part header list ends with an empty part; a single part is one list.
    for (bool empty = false;;) {
        if (std::string bad = walk_part(in, file_size, max_name, empty); !bad.empty())
            return "OpenEXR " + bad;
        if (!multipart || empty) return "";
    }
}

std::string png_chunk_problem(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return "";
    const uint64_t file_size = uint64_t(in.tellg());
    in.seekg(0);
    std::array<unsigned char, 8> magic{};
    in.read(reinterpret_cast<char*>(magic.data()), 8);
    if (!in || magic != kPngMagic) return "";
    // Chunks: big-endian uint32 length, 4-byte type, data, 4-byte CRC; up to IEND.
    for (;;) {
        std::array<unsigned char, 8> head{};
        in.read(reinterpret_cast<char*>(head.data()), 8);
        if (!in) return "";  // the end of the file: libpng says what is missing
        const uint32_t length = uint32_t(head[0]) << 24 | uint32_t(head[1]) << 16 |
                                uint32_t(head[2]) << 8 | uint32_t(head[3]);
        std::string type(reinterpret_cast<const char*>(head.data()) + 4, 4);
        for (char& c : type)
            if (!std::isalpha(static_cast<unsigned char>(c))) c = '?';
        const uint64_t left = file_size - uint64_t(in.tellg());
        if (uint64_t(length) + 4 > left)
            return "truncated or hostile PNG: chunk '" + type + "' declares " +
                   std::to_string(length) +
                   " bytes, more than the " + std::to_string(left) + " left in the file";
        if (type == "IEND") return "";
        in.seekg(std::streamoff(length) + 4, std::ios::cur);
    }
}

namespace {

/// Markers that carry metadata, not pixels: APP1..APP13, APP15 (Exif, XMP, ICC, Photoshop and
/// IPTC, ...) and COM. APP0 (JFIF) and APP14 (Adobe: the colour transform) are kept: libjpeg
/// reads them itself to decode the pixels.
bool is_metadata_marker(unsigned char m) {
    return (m >= 0xE1 && m <= 0xED) || m == 0xEF || m == 0xFE;
}

std::vector<unsigned char> read_file_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return {};
    std::vector<unsigned char> bytes(size_t(in.tellg()));
    in.seekg(0);
    if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(bytes.size()))) return {};
    return bytes;
}

}  // namespace

std::optional<std::vector<unsigned char>> jpeg_pixels_only(const std::string& path) {
    const std::vector<unsigned char> b = read_file_bytes(path);
    if (b.size() < 2 || b[0] != 0xFF || b[1] != 0xD8) return std::nullopt;
    std::vector<unsigned char> kept(b.begin(), b.begin() + 2);
    auto copy = [&](size_t from, size_t to) {
        kept.insert(kept.end(), b.begin() + long(from), b.begin() + long(to));
    };
    // Markers are found the way libjpeg finds them, wherever they are: bytes up to the next
    // 0xFF (entropy-coded data, or garbage libjpeg skips with a warning) are copied; 0xFF fill
    // bytes are skipped; 0xFF00 (a stuffed byte), RSTn, TEM and SOI stand alone; EOI ends the
    // file; every other marker has a big-endian length that counts itself.
    for (size_t i = 2; i < b.size();) {
        size_t ff = i;
        while (ff < b.size() && b[ff] != 0xFF) ++ff;
        copy(i, ff);
        size_t m = ff;
        while (m < b.size() && b[m] == 0xFF) ++m;
        if (m >= b.size()) break;  // the file ends in fill bytes: libjpeg says it is cut short
        const unsigned char marker = b[m];
        const bool alone = marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8);
        if (alone || marker == 0xD9) {
            kept.push_back(0xFF), kept.push_back(marker);
            i = m + 1;
            if (marker == 0xD9) break;
            continue;
        }
        if (m + 3 > b.size()) break;
        const size_t end = m + 1 + (size_t(b[m + 1]) << 8 | b[m + 2]);
        if (end > b.size()) break;  // a segment cut short: the file ends before it
        if (!is_metadata_marker(marker)) kept.push_back(0xFF), copy(m, end);
        i = end;
    }
    return kept;
}

OpenedImage open_image_input(const std::string& path, std::string& error) {
    OpenedImage opened;
    error = exr_header_problem(path);
    if (error.empty()) error = png_chunk_problem(path);
    if (!error.empty()) return opened;
    if (auto jpeg = jpeg_pixels_only(path)) {
        opened.bytes = std::make_unique<std::vector<unsigned char>>(std::move(*jpeg));
        opened.proxy = std::make_unique<OIIO::Filesystem::IOMemReader>(opened.bytes->data(),
                                                                       opened.bytes->size());
        // OpenImageIO 2.4 reads the file itself unless the proxy is also named in the config.
        OIIO::ImageSpec config;
        void* proxy = opened.proxy.get();
        config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
        opened.input = OIIO::ImageInput::open(path, &config, opened.proxy.get());
    } else {
        opened.input = OIIO::ImageInput::open(path);
    }
    if (!opened.input) {
        error = "cannot read: " + OIIO::geterror();
        std::replace(error.begin(), error.end(), '\n', ' ');
    }
    return opened;
}

}  // namespace impulse::output
