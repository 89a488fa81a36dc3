// SPDX-License-Identifier: Apache-2.0
// impulse_bench_motion: the motion benchmarks of issue "Motion" item 9, side by side in one run,
// on the default scene (`drift`, 1920x1080, 30 fps, Gaussian layers carried by wind + curl
// noise):
//   1. sequential frame cost: one scenes::Renderer stepping frames forward (design.md §3);
//   2. random-access cost of frame 10 000: a fresh Renderer integrating every live particle
//      from birth, and its ratio to (1);
//   3. end-to-end frames per second of a 1080p30 H.264 render as the CLI does it (render, shade
//      band by band into the encoder's input, encode on another thread while the next frame
//      renders) with the ultrafast and veryfast presets, and render alone;
//   4. peak resident memory of the `impulse` CLI rendering one 3840x2160 frame to EXR and three
//      to MP4, measured on the child process with wait4().
// Times are medians of repetitions with min and max (std::chrono::steady_clock). See
// bench/README.md ("impulse_bench_motion") for what each row measures.

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "bench/common.h"
#include "kernels/kernels.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "sim/sim.h"

namespace {

namespace fs = std::filesystem;
using namespace impulse;
using namespace impulse::bench;

constexpr const char* kScene = "drift";
constexpr int64_t kRandomFrame = 10000;       ///< the random-access frame of the issue
constexpr double kTargetRatio = 2.0;          ///< random access <= 2x a sequential frame
constexpr double kTargetFps = 24.0;           ///< 1080p30 H.264 end to end, a fast preset
constexpr double kTargetPeakMib = 400.0;      ///< one 3840x2160 frame
constexpr int kBigWidth = 3840, kBigHeight = 2160;

struct Options {
    bool quick = false;
    bool csv = false;
    std::string impulse_path;  ///< the CLI for the memory rows; default: ../app/impulse
    int seq_frames = 60;       ///< timed sequential frames after the first
    int random_reps = 7;       ///< fresh renderers for the random-access frame
    int e2e_frames = 120;      ///< frames per end-to-end run
    int e2e_reps = 3;          ///< end-to-end runs per variant
    int rss_reps = 3;          ///< CLI runs per memory row
};

[[noreturn]] void usage_error(const std::string& message) {
    throw std::invalid_argument(message +
                                " (usage: impulse_bench_motion [--quick] [--csv] [--impulse PATH] "
                                "[--seq-frames N] [--random-reps N] [--e2e-frames N] "
                                "[--e2e-reps N] [--rss-reps N])");
}

int parse_int(std::string_view flag, const char* text, int lo, int hi) {
    char* end = nullptr;
    const long v = std::strtol(text, &end, 10);
    if (end == text || *end != '\0' || v < lo || v > hi)
        usage_error(std::string(flag) + " = " + text + ": expected an integer in [" +
                    std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<int>(v);
}

Options parse_args(int argc, char** argv) {
    Options o;
    std::optional<int> seq, random, e2e_frames, e2e_reps, rss;
    for (int i = 1; i < argc; ++i) {
        const std::string_view a = argv[i];
        auto value = [&]() -> const char* {
            if (i + 1 >= argc) usage_error(std::string(a) + ": missing value");
            return argv[++i];
        };
        if (a == "--quick") o.quick = true;
        else if (a == "--csv") o.csv = true;
        else if (a == "--impulse") o.impulse_path = value();
        else if (a == "--seq-frames") seq = parse_int(a, value(), 2, 5000);
        else if (a == "--random-reps") random = parse_int(a, value(), 1, 1000);
        else if (a == "--e2e-frames") e2e_frames = parse_int(a, value(), 1, 100000);
        else if (a == "--e2e-reps") e2e_reps = parse_int(a, value(), 1, 100);
        else if (a == "--rss-reps") rss = parse_int(a, value(), 0, 100);
        else usage_error("unknown argument \"" + std::string(a) + "\"");
    }
    if (o.quick) o.seq_frames = 15, o.random_reps = 3, o.e2e_frames = 30, o.e2e_reps = 1,
                 o.rss_reps = 1;
    o.seq_frames = seq.value_or(o.seq_frames);
    o.random_reps = random.value_or(o.random_reps);
    o.e2e_frames = e2e_frames.value_or(o.e2e_frames);
    o.e2e_reps = e2e_reps.value_or(o.e2e_reps);
    o.rss_reps = rss.value_or(o.rss_reps);
    return o;
}

// ---------------------------------------------------------------------------------------------
// Small helpers

/// Output of the report: text rows on stdout, or CSV rows on stdout with the text going to
/// stderr (so stdout stays pure CSV).
struct Report {
    bool csv = false;
    FILE* info() const { return csv ? stderr : stdout; }
    void row(const char* name, const char* unit, const Stats& s) const {
        if (csv) std::printf("%s,%s,%.4f,%.4f,%.4f,%zu\n", name, unit, s.med, s.min, s.max, s.n);
        std::fflush(stdout);
    }
};

scenes::Scene load_default(const std::vector<std::string>& overrides = {}) {
    return scenes::load_scene(scenes::resolve_scene(kScene), overrides);
}

/// A scratch directory removed with everything in it when the benchmark ends.
class TempDir {
public:
    TempDir() {
        const char* t = std::getenv("TMPDIR");
        std::string pattern = std::string(t && *t ? t : "/tmp") + "/impulse_bench_motion.XXXXXX";
        if (!::mkdtemp(pattern.data()))
            throw std::runtime_error(pattern + ": cannot create a temporary directory: " +
                                     std::strerror(errno));
        m_path = pattern;
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(m_path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::string file(const std::string& name) const { return m_path + "/" + name; }

private:
    std::string m_path;
};

// ---------------------------------------------------------------------------------------------
// 1 + 2: sequential and random-access frames through scenes::Renderer

struct FrameCosts {
    int64_t seq_first = 0;   ///< first frame of the sequential run (integrates from birth)
    double first_ms = 0;     ///< its cost
    Stats seq;               ///< ms per frame, frames seq_first+1 .. kRandomFrame
    double seq_cpu_ms = 0;   ///< process CPU time (all threads) per timed sequential frame
    Stats random;            ///< ms, render(kRandomFrame) on a fresh Renderer
    Stats random_cpu;        ///< process CPU ms (all threads) of the same calls
    Stats construct;         ///< ms, load_scene not included: Renderer constructor only
    size_t impulses = 0;     ///< live impulses emitted for the view at kRandomFrame, all layers
    double generated = 0;    ///< expected impulses generated in the birth region
    bool identical = false;  ///< random-access frame == sequential frame, bit for bit
    bool range_override = false;  ///< output.frames had to be raised for frame 10 000
};

bool same_bits(const render::Frame& a, const render::Frame& b) {
    return a.width == b.width && a.height == b.height &&
           std::memcmp(a.data.data(), b.data.data(), a.data.size() * sizeof(float)) == 0;
}

FrameCosts measure_frames(const Options& o) {
    FrameCosts r;
    // Frame 10 000 is past output.frames (240). The CLI refuses it; the Renderer is expected
    // not to check. If it does, rerun with the range raised and say so.
    std::vector<std::string> overrides;
    {
        scenes::Renderer probe(load_default());
        render::Frame f;
        try {
            probe.render(kRandomFrame, f);
        } catch (const std::exception&) {
            overrides = {"output.frames=20000"};
            r.range_override = true;
        }
    }

    // Sequential: frames seq_first .. kRandomFrame with one Renderer, so the last frame can be
    // compared with the random-access one. The first frame integrates from birth: reported
    // apart, excluded from the statistics.
    r.seq_first = kRandomFrame - o.seq_frames;
    render::Frame seq_last;
    {
        scenes::Renderer seq(load_default(overrides));
        render::Frame f;
        auto t0 = Clock::now();
        seq.render(r.seq_first, f);
        r.first_ms = ms_since(t0);
        std::vector<double> ms;
        const double cpu0 = own_cpu_s();
        for (int64_t fr = r.seq_first + 1; fr <= kRandomFrame; ++fr) {
            t0 = Clock::now();
            seq.render(fr, f);
            ms.push_back(ms_since(t0));
        }
        r.seq_cpu_ms = (own_cpu_s() - cpu0) * 1e3 / double(ms.size());
        r.seq = summarise(ms);
        for (size_t i = 0; i < seq.scene().layers.size(); ++i) r.impulses += seq.impulses(i).size();
        seq_last = std::move(f);
        for (size_t i = 0; i < seq.scene().layers.size(); ++i) {
            const auto& l = seq.scene().layers[i];
            const auto& out = seq.scene().output;
            sim::LayerSimulator s(l.process, l.flow, sim::Timing{out.fps, 0}, l.kernel.radius);
            const render::View v = seq.scene().camera.view(out.width, out.height, 0.0);
            r.generated += sim::expected_impulses(l.process, s.birth_region(v.box()));
        }
    }

    // Random access: a fresh scene (its own flow object and caches) and Renderer per run;
    // the scene is loaded outside the timer.
    std::vector<double> ms, cons, cpu;
    r.identical = true;
    for (int rep = 0; rep < o.random_reps; ++rep) {
        scenes::Scene scene = load_default(overrides);
        auto t0 = Clock::now();
        scenes::Renderer fresh(std::move(scene));
        cons.push_back(ms_since(t0));
        render::Frame f;
        const double cpu0 = own_cpu_s();
        t0 = Clock::now();
        fresh.render(kRandomFrame, f);
        ms.push_back(ms_since(t0));
        cpu.push_back((own_cpu_s() - cpu0) * 1e3);
        r.identical = r.identical && same_bits(f, seq_last);
    }
    r.random = summarise(ms);
    r.random_cpu = summarise(cpu);
    r.construct = summarise(cons);
    return r;
}

/// Where a frame's time goes: the same work as scenes::Renderer::render (one simulator and
/// kernel per layer, impulses_at then render::accumulate), timed in two parts.
struct Split {
    Stats seq_sim, seq_eval, random_sim, random_eval;
};

Split measure_split(const Options& o, int64_t seq_first) {
    struct Layer {
        kernels::Kernel kernel;
        sim::LayerSimulator sim;
    };
    auto make = [](const scenes::Scene& s) {
        std::vector<Layer> layers;
        const sim::Timing timing{s.output.fps, std::llround(s.output.start_s * s.output.fps)};
        for (const auto& l : s.layers)
            layers.push_back({kernels::Kernel(l.kernel),
                              sim::LayerSimulator(l.process, l.flow, timing, l.kernel.radius)});
        return layers;
    };
    auto frame_view = [](const scenes::Scene& s, int64_t fr) {
        const auto& out = s.output;
        const double t = (std::llround(out.start_s * out.fps) + fr) / out.fps;
        return s.camera.view(out.width, out.height, t);
    };
    auto run = [&](std::vector<Layer>& layers, const scenes::Scene& s, int64_t fr,
                   render::Frame& f, sim::Impulses& imp, double& sim_ms, double& eval_ms) {
        const render::View v = frame_view(s, fr);
        f.resize(v.width, v.height);
        sim_ms = eval_ms = 0;
        for (auto& l : layers) {
            auto t0 = Clock::now();
            l.sim.impulses_at(fr, v.box(), imp);
            sim_ms += ms_since(t0);
            t0 = Clock::now();
            render::accumulate(l.kernel, imp, v, f);
            eval_ms += ms_since(t0);
        }
    };
    const std::vector<std::string> overrides = {"output.frames=20000"};  // range unchecked here
    Split r;
    render::Frame f;
    sim::Impulses imp;
    double s_ms = 0, e_ms = 0;
    {
        const scenes::Scene scene = load_default(overrides);
        auto layers = make(scene);
        run(layers, scene, seq_first, f, imp, s_ms, e_ms);  // from birth: not counted
        std::vector<double> sv, ev;
        for (int64_t fr = seq_first + 1; fr <= kRandomFrame; ++fr) {
            run(layers, scene, fr, f, imp, s_ms, e_ms);
            sv.push_back(s_ms), ev.push_back(e_ms);
        }
        r.seq_sim = summarise(sv), r.seq_eval = summarise(ev);
    }
    std::vector<double> sv, ev;
    for (int rep = 0; rep < o.random_reps; ++rep) {
        const scenes::Scene scene = load_default(overrides);
        auto layers = make(scene);
        run(layers, scene, kRandomFrame, f, imp, s_ms, e_ms);
        sv.push_back(s_ms), ev.push_back(e_ms);
    }
    r.random_sim = summarise(sv), r.random_eval = summarise(ev);
    return r;
}

// ---------------------------------------------------------------------------------------------
// 3: end to end, 1080p30 H.264

struct Variant {
    const char* name;
    const char* preset;  ///< nullptr: render only, no mapping, no encoder
    std::vector<double> fps, cpu_ms, render_ms, stage_ms, encode_ms, wait_ms, open_close_ms;
};

/// One run: frames 0 .. n-1 of the default scene on a fresh Renderer, as `impulse render`
/// does for a video (app/render.cpp): render frame f, stage it (VideoWriter::stage_shaded:
/// output::Shader straight into the encoder's YUV 4:2:0 planes), then encode it on another
/// thread (VideoWriter::encode_staged) while frame f + 1 renders. Returns frames per second
/// over the whole run (open and close included).
void run_e2e(Variant& v, int n, const std::string& path) {
    scenes::Renderer renderer(load_default());
    const scenes::OutputConfig& out = renderer.scene().output;
    const output::Shader shader(renderer.mapping(), renderer.scene().shading);
    render::Frame frame;
    output::VideoWriter writer;
    double render_ms = 0, stage_ms = 0, encode_ms = 0, wait_ms = 0, oc_ms = 0;
    std::future<void> pending;  // the previous frame's encode
    const auto start = Clock::now();
    const double cpu0 = own_cpu_s();
    if (v.preset) {
        output::VideoOptions vo;
        vo.width = out.width, vo.height = out.height, vo.fps = out.fps;
        vo.codec = output::VideoCodec::H264;
        vo.crf = out.crf, vo.preset = v.preset;
        const auto t0 = Clock::now();
        writer.open(path, vo);
        oc_ms += ms_since(t0);
    }
    for (int f = 0; f < n; ++f) {
        auto t0 = Clock::now();
        renderer.render(f, frame);
        render_ms += ms_since(t0);
        if (!v.preset) continue;
        t0 = Clock::now();
        if (pending.valid()) pending.get();
        wait_ms += ms_since(t0);
        t0 = Clock::now();
        writer.stage_shaded(frame, shader);
        stage_ms += ms_since(t0);
        pending = std::async(std::launch::async, [&] {
            const auto e0 = Clock::now();
            writer.encode_staged();
            encode_ms += ms_since(e0);  // read after pending.get(): ordered by the future
        });
    }
    if (v.preset) {
        auto t0 = Clock::now();
        if (pending.valid()) pending.get();
        wait_ms += ms_since(t0);
        t0 = Clock::now();
        writer.close();  // flushes the frames x264 still holds (lookahead, frame threads)
        oc_ms += ms_since(t0);
    }
    const double total_s = ms_since(start) / 1e3;
    v.fps.push_back(n / total_s);
    v.cpu_ms.push_back((own_cpu_s() - cpu0) * 1e3 / n);
    v.render_ms.push_back(render_ms / n);
    v.stage_ms.push_back(stage_ms / n);
    v.encode_ms.push_back(encode_ms / n);
    v.wait_ms.push_back(wait_ms / n);
    v.open_close_ms.push_back(oc_ms);
    std::error_code ec;
    fs::remove(path, ec);
}

// ---------------------------------------------------------------------------------------------
// 4: peak memory of the CLI at 3840x2160

std::string default_impulse_path() {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return "";
    return (self.parent_path().parent_path() / "app" / "impulse").string();
}

struct ChildRun {
    double peak_mib = 0;
    double wall_s = 0;
};

/// Runs `argv` with stdout and stderr to `log`; peak RSS of that child from wait4(). Throws
/// with the child's output when it fails.
ChildRun run_child(const std::vector<std::string>& argv, const std::string& log) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::fflush(stdout), std::fflush(stderr);
    const auto t0 = Clock::now();
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) ::dup2(fd, 1), ::dup2(fd, 2), ::close(fd);
        ::execv(args[0], args.data());
        std::fprintf(stderr, "execv %s: %s\n", args[0], std::strerror(errno));
        ::_exit(127);
    }
    int status = 0;
    rusage ru{};
    if (::wait4(pid, &status, 0, &ru) != pid)
        throw std::runtime_error(std::string("wait4: ") + std::strerror(errno));
    ChildRun r;
    r.wall_s = ms_since(t0) / 1e3;
    r.peak_mib = double(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::ifstream in(log);
        std::stringstream text;
        text << in.rdbuf();
        std::string cmd;
        for (const auto& a : argv) cmd += (cmd.empty() ? "" : " ") + a;
        throw std::runtime_error(cmd + ": failed (status " + std::to_string(status) + "): " +
                                 text.str());
    }
    return r;
}

struct MemoryRow {
    const char* name;
    std::vector<std::string> args;  ///< after the binary; "{dir}" files made by the caller
    std::string output;             ///< file the child writes ("" for none)
    std::vector<double> mib, wall_s;
};

// ---------------------------------------------------------------------------------------------

struct Memory {
    std::string binary;
    std::string why_not;      ///< non-empty: not measured, and why
    double own_anon_mib = 0;  ///< this process's RssAnon when the children were started
    double estimate_mib = 0;  ///< Renderer::estimated_memory_mib() at 3840x2160
    std::vector<MemoryRow> rows;
};

/// RssAnon of this process in MiB (/proc/self/status), or 0.
double own_anon_mib() {
    std::ifstream in("/proc/self/status");
    std::string key;
    double kib = 0;
    while (in >> key) {
        if (key == "RssAnon:") {
            in >> kib;
            return kib / 1024.0;
        }
        in.ignore(1 << 20, '\n');
    }
    return 0;
}

/// Peak RSS of the CLI at 3840x2160. Run before this process allocates frames: a forked
/// child starts with the parent's anonymous pages mapped, and exec records that mm's high-water
/// mark in the child's ru_maxrss, so a large parent would inflate every reading.
Memory measure_memory(const Options& o, const TempDir& tmp) {
    Memory m;
    m.binary = o.impulse_path.empty() ? default_impulse_path() : o.impulse_path;
    if (o.rss_reps == 0) {
        m.why_not = "--rss-reps 0";
        return m;
    }
    if (m.binary.empty() || ::access(m.binary.c_str(), X_OK) != 0) {
        m.why_not = "no executable at \"" + m.binary + "\" (pass --impulse PATH)";
        return m;
    }
    const std::string size = std::to_string(kBigWidth) + "x" + std::to_string(kBigHeight);
    m.rows = {{"startup (info)", {"info", kScene, "--crop", size}, "", {}, {}},
              {"1 frame .exr", {"render", kScene, "--crop", size, "--frames", "0", "-q", "-o"},
               tmp.file("big.exr"), {}, {}},
              {"3 frames .mp4", {"render", kScene, "--crop", size, "--frames", "0-2", "-q", "-o"},
               tmp.file("big.mp4"), {}, {}}};
    m.own_anon_mib = own_anon_mib();
    for (int r = 0; r < o.rss_reps; ++r)
        for (auto& row : m.rows) {
            std::vector<std::string> cmd = {m.binary};
            cmd.insert(cmd.end(), row.args.begin(), row.args.end());
            if (!row.output.empty()) cmd.push_back(row.output);
            const ChildRun c = run_child(cmd, tmp.file("child.log"));
            row.mib.push_back(c.peak_mib), row.wall_s.push_back(c.wall_s);
            std::error_code ec;
            if (!row.output.empty()) fs::remove(row.output, ec);
        }
    // Estimated after the children ran (the estimate builds a Renderer here).
    scenes::Renderer r(load_default({"output.size=[3840,2160]"}));
    m.estimate_mib = r.estimated_memory_mib();
    return m;
}

const char* verdict(bool ok) { return ok ? "PASS" : "MISS"; }

/// [1] + [2]: sequential frames and random access, with the split into simulation and
/// evaluation.
FrameCosts report_frames(const Options& o, const Report& rep, const scenes::Scene& scene) {
    FILE* info = rep.info();
    const auto& out = scene.output;
    // 1 + 2 -----------------------------------------------------------------------------
    const FrameCosts fc = measure_frames(o);
    const double ratio = fc.random.med / fc.seq.med;
    std::fprintf(info, "\n[1] sequential frames %lld..%lld, one scenes::Renderer, float frame "
                       "only (%d timed; the first is excluded)\n",
                 static_cast<long long>(fc.seq_first), static_cast<long long>(kRandomFrame),
                 o.seq_frames);
    std::fprintf(info, "    per frame                 %s ms   (%.1f CPU-ms; first frame, from "
                       "birth: %.1f ms)\n", cell(fc.seq).c_str(), fc.seq_cpu_ms, fc.first_ms);
    std::fprintf(info, "    live impulses emitted     %zu  (expected generated in the birth "
                       "region: %.0f)\n", fc.impulses, fc.generated);
    std::fprintf(info, "\n[2] random access: frame %lld alone on a fresh Renderer (%d runs; "
                       "output.frames = %lld, %s)\n",
                 static_cast<long long>(kRandomFrame), o.random_reps,
                 static_cast<long long>(out.frames),
                 fc.range_override ? "Renderer refused it: rerun with output.frames=20000"
                                   : "Renderer::render does not check the range");
    std::fprintf(info, "    render(%lld)              %s ms   = %.2fx a sequential frame (%.1f CPU-ms "
                       "= %.2fx)\n",
                 static_cast<long long>(kRandomFrame), cell(fc.random).c_str(), ratio,
                 fc.random_cpu.med, fc.random_cpu.med / fc.seq_cpu_ms);
    std::fprintf(info, "    Renderer constructor      %s ms   (scene loading not timed)\n",
                 cell(fc.construct).c_str());
    std::fprintf(info, "    same bits as the sequential frame %lld: %s\n",
                 static_cast<long long>(kRandomFrame), fc.identical ? "yes" : "NO");
    rep.row("sequential_frame", "ms", fc.seq);
    rep.row("random_access_frame_10000", "ms", fc.random);
    rep.row("random_to_sequential", "ratio", {ratio, ratio, ratio, 1});

    const Split sp = measure_split(o, fc.seq_first);
    std::fprintf(info, "    split (same work as Renderer::render, timed in parts; frame "
                       "clear excluded):\n");
    std::fprintf(info, "      sequential  impulses_at %s   accumulate %s\n",
                 cell(sp.seq_sim).c_str(), cell(sp.seq_eval).c_str());
    std::fprintf(info, "      random      impulses_at %s   accumulate %s\n",
                 cell(sp.random_sim).c_str(), cell(sp.random_eval).c_str());
    rep.row("sequential_impulses_at", "ms", sp.seq_sim);
    rep.row("sequential_accumulate", "ms", sp.seq_eval);
    rep.row("random_impulses_at", "ms", sp.random_sim);
    rep.row("random_accumulate", "ms", sp.random_eval);
    return fc;
}

/// [3]: end to end, render only and two H.264 presets, interleaved run by run.
std::vector<Variant> report_e2e(const Options& o, const Report& rep, const scenes::Scene& scene,
                                TempDir& tmp) {
    FILE* info = rep.info();
    const auto& out = scene.output;
    // 3 ---------------------------------------------------------------------------------
    std::vector<Variant> variants = {{"render only", nullptr, {}, {}, {}, {}, {}, {}, {}},
                                     {"h264 ultrafast", "ultrafast", {}, {}, {}, {}, {}, {}, {}},
                                     {"h264 veryfast", "veryfast", {}, {}, {}, {}, {}, {}, {}}};
    // Variants interleaved run by run, so drift in machine speed hits them alike.
    for (int r = 0; r < o.e2e_reps; ++r)
        for (auto& v : variants) run_e2e(v, o.e2e_frames, tmp.file("e2e.mp4"));
    std::fprintf(info, "\n[3] end to end: frames 0..%d of %s, %dx%d at %g fps, fresh Renderer, "
                       "crf %d, encoder threads auto (%d run%s each)\n",
                 o.e2e_frames - 1, kScene, out.width, out.height, out.fps, out.crf,
                 o.e2e_reps, o.e2e_reps == 1 ? "" : "s");
    std::fprintf(info, "    %-15s %-20s %-8s  per frame, ms: %-19s %-17s %-19s %-17s  "
                       "open+close ms\n",
                 "", "fps", "CPU-ms/f", "render", "stage", "encode (overlaps)", "wait");
    for (const auto& v : variants) {
        std::fprintf(info, "    %-15s %-20s %-8.1f  %-19s %-17s %-19s %-17s  %s\n", v.name,
                     cell(summarise(v.fps)).c_str(), summarise(v.cpu_ms).med,
                     cell(summarise(v.render_ms)).c_str(),
                     v.preset ? cell(summarise(v.stage_ms)).c_str() : "-",
                     v.preset ? cell(summarise(v.encode_ms)).c_str() : "-",
                     v.preset ? cell(summarise(v.wait_ms)).c_str() : "-",
                     v.preset ? cell(summarise(v.open_close_ms)).c_str() : "-");
    }
    rep.row("e2e_render_only", "fps", summarise(variants[0].fps));
    rep.row("e2e_h264_ultrafast", "fps", summarise(variants[1].fps));
    rep.row("e2e_h264_veryfast", "fps", summarise(variants[2].fps));
    return variants;
}

/// [4]: peak resident memory of the CLI (measured first, see measure_memory).
void report_memory(const Options& o, const Report& rep, const Memory& mem) {
    FILE* info = rep.info();
    // 4 (measured first, see measure_memory) ---------------------------------------------
    std::fprintf(info, "\n[4] peak resident memory of `impulse` at %dx%d (child ru_maxrss "
                       "from wait4; %d run%s each; measured before [1])\n",
                 kBigWidth, kBigHeight, o.rss_reps, o.rss_reps == 1 ? "" : "s");
    const bool have_cli = mem.why_not.empty();
    if (!have_cli) {
        std::fprintf(info, "    not measured: %s\n", mem.why_not.c_str());
    } else {
        std::fprintf(info, "    binary: %s\n", mem.binary.c_str());
        std::fprintf(info, "    floor: this process had %.0f MiB anonymous resident when it "
                           "forked (a child's ru_maxrss cannot read lower)\n",
                     mem.own_anon_mib);
        std::fprintf(info, "    Renderer::estimated_memory_mib(): %.0f MiB\n",
                     mem.estimate_mib);
        for (const auto& m : mem.rows)
            std::fprintf(info, "    %-16s %s MiB   (wall %s s)\n", m.name,
                         cell(summarise(m.mib)).c_str(), cell(summarise(m.wall_s)).c_str());
        rep.row("peak_rss_info_4k", "MiB", summarise(mem.rows[0].mib));
        rep.row("peak_rss_exr_4k", "MiB", summarise(mem.rows[1].mib));
        rep.row("peak_rss_mp4_4k", "MiB", summarise(mem.rows[2].mib));
    }
}

/// The targets, met or missed.
void report_targets(const Report& rep, const FrameCosts& fc, const std::vector<Variant>& variants,
                    const Memory& mem) {
    FILE* info = rep.info();
    const double ratio = fc.random.med / fc.seq.med;
    const bool have_cli = mem.why_not.empty();
    // 5: targets --------------------------------------------------------------------------
    std::fprintf(info, "\ntargets\n");
    std::fprintf(info, "  random access of frame %lld <= %.0fx a sequential frame: %.2fx "
                       "(%.1f / %.1f ms)  %s\n",
                 static_cast<long long>(kRandomFrame), kTargetRatio, ratio, fc.random.med,
                 fc.seq.med, verdict(ratio <= kTargetRatio));
    const double uf = summarise(variants[1].fps).med, vf = summarise(variants[2].fps).med;
    std::fprintf(info, "  1080p30 H.264 end to end >= %.0f fps with a fast preset: ultrafast "
                       "%.1f, veryfast %.1f  %s\n",
                 kTargetFps, uf, vf, verdict(std::max(uf, vf) >= kTargetFps));
    if (have_cli) {
        const double exr = summarise(mem.rows[1].mib).med,
                     mp4 = summarise(mem.rows[2].mib).med;
        std::fprintf(info, "  peak memory of a %dx%d frame <= %.0f MiB: exr %.0f, mp4 %.0f  "
                           "%s\n",
                     kBigWidth, kBigHeight, kTargetPeakMib, exr, mp4,
                     verdict(std::max(exr, mp4) <= kTargetPeakMib));
    } else {
        std::fprintf(info, "  peak memory of a %dx%d frame <= %.0f MiB: NOT MEASURED\n",
                     kBigWidth, kBigHeight, kTargetPeakMib);
    }
    if (!fc.identical)
        std::fprintf(info, "  (random access and sequential frame %lld differ: design.md §3 "
                           "frame independence is broken)\n",
                     static_cast<long long>(kRandomFrame));
}

/// Wall and CPU time of the whole run, and what other processes took meanwhile.
void report_machine(FILE* info, Clock::time_point wall0, double busy0, double own0) {
    const double busy1 = machine_busy_s(), own1 = own_cpu_s();
    std::fprintf(info, "\nload average at end: %s\n", loadavg().c_str());
    if (busy0 >= 0 && busy1 >= 0) {
        // Own CPU time excludes the CLI children; ru of children is added back.
        rusage ch{};
        getrusage(RUSAGE_CHILDREN, &ch);
        const double child = double(ch.ru_utime.tv_sec) + 1e-6 * ch.ru_utime.tv_usec +
                             double(ch.ru_stime.tv_sec) + 1e-6 * ch.ru_stime.tv_usec;
        const double wall = ms_since(wall0) / 1e3;
        const double other = std::max(0.0, (busy1 - busy0) - (own1 - own0) - child);
        std::fprintf(info, "machine: %.1f s wall, %.1f CPU-s here (+%.1f in the CLI runs), "
                           "%.1f CPU-s by other processes%s\n",
                     wall, own1 - own0, child, other,
                     other > 0.05 * wall ? " (over 5 % of a core: timings may be disturbed)"
                                         : "");
    }
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const Options o = parse_args(argc, argv);
        const Report rep{o.csv};
        FILE* info = rep.info();
        const auto wall0 = Clock::now();
        const double busy0 = machine_busy_s(), own0 = own_cpu_s();
        const std::string load0 = loadavg();
        output::quiet_video_logs();
        TempDir tmp;
        // Before anything else grows this process: see measure_memory.
        const Memory mem = measure_memory(o, tmp);

        const scenes::Scene scene = load_default();
        const auto& out = scene.output;
        std::fprintf(info, "impulse_bench_motion: scene %s (%s), %dx%d, %g fps, %zu layer%s\n",
                     kScene, scenes::resolve_scene(kScene).c_str(), out.width, out.height,
                     out.fps, scene.layers.size(), scene.layers.size() == 1 ? "" : "s");
        std::fprintf(info, "tbb threads %d (default arena), %u hardware threads, avx2 %s; "
                           "times in ms as median [min-max]%s\n",
                     tbb::this_task_arena::max_concurrency(),
                     static_cast<unsigned>(sysconf(_SC_NPROCESSORS_ONLN)),
                     __builtin_cpu_supports("avx2") ? "yes" : "no", o.quick ? "; --quick" : "");
        std::fprintf(info, "load average at start: %s\n", load0.c_str());
        if (o.csv) std::printf("metric,unit,median,min,max,runs\n");
        const FrameCosts fc = report_frames(o, rep, scene);
        const std::vector<Variant> variants = report_e2e(o, rep, scene, tmp);
        report_memory(o, rep, mem);
        report_targets(rep, fc, variants, mem);
        report_machine(info, wall0, busy0, own0);
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "impulse_bench_motion: %s\n", e.what());
        return 1;
    }
}
