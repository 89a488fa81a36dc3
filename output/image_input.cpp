// SPDX-License-Identifier: Apache-2.0
#include "output/image_input.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
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

/// The IPTC records of a Photoshop APP13 segment's 8BIM resources (`seg`: the segment's bytes
/// after its length): "" when every resource and every record fits inside what holds it.
std::string iptc_problem(const std::vector<unsigned char>& seg) {
    static const std::string kPhotoshop("Photoshop 3.0", 14);  // with its terminating NUL
    if (seg.size() < kPhotoshop.size() || !std::equal(kPhotoshop.begin(), kPhotoshop.end(), seg.begin()))
        return "";
    size_t i = kPhotoshop.size();
    auto u16 = [&](size_t at) { return size_t(seg[at]) << 8 | seg[at + 1]; };
    while (i + 4 <= seg.size() && std::equal(seg.begin() + long(i), seg.begin() + long(i) + 4, "8BIM")) {
        const size_t id_at = i + 4;
        if (id_at + 3 > seg.size()) return "an 8BIM resource header runs past its segment";
        size_t name = 1 + seg[id_at + 2];  // Pascal string, padded to an even length
        name += name & 1;
        const size_t size_at = id_at + 2 + name;
        if (size_at + 4 > seg.size()) return "an 8BIM resource header runs past its segment";
        const size_t size = size_t(seg[size_at]) << 24 | size_t(seg[size_at + 1]) << 16 |
                            size_t(seg[size_at + 2]) << 8 | seg[size_at + 3];
        const size_t data = size_at + 4;
        if (size > seg.size() - data)
            return "an 8BIM resource declares " + std::to_string(size) + " bytes, more than the " +
                   std::to_string(seg.size() - data) + " left in its segment";
        if (u16(id_at) == 0x0404)  // IPTC-NAA: records 0x1C, record, dataset, 2-byte length
            for (size_t r = data; r < data + size;) {
                if (seg[r] != 0x1C) break;
                if (r + 5 > data + size) return "an IPTC record header runs past its resource";
                const size_t len = u16(r + 3);
                if (len & 0x8000) return "an IPTC record uses an extended length";
                if (len > data + size - (r + 5))
                    return "an IPTC record declares " + std::to_string(len) +
                           " bytes, more than its resource holds";
                r += 5 + len;
            }
        i = data + size + (size & 1);
    }
    return "";
}

}  // namespace

std::string jpeg_segment_problem(const std::string& path) {
    // OpenImageIO 2.4 decodes a JPEG's IPTC records without checking their lengths against
    // the segment (a heap overflow fuzz_image found); the segments before the scan are walked
    // here first.
    std::ifstream in(path, std::ios::binary);
    std::array<unsigned char, 2> soi{};
    if (!in.read(reinterpret_cast<char*>(soi.data()), 2) || soi[0] != 0xFF || soi[1] != 0xD8) return "";
    for (;;) {
        std::array<unsigned char, 4> m{};
        if (!in.read(reinterpret_cast<char*>(m.data()), 4) || m[0] != 0xFF) return "";
        if (m[1] == 0xDA || m[1] == 0xD9) return "";  // the scan (or the end): no more headers
        const size_t length = size_t(m[2]) << 8 | m[3];
        if (length < 2) return "";
        std::vector<unsigned char> seg(length - 2);
        if (!in.read(reinterpret_cast<char*>(seg.data()), std::streamsize(seg.size()))) return "";
        if (m[1] != 0xED) continue;
        if (const std::string why = iptc_problem(seg); !why.empty())
            return "truncated or hostile JPEG: " + why;
    }
}

std::unique_ptr<OIIO::ImageInput> open_image_input(const std::string& path, std::string& error) {
    error = exr_header_problem(path);
    if (error.empty()) error = png_chunk_problem(path);
    if (error.empty()) error = jpeg_segment_problem(path);
    if (!error.empty()) return nullptr;
    auto in = OIIO::ImageInput::open(path);
    if (!in) {
        error = "cannot read: " + OIIO::geterror();
        std::replace(error.begin(), error.end(), '\n', ' ');
    }
    return in;
}

}  // namespace impulse::output
