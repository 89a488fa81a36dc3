// SPDX-License-Identifier: Apache-2.0
// Atomic, durable whole-file writes: temporary beside the target, checked writes, fsync, rename,
// fsync of the folder (output/files.h).

#include "output/files.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <system_error>

#include "numeric/errors.h"

namespace impulse::output {
namespace {

namespace fs = std::filesystem;

/// Writes the bytes to a new file with every write, the flush to the disk and the close checked:
/// a full disk or a file size limit is an error here, never a short file. Returns "" or the
/// system's message.
std::string write_bytes(const std::string& path, const unsigned char* bytes, size_t size) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) return std::strerror(errno);
    size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd, bytes + done, size - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const int e = n < 0 ? errno : ENOSPC;
            ::close(fd);
            return std::strerror(e);
        }
        done += size_t(n);
    }
    // The data on the disk before the rename makes it visible: otherwise a crash soon after can
    // leave the new name on an empty file (ext4, XFS and btrfs may order the rename first).
    if (::fsync(fd) != 0) {
        const int e = errno;
        ::close(fd);
        return std::strerror(e);
    }
    // close reports deferred errors (NFS, quotas).
    if (::close(fd) != 0) return std::strerror(errno);
    return "";
}

/// fsync of an existing file or folder by name; "" or the system's message. A folder whose file
/// system cannot flush folders (EINVAL) needs none.
std::string sync_path(const std::string& path, bool folder) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | (folder ? O_DIRECTORY : 0));
    if (fd < 0) return std::strerror(errno);
    const int e = ::fsync(fd) == 0 || (folder && errno == EINVAL) ? 0 : errno;
    ::close(fd);
    return e == 0 ? "" : std::strerror(e);
}

/// The folder `path` is in ("." for a bare name).
std::string folder_of(const std::string& path) {
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? "." : parent.string();
}

/// Renames a flushed temporary into place, then flushes the folder so the new name is on the
/// disk too; removes the temporary and throws IoError naming `path` on failure.
void rename_durably(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot rename temporary file into place: " + ec.message());
    }
    if (const std::string e = sync_path(folder_of(path), true); !e.empty())
        throw IoError(path + ": cannot flush its folder to the disk: " + e);
}

}  // namespace

std::string lower_extension(const std::string& path) {
    std::string e = fs::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
    return e;
}

std::string partial_path(const std::string& path) {
    const fs::path p(path);
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on a chain of string operator+.
    std::string name = ".";
    name += p.stem().string();
    name += ".partial-";
    name += std::to_string(::getpid());
    name += p.extension().string();
    return (p.parent_path() / name).string();
}

void commit_partial(const std::string& tmp, const std::string& path) {
    if (const std::string e = sync_path(tmp, false); !e.empty()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot flush to the disk: " + e);
    }
    rename_durably(tmp, path);
}

void write_file_atomic(const std::string& path, const void* data, size_t size) {
    const std::string tmp = partial_path(path);
    if (const std::string e = write_bytes(tmp, static_cast<const unsigned char*>(data), size);
        !e.empty()) {
        std::error_code ec;
        fs::remove(tmp, ec);
        throw IoError(path + ": write failed: " + e);
    }
    rename_durably(tmp, path);  // write_bytes flushed it
}

}  // namespace impulse::output
