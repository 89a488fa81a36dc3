// SPDX-License-Identifier: Apache-2.0
// Ctrl-C during a video render closes the file so what was encoded stays playable.
#include <catch2/catch.hpp>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

#include "output/video.h"

extern char** environ;
namespace fs = std::filesystem;

TEST_CASE("SIGINT closes a video so the encoded frames stay playable", "[cli][video]") {
    const fs::path dir = fs::temp_directory_path() / ("impulse_int_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const fs::path scene = dir / "long.toml";
    std::ofstream(scene) << "[output]\nsize = [320, 240]\nframes = 100000\nfps = 30\n"
                            "[[layer]]\nlifetime = 1.0\n[layer.kernel]\ntype = \"gaussian\"\n"
                            "radius = 24.0\nsigma = 8.0\n[[layer.flow]]\ntype = \"uniform\"\n"
                            "velocity = [20.0, 0.0]\n";
    const std::string out = (dir / "clip.mp4").string();
    const std::string bin = IMPULSE_BINARY;
    std::vector<std::string> args = {bin, "render", scene.string(), "-o", out, "-q"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, bin.c_str(), nullptr, nullptr, argv.data(), environ) == 0);
    // Wait until encoding has started (the temporary file exists and has grown), however slow
    // the machine, then let it run a little longer.
    auto encoding = [&] {
        for (const auto& e : fs::directory_iterator(dir))
            if (e.path().filename().string().find("partial") != std::string::npos &&
                fs::file_size(e.path()) > 0)
                return true;
        return false;
    };
    for (int i = 0; i < 600 && !encoding(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
    REQUIRE(::kill(pid, SIGINT) == 0);
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == 130);
    REQUIRE(fs::exists(out));
    const auto info = impulse::output::probe_video(out);
    CHECK(info.frame_count > 0);
    CHECK(info.frame_count < 100000);
    CHECK(info.width == 320);
    for (const auto& e : fs::directory_iterator(dir))  // no temporary file left behind
        CHECK(e.path().filename().string().find("partial") == std::string::npos);
    fs::remove_all(dir);
}
