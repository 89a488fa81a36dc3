// SPDX-License-Identifier: Apache-2.0
// `impulse farm` (app/farm.h): Slurm array scripts for a sequence render, and their submission.

#include "app/farm.h"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>

#include "numeric/errors.h"
#include "output/output.h"
#include "scenes/scenes.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

/// Single-quoted for sh (a ' inside becomes '\'').
std::string quoted(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

/// What run_farm worked out before writing anything.
struct Plan {
    std::string impulse, scene, pattern, video, script, encode_script, logs, stem;
    long long first = 0, last = 0, chunk = 1, tasks = 1;
};

/// The path of this executable (the nodes run the same install, by absolute path).
std::string own_executable() {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (ec) throw IoError("/proc/self/exe: cannot find the impulse executable: " + ec.message());
    return self.string();
}

void check_sbatch_values(const FarmOptions& o) {
    // Slurm's time formats: M, M:S, H:M:S, D-H, D-H:M, D-H:M:S (sbatch(1) --time).
    static const std::regex time(
        R"((\d+(:\d{1,2}){0,2}|\d+-\d+(:\d{1,2}){0,2}|UNLIMITED|INFINITE))");
    static const std::regex partition(R"([A-Za-z0-9_.-]+(,[A-Za-z0-9_.-]+)*)");
    if (!o.time.empty() && !std::regex_match(o.time, time))
        throw ValueError("--time " + o.time +
                         ": expected minutes, H:M:S, D-H or D-H:M:S (sbatch --time)");
    if (!o.partition.empty() && !std::regex_match(o.partition, partition))
        throw ValueError("--partition " + o.partition +
                         ": expected a partition name (letters, digits, _ . -)");
    if (!o.cpus.empty() &&
        whole_number("--cpus-per-task", o.cpus, o.cpus, "a positive integer") < 1)
        throw ValueError("--cpus-per-task " + o.cpus + ": expected a positive integer");
    if (!o.max_running.empty() &&
        whole_number("--max-running", o.max_running, o.max_running, "a positive integer") < 1)
        throw ValueError("--max-running " + o.max_running + ": expected a positive integer");
}

Plan make_plan(const FarmOptions& o, const scenes::Scene& scene) {
    Plan p;
    const std::string& out = o.render.output;
    const std::string name = fs::path(out).filename().string();
    if (out.empty() || !find_pattern(name).found || !output::is_image_path(name))
        throw ValueError("-o " + (out.empty() ? std::string("(none)") : out) +
                         ": expected an image-sequence pattern in the file name, e.g. "
                         "frames/f_####.exr (each array task writes its own frames)");
    p.chunk =
        whole_number("--chunk", o.chunk, o.chunk, "a positive number of frames per array task");
    if (p.chunk < 1)
        throw ValueError("--chunk " + o.chunk +
                         ": expected a positive number of frames per array task");
    p.last = scene.output.frames - 1;
    if (!o.render.frames.empty())
        std::tie(p.first, p.last) = parse_frame_range(o.render.frames, scene.output.frames);
    p.tasks = (p.last - p.first) / p.chunk + 1;
    p.impulse = own_executable();
    p.scene = fs::absolute(scene.path).lexically_normal().string();
    p.pattern = fs::absolute(out).lexically_normal().string();
    const fs::path dir = fs::path(p.pattern).parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw IoError(out + ": output directory " + dir.string() + " does not exist");
    p.stem = fs::path(p.scene).stem().string();
    p.video = o.video.empty() ? (dir / (p.stem + ".mp4")).string() : fs::absolute(o.video).string();
    if (!output::is_video_path(p.video))
        throw ValueError("--video " + o.video + ": expected a video (.mp4 .mov .mkv .webm)");
    p.script =
        o.script.empty() ? (dir / (p.stem + ".sbatch")).string() : fs::absolute(o.script).string();
    const fs::path s(p.script);
    p.encode_script = (s.parent_path() / (s.stem().string() + ".encode.sbatch")).string();
    p.logs = dir.string();
    return p;
}

/// The render options every task passes on (the frame range is the task's own).
std::string render_arguments(const RenderOptions& r) {
    std::string a;
    if (!r.size.empty()) a += " --size " + quoted(r.size);
    if (!r.crop.empty()) a += " --crop " + quoted(r.crop);
    if (!r.seed.empty()) a += " --seed " + quoted(r.seed);
    for (const auto& s : r.sets) a += " --set " + quoted(s);
    if (r.tile != 128) a += " --tile " + std::to_string(r.tile);
    return a;
}

std::string sbatch_header(const FarmOptions& o, const std::string& job, const std::string& log) {
    std::string h = "#SBATCH --job-name=" + job + "\n#SBATCH --output=" + log + "\n";
    if (!o.partition.empty()) h += "#SBATCH --partition=" + o.partition + "\n";
    if (!o.time.empty()) h += "#SBATCH --time=" + o.time + "\n";
    return h;
}

std::string submit_line(const Plan& p) {
    return "jid=$(sbatch --parsable " + quoted(p.script) +
           ") && sbatch --dependency=afterok:$jid " + quoted(p.encode_script);
}

std::string array_script(const FarmOptions& o, const Plan& p) {
    const std::string first = std::to_string(p.first), last = std::to_string(p.last),
                      chunk = std::to_string(p.chunk);
    std::string s =
        "#!/bin/bash\n# Written by `impulse farm`: frames " + first + "-" + last + " of " +
        p.scene + " as " + std::to_string(p.tasks) + " array tasks of " + chunk +
        " frames.\n# Submit with the encode job (it runs when every task succeeded):\n#   " +
        submit_line(p) +
        "\n# Failed or preempted tasks resubmitted resume where they stopped (whole frames "
        "are kept),\n# e.g. task " +
        std::to_string(p.tasks - 1) + ": sbatch --array=" + std::to_string(p.tasks - 1) + " " +
        quoted(p.script) + "\n";
    s += sbatch_header(o, "impulse-" + p.stem, p.logs + "/slurm-%A_%a.out");
    s += "#SBATCH --array=0-" + std::to_string(p.tasks - 1) +
         (o.max_running.empty() ? "" : "%" + o.max_running) + "\n";
    if (!o.cpus.empty()) s += "#SBATCH --cpus-per-task=" + o.cpus + "\n";
    // Slurm sends SIGTERM at the time limit: render stops between frames, keeping whole ones.
    s += "set -eu\nfirst=$((" + first + " + SLURM_ARRAY_TASK_ID * " + chunk +
         "))\nlast=$((first + " + chunk + " - 1))\nif [ \"$last\" -gt " + last +
         " ]; then last=" + last + "; fi\n";
    s += "exec " + quoted(p.impulse) + " render " + quoted(p.scene) + " -o " + quoted(p.pattern) +
         " --frames \"$first-$last\" --resume --quiet" + render_arguments(o.render) +
         (o.cpus.empty() ? "" : " --threads \"$SLURM_CPUS_PER_TASK\"") + "\n";
    return s;
}

std::string encode_script(const FarmOptions& o, const Plan& p) {
    std::string s = "#!/bin/bash\n# Written by `impulse farm`: assembles " + p.video +
                    " once every task of " + p.script + " succeeded.\n";
    s += sbatch_header(o, "impulse-" + p.stem + "-encode", p.logs + "/slurm-%j.out");
    // A task that failed makes afterok unsatisfiable: the job is cancelled rather than left
    // pending for ever; after resubmitting the tasks, submit this script again after them.
    s += "#SBATCH --kill-on-invalid-dep=yes\n";
    s += "set -eu\nexec " + quoted(p.impulse) + " encode " + quoted(p.pattern) + " -o " +
         quoted(p.video) + " --frames " + std::to_string(p.first) + "-" + std::to_string(p.last) +
         (o.render.codec.empty() ? "" : " --codec " + quoted(o.render.codec)) + "\n";
    return s;
}

/// The GNU parallel command line that renders the same chunks on one machine, then encodes.
std::string parallel_line(const FarmOptions& o, const Plan& p) {
    std::string chunks;
    for (long long t = 0; t < std::min<long long>(p.tasks, 12); ++t)
        chunks += " " + std::to_string(p.first + t * p.chunk) + "-" +
                  std::to_string(std::min(p.last, p.first + (t + 1) * p.chunk - 1));
    if (p.tasks > 12) chunks += " ...";
    return "parallel impulse render " + quoted(p.scene) + " -o " + quoted(p.pattern) +
           " --resume -q" + render_arguments(o.render) + " --frames {} :::" + chunks +
           " && impulse encode " + quoted(p.pattern) + " -o " + quoted(p.video);
}

/// `name` on PATH, or "".
std::string on_path(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "";
    for (size_t start = 0; start <= dirs.size();) {
        const size_t end = dirs.find(':', start);
        const std::string d = dirs.substr(start, end == std::string::npos ? end : end - start);
        const fs::path candidate = fs::path(d.empty() ? "." : d) / name;
        if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return "";
}

/// Written whole or not at all: a temporary beside `path`, checked, made executable, renamed.
void write_script(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".partial-" + std::to_string(::getpid());
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        out << text;
        out.close();
        if (!out) {
            std::error_code ec;
            fs::remove(tmp, ec);
            throw IoError(path + ": cannot write the script");
        }
    }
    std::error_code ec;
    fs::permissions(tmp,
                    fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                        fs::perms::others_read | fs::perms::others_exec,
                    ec);
    if (!ec) fs::rename(tmp, path, ec);
    if (ec) {
        fs::remove(tmp, ec);
        throw IoError(path + ": cannot write the script: " + ec.message());
    }
}

/// Runs `sbatch --parsable ARGS`; returns the job id, or throws with sbatch's own words.
std::string sbatch(const std::string& sbatch_path, const std::string& args) {
    const std::string command = quoted(sbatch_path) + " --parsable " + args + " 2>&1";
    FILE* pipe = ::popen(command.c_str(), "r");
    if (!pipe) throw IoError("sbatch: cannot run: " + std::string(std::strerror(errno)));
    std::string text;
    char buf[512];
    while (std::fgets(buf, sizeof buf, pipe)) text += buf;
    const int status = ::pclose(pipe);
    std::smatch m;
    static const std::regex id(R"((\d+)(;\S+)?\s*)");
    if (status != 0 || !std::regex_match(text, m, id)) {
        while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
        std::replace(text.begin(), text.end(), '\n', ' ');
        throw IoError("sbatch " + args + ": " + (text.empty() ? "failed" : text.substr(0, 300)));
    }
    return m[1].str();
}

}  // namespace

CLI::App* add_farm(CLI::App& app, FarmOptions& o) {
    CLI::App* c = app.add_subcommand(
        "farm",
        "Render on a Slurm cluster: write an sbatch array script (one task per chunk of "
        "frames, each `render --frames A-B --resume`) and a dependent encode job; "
        "--submit submits them");
    c->add_option("scene", o.render.scene, "Scene file (TOML) or built-in scene name")->required();
    c->add_option("-o,--output", o.render.output,
                  "Frames: a sequence pattern, e.g. frames/f_####.exr")
        ->required();
    c->add_option("--chunk", o.chunk, "Frames per array task")->required();
    c->add_option("--partition", o.partition, "Slurm partition (sbatch --partition)");
    c->add_option("--time", o.time, "Time limit per task (sbatch --time, e.g. 30 or 2:00:00)");
    c->add_option("--cpus-per-task", o.cpus,
                  "CPUs per task (sbatch --cpus-per-task; the render's --threads)");
    c->add_option("--max-running", o.max_running, "At most N tasks at once (sbatch --array=...%N)");
    c->add_option("--video", o.video,
                  "The encode job's video (default: beside the frames, SCENE.mp4)");
    c->add_option("--script", o.script,
                  "The array script (default: beside the frames, SCENE.sbatch)");
    c->add_flag("--submit", o.submit, "Submit with sbatch and print the array's job id");
    c->add_option("--frames", o.render.frames, "Inclusive 0-based frame range A-B (default: all)");
    c->add_option("--size", o.render.size, "The scene at WxH pixels (as render --size)");
    c->add_option("--crop", o.render.crop, "A WxH window at the scene's scale (as render --crop)");
    c->add_option("--seed", o.render.seed, "Scene-wide seed (as render --seed)");
    c->add_option("--set", o.render.sets, "Override a scene key (as render --set)")
        ->allow_extra_args(false);
    c->add_option("--codec", o.render.codec,
                  "The encode job's codec: auto, h264, prores, ffv1, vp9");
    return c;
}

int run_farm(const FarmOptions& o) {
    check_sbatch_values(o);
    RenderOptions checked = o.render;
    checked.codec.clear();  // the frames are images; the codec is the encode job's
    const scenes::Scene scene = load_render_scene(checked);
    if (!o.render.codec.empty()) output::video_codec_from_string(o.render.codec);
    const Plan p = make_plan(o, scene);
    const std::string sbatch_path = o.submit ? on_path("sbatch") : "";
    if (o.submit && sbatch_path.empty())
        throw IoError(
            "--submit: sbatch not found on PATH: install Slurm's client (Debian: apt-get "
            "install slurm-client) on a machine of the cluster, or render here with GNU "
            "parallel: " +
            parallel_line(o, p));
    write_script(p.script, array_script(o, p));
    write_script(p.encode_script, encode_script(o, p));
    if (!o.submit) {
        std::cout << "wrote " << p.script << " (" << p.tasks << " array task"
                  << (p.tasks == 1 ? "" : "s") << " of up to " << p.chunk << " frames) and "
                  << p.encode_script << "\nsubmit with: " << submit_line(p) << "\n";
        return 0;
    }
    const std::string job = sbatch(sbatch_path, quoted(p.script));
    std::string encode;
    try {
        encode = sbatch(sbatch_path, "--dependency=afterok:" + job + " " + quoted(p.encode_script));
    } catch (const IoError& e) {
        throw IoError(std::string(e.what()) + " (array job " + job + " is submitted: run " +
                      quoted(p.encode_script) + " when it is done)");
    }
    std::cerr << "submitted array job " << job << " (" << p.tasks << " tasks) and encode job "
              << encode << " (" << p.video << ", after every task succeeded)\n";
    std::cout << job << "\n";
    return 0;
}

}  // namespace impulse::app
