// SPDX-License-Identifier: Apache-2.0
#pragma once
// Opening untrusted image files (part of impulse::output). Every reader of an image file goes
// through open_image_input, so a hostile header is refused before a decoder sizes a buffer from
// it. Unlike image.h this header names OpenImageIO's types: include it only where OIIO is used.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

namespace impulse::output {

/// "" when the bytes at `path` are not an OpenEXR file or are one whose header is consistent
/// with the file's length; else what is wrong ("header attribute 'x' declares 1836216126 bytes,
/// more than the 700 left in the file"). OpenEXR sizes an attribute's value to its declared
/// length before reading it, so a 748-byte file can make it allocate gigabytes: the header's
/// attributes (name, type, int32 size, value; every part of a multi-part file) are walked and
/// each declared size is held against the bytes that remain.
std::string exr_header_problem(const std::string& path);

/// The same for PNG ("truncated or hostile PNG: chunk ..."): "" when the bytes at `path` are not a PNG file or every chunk's declared
/// length fits in what follows it; else what is wrong. libpng allocates a chunk's declared
/// length (up to 2^31 - 1) before reading it: fuzzing found a 322-byte file whose text chunk
/// asked for 1.97 GB.
std::string png_chunk_problem(const std::string& path);
/// The bytes of the JPEG at `path` with its metadata segments left out (Exif, XMP, ICC, IPTC and
/// the other APP1..APP15 but APP14, and comments); std::nullopt when the file is not a JPEG.
/// impulse reads a JPEG's pixels, never its metadata, and OpenImageIO 2.4 decodes that
/// metadata without holding every length against its segment: fuzz_image found heap overflows
/// in its IPTC and then in another metadata reader. Leaving the segments out closes the whole
/// class rather than one reader at a time.
std::optional<std::vector<unsigned char>> jpeg_pixels_only(const std::string& path);

/// An opened image: OpenImageIO's reader and, for a JPEG, the bytes it reads from memory (kept
/// alive as long as the reader; destroyed after it). Used like the reader's pointer.
struct OpenedImage {
    std::unique_ptr<std::vector<unsigned char>> bytes;
    std::unique_ptr<OIIO::Filesystem::IOProxy> proxy;
    std::unique_ptr<OIIO::ImageInput> input;
    explicit operator bool() const { return bool(input); }
    OIIO::ImageInput* operator->() const { return input.get(); }
};

/// OIIO::ImageInput::open after exr_header_problem and png_chunk_problem, and of a JPEG's
/// jpeg_pixels_only; an empty OpenedImage with `error` set (one line) when the file is refused
/// or OpenImageIO cannot open it.
OpenedImage open_image_input(const std::string& path, std::string& error);

}  // namespace impulse::output
