// SPDX-License-Identifier: Apache-2.0
#pragma once
// Helpers shared by the test suites: temporary directories, files, and running commands with
// their output captured.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace impulse::test {

namespace fs = std::filesystem;

/// A fresh directory under the system temp dir (unique per process, call and run), removed with
/// everything in it.
class TempDir {
public:
    explicit TempDir(const std::string& tag = "test") {
        static std::atomic<int> counter{0};
        std::random_device rd;
        m_path = fs::temp_directory_path() /
                 ("impulse-" + tag + "-" + std::to_string(::getpid()) + "-" +
                  std::to_string(counter++) + "-" + std::to_string(rd()));
        fs::create_directories(m_path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    /// Path of `name` inside the directory.
    std::string operator/(const std::string& name) const { return (m_path / name).string(); }
    std::string file(const std::string& name) const { return *this / name; }
    const fs::path& path() const { return m_path; }
    /// Names of the entries, sorted (hidden ones included).
    std::vector<std::string> files() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(m_path)) names.push_back(e.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }
    std::vector<std::string> entries() const { return files(); }

private:
    fs::path m_path;
};

inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void write_file(const std::string& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
}

/// Single-quoted for the shell.
inline std::string quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// Exit status and captured output of a command.
struct Result {
    int status = -1;
    std::string out, err;
    /// stderr split into lines (without the trailing newline).
    std::vector<std::string> err_lines() const {
        std::vector<std::string> lines;
        std::istringstream in(err);
        for (std::string l; std::getline(in, l);) lines.push_back(l);
        return lines;
    }
};

/// Runs a shell command line with stdout and stderr captured in files of `dir` (never a
/// terminal, so no progress display) and no standard input.
inline Result shell(const TempDir& dir, const std::string& command) {
    const std::string out = dir / ".stdout", err = dir / ".stderr";
    const int rc = std::system((command + " >" + quote(out) + " 2>" + quote(err) + " </dev/null").c_str());
    Result r;
    r.status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    r.out = read_file(out);
    r.err = read_file(err);
    fs::remove(out);
    fs::remove(err);
    return r;
}

}  // namespace impulse::test
