// SPDX-License-Identifier: Apache-2.0
#pragma once
// Whole files written atomically and durably (part of impulse::output): the bytes go to a
// temporary file beside the target, every write checked, the file flushed to the disk (fsync)
// and closed, then renamed into place and the folder flushed, so neither an interrupted run nor
// a crash or power cut leaves a partial or empty file under the target's name: the old file or
// the new one (design.md §4). The image, video, volume and mesh writers all commit this way.

#include <cstddef>
#include <string>

namespace impulse::output {

/// The extension of `path` in lower case, with its dot (".png"), or "".
std::string lower_extension(const std::string& path);

/// Temporary name beside `path` that keeps its extension: DIR/.STEM.partial-PID.EXT.
std::string partial_path(const std::string& path);

/// Flushes a finished temporary (partial_path(path), written and closed) to the disk, renames
/// it into place and flushes the folder; on failure removes it and throws IoError naming `path`.
void commit_partial(const std::string& tmp, const std::string& path);

/// Writes `size` bytes to `path` atomically and durably (temporary, fsync, rename, fsync of the
/// folder). Throws IoError naming `path` with the system's message (a missing directory, a full
/// disk, a file size limit, an I/O error on flushing); nothing is left behind then.
void write_file_atomic(const std::string& path, const void* data, size_t size);

}  // namespace impulse::output
