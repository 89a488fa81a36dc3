// SPDX-License-Identifier: Apache-2.0
// No silent data loss (issue 14): a write that fails on a full disk or past a file size limit
// fails the render with the file named, every format alike, and leaves no temporary; SIGTERM
// and SIGHUP stop a render as SIGINT does; --resume renders again the frames that do not check
// out and removes the temporaries of killed runs.

#include <fcntl.h>
#include <spawn.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "output/output.h"
#include "render/render.h"
#include "tests/support.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args, const std::string& prefix = "") {
    return shell(dir, prefix + quote(IMPULSE_BINARY) + " " + args);
}

// A 1024x1024 still field of small kernels: noise that compresses badly, so one frame is
// larger than the 96 KiB disks below in every format.
const char* kNoise = R"([output]
size = [1024, 1024]
frames = 6
[[layer]]
seed = 3
density = 12.0
[layer.kernel]
type = "cosine"
radius = 3.0
)";

/// A place where writes fail: a small tmpfs (a real full file system; needs root, as CI has),
/// or a file size limit (`ulimit -f`, RLIMIT_FSIZE) in the shell that runs impulse.
struct SmallDisk {
    std::string how;     ///< for messages
    std::string prefix;  ///< shell prefix of the command
    fs::path mount;      ///< the tmpfs mount point, or empty
};

/// Mounts a `kib` KiB tmpfs on `dir` when allowed; empty `how` if not.
SmallDisk tmpfs_disk(const TempDir& dir, int kib) {
    const fs::path m = dir.path() / "tmpfs";
    fs::create_directories(m);
    const std::string opts = "size=" + std::to_string(kib) + "k";
    if (::mount("tmpfs", m.c_str(), "tmpfs", 0, opts.c_str()) != 0) return {};
    return {"a " + std::to_string(kib) + " KiB tmpfs", "", m};
}

/// Runs `body` on each small disk that can be set up here; says which cannot.
template <class Body>
void on_small_disks(int kib, Body body) {
    int tried = 0;
    {
        TempDir dir("full");
        SmallDisk disk = tmpfs_disk(dir, kib);
        if (disk.how.empty()) {
            WARN("SKIPPED on a tmpfs: mount needs root (CI runs as root); the file size limit "
                 "below stands in for a full disk");
        } else {
            ++tried;
            // Unmounted however the body ends (a failed REQUIRE throws).
            struct Unmount {
                fs::path at;
                ~Unmount() { ::umount(at.c_str()); }
            } unmount{disk.mount};
            body(disk, dir);
        }
    }
    TempDir dir("fsize");
    const Result probe = shell(dir, "ulimit -f " + std::to_string(kib) + " && true");
    if (probe.status != 0) {
        WARN("SKIPPED with ulimit -f: cannot set a file size limit here");
    } else {
        ++tried;
        body(SmallDisk{"ulimit -f " + std::to_string(kib), "ulimit -f " + std::to_string(kib) + " && ", {}},
             dir);
    }
    if (tried == 0) WARN("SKIPPED: no full disk could be set up; nothing was checked");
}

fs::path out_dir(const SmallDisk& disk, const TempDir& dir) {
    return disk.mount.empty() ? dir.path() : disk.mount;
}

std::vector<std::string> names_in(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    return names;
}

void check_failed_write(const Result& r, const fs::path& dir, const std::string& what) {
    INFO(what << "\nstdout: " << r.out << "\nstderr: " << r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.out, !Contains("wrote"));
    // One line naming the file and the system's reason.
    const auto lines = r.err_lines();
    REQUIRE(lines.size() == 1);
    CHECK_THAT(lines[0], Contains("error: " + dir.string() + "/"));
    CHECK((lines[0].find("No space left on device") != std::string::npos ||
           lines[0].find("File too large") != std::string::npos));
    for (const auto& name : names_in(dir)) {
        CHECK(name.find("partial") == std::string::npos);  // no temporary left behind
        // Whatever is present is whole.
        if (name != "tmpfs") CHECK_NOTHROW(impulse::output::read_image((dir / name).string()));
    }
}

}  // namespace

TEST_CASE("a full disk fails the render with the file named, in every image format",
          "[cli][dataloss]") {
    on_small_disks(96, [](const SmallDisk& disk, const TempDir& dir) {
        write_file(dir / "noise.toml", kNoise);
        const fs::path out = out_dir(disk, dir) / "seq";
        fs::create_directories(out);
        // A sequence: the frames that fit are whole, the first that does not fails the run.
        check_failed_write(run(dir, "render " + quote(dir / "noise.toml") + " -q -o " +
                                        quote((out / "f_####.png").string()),
                               disk.prefix),
                           out, disk.how + ": PNG sequence");
        for (const char* ext : {"png", "tif", "jpg", "exr"}) {
            fs::remove_all(out);
            fs::create_directories(out);
            const std::string one = (out / (std::string("one.") + ext)).string();
            check_failed_write(
                run(dir, "render " + quote(dir / "noise.toml") + " -q --frames 0 -o " + quote(one),
                    disk.prefix),
                               out, disk.how + ": one ." + ext);
            CHECK_FALSE(fs::exists(one));
        }
        fs::remove_all(out);
    });
}

namespace {

/// One layer of Gaussian impulses (radius 3 sigma) living a second, carried by a uniform wind.
std::string windy_scene(int width, int height, long frames, double radius, const char* velocity) {
    return "[output]\nsize = [" + std::to_string(width) + ", " + std::to_string(height) +
           "]\nframes = " + std::to_string(frames) +
           "\n[[layer]]\nseed = 21\nlifetime = 1.0\n[layer.kernel]\ntype = \"gaussian\"\nradius = " +
           std::to_string(radius) + "\nsigma = " + std::to_string(radius / 3) +
           "\n[[layer.flow]]\ntype = \"uniform\"\nvelocity = " + velocity + "\n";
}

// Long enough never to finish while the tests below run.
const std::string kLong = windy_scene(320, 240, 100000, 24.0, "[20.0, 0.0]");

/// Starts `impulse ARGS` with stderr to `err`, and SIGINT, SIGTERM and SIGHUP at their default
/// dispositions whatever the test runner ignores.
pid_t spawn_impulse(std::vector<std::string> args, const std::string& err) {
    args.insert(args.begin(), IMPULSE_BINARY);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults;
    sigemptyset(&defaults);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&defaults, s);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
    posix_spawn_file_actions_t files;
    posix_spawn_file_actions_init(&files);
    posix_spawn_file_actions_addopen(&files, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, argv[0], &files, &attr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&files);
    posix_spawnattr_destroy(&attr);
    return rc == 0 ? pid : -1;
}

/// Waits (up to a minute, however slow the machine) until `ready()`, then a second more.
template <class Ready>
void wait_until(Ready ready) {
    for (int i = 0; i < 600 && !ready(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::this_thread::sleep_for(std::chrono::milliseconds(1000));
}

/// Sends `signo` to `pid` and returns its exit status (-1 if it did not exit normally).
int stop_with(pid_t pid, int signo) {
    REQUIRE(::kill(pid, signo) == 0);
    int status = 0;
    REQUIRE(::waitpid(pid, &status, 0) == pid);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The N of "interrupted by NAME: N frames written to ..." (-1 if absent).
long long frames_reported(const std::string& err, const std::string& name) {
    const std::string head = "interrupted by " + name + ": ";
    const size_t at = err.find(head);
    return at == std::string::npos ? -1 : std::atoll(err.c_str() + at + head.size());
}

}  // namespace

TEST_CASE("SIGTERM and SIGHUP close a video as SIGINT does, with exit status 128 + signal",
          "[cli][video][dataloss]") {
    for (const auto& [signo, name] : {std::pair{SIGTERM, "SIGTERM"}, std::pair{SIGHUP, "SIGHUP"},
                                      std::pair{SIGINT, "SIGINT"}}) {
        INFO(name);
        TempDir dir("signal");
        write_file(dir / "long.toml", kLong);
        const std::string out = dir / "clip.mp4", err = dir / "stderr";
        const pid_t pid = spawn_impulse({"render", dir / "long.toml", "-o", out, "-q"}, err);
        REQUIRE(pid > 0);
        wait_until([&] {
            for (const auto& e : fs::directory_iterator(dir.path()))
                if (e.path().filename().string().find("partial") != std::string::npos &&
                    fs::file_size(e.path()) > 0)
                    return true;
            return false;
        });
        CHECK(stop_with(pid, signo) == 128 + signo);
        const std::string text = read_file(err);
        INFO(text);
        const long long n = frames_reported(text, name);
        CHECK(n > 0);
        REQUIRE(fs::exists(out));
        const auto info = impulse::output::probe_video(out);
        CHECK(info.frame_count == n);  // every frame it says it wrote plays
        CHECK(info.width == 320);
        for (const auto& e : dir.files()) CHECK(e.find("partial") == std::string::npos);
    }
    TempDir dir("signal-help");
    CHECK_THAT(run(dir, "render --help").out, Contains("SIGTERM (143)"));
}

TEST_CASE("SIGTERM stops an image sequence between frames: every file whole, 143",
          "[cli][dataloss]") {
    TempDir dir("signal-seq");
    write_file(dir / "long.toml", kLong);
    fs::create_directories(dir.path() / "seq");
    const std::string err = dir / "stderr";
    const pid_t pid =
        spawn_impulse({"render", dir / "long.toml", "-o", dir / "seq/f_######.png", "-q"}, err);
    REQUIRE(pid > 0);
    wait_until([&] { return fs::exists(dir / "seq/f_000001.png"); });
    CHECK(stop_with(pid, SIGTERM) == 143);
    const std::vector<std::string> files = names_in(dir.path() / "seq");
    INFO(read_file(err));
    CHECK(frames_reported(read_file(err), "SIGTERM") == static_cast<long long>(files.size()));
    for (const auto& f : files) {
        CHECK(f.find("partial") == std::string::npos);
        CHECK_NOTHROW(impulse::output::read_image((dir.path() / "seq" / f).string()));
    }
}

namespace {

const std::string kFour = windy_scene(96, 72, 4, 12.0, "[20.0, 5.0]");

void copy(const std::string& from, const std::string& to) {
    fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

}  // namespace

TEST_CASE("render --resume renders again the frames that do not check out, and says why",
          "[cli][dataloss]") {
    TempDir dir("resume");
    write_file(dir / "four.toml", kFour);
    const std::string scene = quote(dir / "four.toml");
    for (const char* d : {"ref", "seq", "other"}) fs::create_directories(dir.path() / d);
    REQUIRE(run(dir, "render " + scene + " -q -o " + quote(dir / "ref/f_####.png")).status == 0);
    REQUIRE(run(dir, "render " + scene + " -q --seed 5 -o " + quote(dir / "other/f_####.png")).status == 0);
    for (int f = 0; f < 4; ++f)
        copy(dir / ("ref/f_000" + std::to_string(f) + ".png"), dir / ("seq/f_000" + std::to_string(f) + ".png"));
    // Frame 1 cut short (a full disk, a killed copy), frame 2 of another seed, frame 3 a copy
    // of frame 0; frame 0 is right.
    const std::string one = read_file(dir / "ref/f_0001.png");
    write_file(dir / "seq/f_0001.png", one.substr(0, one.size() / 2));
    copy(dir / "other/f_0002.png", dir / "seq/f_0002.png");
    copy(dir / "ref/f_0000.png", dir / "seq/f_0003.png");

    const Result r = run(dir, "render " + scene + " -q --resume -o " + quote(dir / "seq/f_####.png"));
    INFO(r.out << r.err);
    CHECK(r.status == 0);
    const auto lines = r.err_lines();
    REQUIRE(lines.size() == 3);
    CHECK_THAT(lines[0], Contains("f_0001.png: rendering again: "));
    CHECK_THAT(lines[0], Contains("truncated"));
    CHECK_THAT(lines[1], Contains("f_0002.png: rendering again: impulse:seed is "));
    CHECK_THAT(lines[2], Contains("f_0003.png: rendering again: impulse:frame is 0, expected 3"));
    CHECK_THAT(r.out, Contains("3 frames, 1 already present, 3 replaced"));
    for (int f = 0; f < 4; ++f) {
        const std::string name = "f_000" + std::to_string(f) + ".png";
        CHECK(read_file(dir / ("seq/" + name)) == read_file(dir / ("ref/" + name)));
    }

    // TIFF keeps no metadata: size, channels and a whole decode are what is checked.
    REQUIRE(run(dir, "render " + scene + " -q --size 64x48 -o " + quote(dir / "t_####.tif")).status == 0);
    const Result t = run(dir, "render " + scene + " -q --resume -o " + quote(dir / "t_####.tif"));
    CHECK(t.status == 0);
    CHECK(t.err_lines().size() == 5);
    CHECK_THAT(t.err, Contains("this format keeps no metadata"));
    CHECK_THAT(t.err, Contains("t_0000.tif: rendering again: 64x48 pixels, expected 96x72"));
    CHECK(impulse::output::probe_image(dir / "t_0003.tif").width == 96);
}

TEST_CASE("render --resume removes the temporaries of killed runs of its own pattern", "[cli][dataloss]") {
    TempDir dir("stale");
    write_file(dir / "four.toml", kFour);
    fs::create_directories(dir.path() / "seq");
    const auto seq = [&](const std::string& name) { return dir / ("seq/" + name); };
    // Above Linux's largest pid_max (2^22): no such process.
    const std::string gone = "4194305", alive = std::to_string(::getpid());
    write_file(seq(".f_0002.partial-" + gone + ".png"), "half a frame");
    write_file(seq(".f_0003.partial-" + alive + ".png"), "being written");
    write_file(seq(".f_0001.partial-" + gone + ".png"), "just written");
    write_file(seq(".g_0001.partial-" + gone + ".png"), "another pattern's");
    const auto hour_ago = fs::file_time_type::clock::now() - std::chrono::hours(1);
    for (const char* n : {".f_0002.partial-", ".f_0003.partial-", ".g_0001.partial-"})
        for (const auto& e : fs::directory_iterator(dir.path() / "seq"))
            if (e.path().filename().string().rfind(n, 0) == 0) fs::last_write_time(e.path(), hour_ago);

    const Result r = run(dir, "render " + quote(dir / "four.toml") + " -q --resume -o " + quote(seq("f_####.png")));
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK_FALSE(fs::exists(seq(".f_0002.partial-" + gone + ".png")));
    CHECK_THAT(r.err, Contains("removed " + seq(".f_0002.partial-" + gone + ".png") + ": a stale temporary"));
    // A running process's, a minute-fresh one (maybe another machine's on shared storage), and
    // another pattern's stay.
    CHECK(fs::exists(seq(".f_0003.partial-" + alive + ".png")));
    CHECK_THAT(r.err, Contains(".f_0003.partial-" + alive + ".png: left in place: process " + alive + " is running"));
    CHECK(fs::exists(seq(".f_0001.partial-" + gone + ".png")));
    CHECK_THAT(r.err, Contains("left in place: written less than a minute ago"));
    CHECK(fs::exists(seq(".g_0001.partial-" + gone + ".png")));
    CHECK(fs::exists(seq("f_0003.png")));
}
