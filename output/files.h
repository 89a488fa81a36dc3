// SPDX-License-Identifier: Apache-2.0
#pragma once
// Whole files written atomically (part of impulse::output): the bytes go to a temporary file
// beside the target, every write and the close checked, then renamed into place, so a partial
// file never appears under the target's name (design.md §4). The image writer uses the same.

#include <cstddef>
#include <string>

namespace impulse::output {

/// The extension of `path` in lower case, with its dot (".png"), or "".
std::string lower_extension(const std::string& path);

/// Temporary name beside `path` that keeps its extension: DIR/.STEM.partial-PID.EXT.
std::string partial_path(const std::string& path);

/// Renames a finished temporary (partial_path(path)) into place; on failure removes it and
/// throws IoError naming `path`.
void commit_partial(const std::string& tmp, const std::string& path);

/// Writes `size` bytes to `path` atomically (temporary + rename). Throws IoError naming `path`
/// with the system's message (a missing directory, a full disk, a file size limit); nothing is
/// left behind then.
void write_file_atomic(const std::string& path, const void* data, size_t size);

}  // namespace impulse::output
