// SPDX-License-Identifier: Apache-2.0
// `impulse preview`: the files a scene is made of, watched for changes (the numeric keys the page
// exposes are scenes/exposed.h's).

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <set>

#include "app/detail/preview.h"
#include "numeric/errors.h"

namespace impulse::app::preview {
namespace {

namespace fs = std::filesystem;

FileStamp stamp(const fs::path& p) {
    FileStamp s;
    s.path = p.string();
    std::error_code ec;
    const auto t = fs::last_write_time(p, ec);
    if (ec) return s;
    s.exists = true;
    s.mtime_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
    const auto size = fs::file_size(p, ec);
    s.size = ec ? 0 : size;
    return s;
}

void collect(const fs::path& file, std::vector<FileStamp>& out, std::set<std::string>& seen) {
    if (!seen.insert(file.lexically_normal().string()).second || seen.size() > 64) return;
    out.push_back(stamp(file));
    try {
        for (const std::string& p : scenes::scene_includes(file.string())) collect(p, out, seen);
    } catch (const std::exception&) {
        // Unreadable or malformed: the loader says why; the file itself stays watched.
    }
}

}  // namespace

std::vector<FileStamp> scene_files(const std::string& path) {
    std::vector<FileStamp> out;
    std::set<std::string> seen;
    collect(fs::path(path), out, seen);
    return out;
}

std::string json_quote(const std::string& s) {
    std::string o = "\"";
    for (const unsigned char c : s) {
        if (c == '"' || c == '\\') {
            o += '\\', o += char(c);
        } else if (c < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\u%04x", c);
            o += buf;
        } else {
            o += char(c);
        }
    }
    return o + "\"";
}

}  // namespace impulse::app::preview
