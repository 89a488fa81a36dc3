// SPDX-License-Identifier: Apache-2.0
// `impulse export flipbook|flowmap|volume` (issue 38, docs/export.md): an atlas's cells are the
// frames `impulse render` writes, bit for bit; a loop's successor is its first frame; opposite
// tile edges meet within the steps inside a tile; a flow map holds the encoded velocity; a
// volume's slices, raw file and period agree; bad input is one line and nothing written.
//
// The seam measurements carry their own negative controls: the same scene without `loop`, or
// without `period`, must fail the measurement the exported atlas passes, so each test fails
// when the mechanism it guards (births periodic in time, cell keys that wrap) is off.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <numeric>

#include "output/io_module.h"
#include "output/output.h"
#include "tests/support.h"

namespace {

using namespace impulse;
using namespace impulse::test;
using Catch::Matchers::Contains;

Result run(const TempDir& dir, const std::string& args) { return shell(dir, quote(IMPULSE_BINARY) + " " + args); }

constexpr int kW = 96, kH = 64, kLoopFrames = 24;  // loop = 2 s at 12 fps

/// A small tileable looping scene: one period across the picture (zoom 1), births repeating
/// every 2 s, carried by a uniform wind (which keeps both, docs/scenes.md "[[layer]]", its `loop` key).
std::string loop_scene(bool period = true, bool loop = true) {
    return std::string("[output]\nsize = [96, 64]\nframes = 48\nfps = 12\n") +
           "[[layer]]\nseed = 3\ndensity = 16.0\nlifetime = 1.0\n" + (loop ? "loop = 2.0\n" : "") +
           (period ? "period = [96, 64]\n" : "") +
           "[layer.kernel]\ntype = \"cosine\"\nradius = 8.0\n"
           "[[layer.flow]]\ntype = \"uniform\"\nvelocity = [6.0, 2.0]\n";
}

output::Frame read_exr(const std::string& path) { return output::read_image(path); }

/// Cell `index` of an atlas of `columns` columns of kW x kH cells.
output::Frame cell(const output::Frame& atlas, int index, int columns) {
    output::Frame c;
    c.resize(kW, kH);
    const int x0 = index % columns * kW, y0 = index / columns * kH;
    for (int y = 0; y < kH; ++y)
        std::memcpy(&c.data[size_t(y) * kW], &atlas.data[size_t(y0 + y) * atlas.width + x0], kW * sizeof(float));
    return c;
}

double mean_abs_difference(const output::Frame& a, const output::Frame& b) {
    double s = 0;
    for (size_t i = 0; i < a.data.size(); ++i) s += std::abs(double(a.data[i]) - double(b.data[i]));
    return s / double(a.data.size());
}

/// How many standard deviations `x` lies above the mean of `samples`.
double z_above(double x, const std::vector<double>& samples) {
    const double n = double(samples.size());
    const double mean = std::accumulate(samples.begin(), samples.end(), 0.0) / n;
    double var = 0;
    for (const double s : samples) var += (s - mean) * (s - mean) / (n - 1);
    return (x - mean) / std::sqrt(var);
}

/// The mean |step| across each vertical line between columns c and c + 1 (c = 0 .. W - 2), and
/// across the tile's border, from column W - 1 to column 0 of the next copy (the last entry).
std::vector<double> column_steps(const output::Frame& f) {
    std::vector<double> steps;
    for (int c = 0; c < f.width; ++c) {
        const int next = (c + 1) % f.width;
        double s = 0;
        for (int y = 0; y < f.height; ++y) s += std::abs(double(f.at(next, y)) - double(f.at(c, y)));
        steps.push_back(s / f.height);
    }
    return steps;
}

/// The same along rows (the tile's top and bottom edges).
std::vector<double> row_steps(const output::Frame& f) {
    output::Frame t;
    t.resize(f.height, f.width);
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) t.data[size_t(x) * f.height + y] = f.at(x, y);
    return column_steps(t);
}

/// The border's step in standard deviations of the steps inside (the last entry is the border).
double border_z(std::vector<double> steps) {
    const double border = steps.back();
    steps.pop_back();
    return z_above(border, steps);
}

nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_file(path)); }

}  // namespace

TEST_CASE("flipbook cells are the frames render writes, bit for bit", "[cli][export]") {
    TempDir dir;
    write_file(dir / "loop.toml", loop_scene());
    const Result r = run(dir, "export flipbook " + quote(dir / "loop.toml") + " --loop --tileable -o " + quote(dir / "atlas.exr"));
    REQUIRE(r.status == 0);
    REQUIRE(run(dir, "render " + quote(dir / "loop.toml") + " -q --frames 0-23 -o " + quote(dir / "f_####.exr")).status == 0);
    const output::Frame atlas = read_exr(dir / "atlas.exr");
    const nlohmann::json j = read_json(dir / "atlas.json");
    CHECK(j["frames"] == kLoopFrames);
    CHECK(j["fps"] == 12);
    CHECK(j["layout"]["rows"] == 5);
    CHECK(j["layout"]["columns"] == 5);
    CHECK(j["cell"]["width"] == kW);
    CHECK(j["cell"]["height"] == kH);
    CHECK(j["loop"] == true);
    CHECK(j["loop_s"] == 2);
    CHECK(j["tileable"] == true);
    CHECK(j["period"] == nlohmann::json::array({96, 64}));
    CHECK(j["image"] == "atlas.exr");
    REQUIRE(atlas.width == 5 * kW);
    REQUIRE(atlas.height == 5 * kH);
    for (int f = 0; f < kLoopFrames; ++f) {
        INFO("frame " << f);
        char name[16];
        std::snprintf(name, sizeof name, "f_%04d.exr", f);
        CHECK(cell(atlas, f, 5).data == read_exr(dir / name).data);
    }
    CHECK(cell(atlas, 24, 5).data == std::vector<float>(size_t(kW) * kH, 0.0f));  // the unused cell
    // The same bytes on one thread (design.md §4: any thread count).
    REQUIRE(run(dir, "export flipbook " + quote(dir / "loop.toml") + " --loop --tileable --threads 1 -o " +
                         quote(dir / "one.exr")).status == 0);
    CHECK(read_file(dir / "one.exr") == read_file(dir / "atlas.exr"));
}

TEST_CASE("a looping flipbook's last frame is followed by its first", "[cli][export]") {
    TempDir dir;
    write_file(dir / "loop.toml", loop_scene());
    write_file(dir / "open.toml", loop_scene(true, false));  // control: the same births, not looped
    REQUIRE(run(dir, "export flipbook " + quote(dir / "loop.toml") + " --loop -o " + quote(dir / "atlas.exr")).status == 0);
    const output::Frame atlas = read_exr(dir / "atlas.exr");
    // The successor of the last cell is frame P = 24: rendered, it is cell 0 bit for bit.
    REQUIRE(run(dir, "render " + quote(dir / "loop.toml") + " -q --frames 24 -o " + quote(dir / "p.exr")).status == 0);
    CHECK(read_exr(dir / "p.exr").data == cell(atlas, 0, 5).data);
    // The step from the last cell to the first is one of the steps between consecutive cells.
    std::vector<double> steps;
    for (int f = 0; f + 1 < kLoopFrames; ++f) steps.push_back(mean_abs_difference(cell(atlas, f, 5), cell(atlas, f + 1, 5)));
    const double seam = mean_abs_difference(cell(atlas, kLoopFrames - 1, 5), cell(atlas, 0, 5));
    // One more draw from the steps' distribution: above mean + 5 sd with probability < 1/26 for
    // any distribution (Cantelli), ~3e-7 for a normal one; the seed is fixed.
    CHECK(z_above(seam, steps) < 5.0);
    // Control: without `loop` the frames 0-23 render, and the jump from 23 back to 0 is no step.
    REQUIRE(run(dir, "export flipbook " + quote(dir / "open.toml") + " --frames 0-23 -o " + quote(dir / "open.exr")).status == 0);
    const output::Frame open = read_exr(dir / "open.exr");
    std::vector<double> open_steps;
    for (int f = 0; f + 1 < kLoopFrames; ++f) open_steps.push_back(mean_abs_difference(cell(open, f, 5), cell(open, f + 1, 5)));
    const double open_seam = mean_abs_difference(cell(open, kLoopFrames - 1, 5), cell(open, 0, 5));
    INFO("looped seam z = " << z_above(seam, steps) << ", unlooped z = " << z_above(open_seam, open_steps));
    CHECK(z_above(open_seam, open_steps) > 5.0);
}

TEST_CASE("a tileable flipbook's opposite edges meet within the steps inside a tile", "[cli][export]") {
    TempDir dir;
    write_file(dir / "loop.toml", loop_scene());
    write_file(dir / "free.toml", loop_scene(false, true));  // control: no period
    REQUIRE(run(dir, "export flipbook " + quote(dir / "loop.toml") + " --loop --tileable --layout 4x6 -o " + quote(dir / "tiled.exr")).status == 0);
    REQUIRE(run(dir, "export flipbook " + quote(dir / "free.toml") + " --loop --layout 4x6 -o " + quote(dir / "free.exr")).status == 0);
    const output::Frame tiled = read_exr(dir / "tiled.exr"), free = read_exr(dir / "free.exr");
    REQUIRE(tiled.width == 6 * kW);
    double worst = -1e9, control = 1e9;
    for (int f = 0; f < kLoopFrames; f += 5) {
        // The border's mean step is one more draw from the distribution of the W - 1 (H - 1)
        // interior lines' (the field is stationary, and periodic with the tile): 5 sd as above.
        const output::Frame c = cell(tiled, f, 6), u = cell(free, f, 6);
        worst = std::max({worst, border_z(column_steps(c)), border_z(row_steps(c))});
        control = std::min({control, border_z(column_steps(u)), border_z(row_steps(u))});
    }
    INFO("periodic worst border z = " << worst << ", non-periodic least z = " << control);
    CHECK(worst < 5.0);
    CHECK(control > 5.0);
}

TEST_CASE("a flow map encodes the layer's velocity", "[cli][export]") {
    TempDir dir;
    write_file(dir / "loop.toml", loop_scene());
    REQUIRE(run(dir, "export flowmap " + quote(dir / "loop.toml") + " -o " + quote(dir / "flow.png")).status == 0);
    REQUIRE(run(dir, "export flowmap " + quote(dir / "loop.toml") + " --bits 16 --vmax 12 -o " + quote(dir / "flow16.png")).status == 0);
    REQUIRE(run(dir, "export flowmap " + quote(dir / "loop.toml") + " -o " + quote(dir / "flow.exr")).status == 0);
    const auto pixels = [&](const std::string& name) {
        output::Pixels p;
        std::string error;
        REQUIRE(output::read_pixels(dir / name, p, error));
        REQUIRE(p.width == kW);
        return p;
    };
    // Wind (6, 2): vmax = 6 by default, R = 0.5 + 0.5 * 6 / 6 = 1, G = 0.5 + 0.5 * 2 / 6 = 2/3.
    const output::Pixels png = pixels("flow.png"), png16 = pixels("flow16.png"), exr = pixels("flow.exr");
    CHECK(png.values[0] == 1.0f);
    CHECK(png.values[1] == Approx(170.0 / 255).margin(1e-6));  // round(255 * 2/3)
    CHECK(png16.values[0] == Approx(std::round(65535 * 0.75) / 65535).margin(1e-7));  // vmax 12
    CHECK(exr.values[0] == 6.0f);
    CHECK(exr.values[1] == 2.0f);
    CHECK(read_json(dir / "flow.json")["vmax"] == 6);
    CHECK(read_json(dir / "flow16.json")["bits"] == 16);
}

TEST_CASE("a volume's slices, raw file and sidecar agree, and it tiles", "[cli][export]") {
    TempDir dir;
    REQUIRE(run(dir, "export volume --size 32x32x16 --radius 8 --seed 4 -o " + quote(dir / "v.exr")).status == 0);
    REQUIRE(shell(dir, "taskset -c 0 " + quote(IMPULSE_BINARY) + " export volume --size 32x32x16 --radius 8 --seed 4 -o " +
                           quote(dir / "w.exr")).status == 0);
    CHECK(read_file(dir / "w.raw") == read_file(dir / "v.raw"));  // one core: the same bytes
    const nlohmann::json j = read_json(dir / "v.json");
    CHECK(j["size"] == nlohmann::json::array({32, 32, 16}));
    CHECK(j["radius_voxels"] == 8);
    const std::string raw = read_file(dir / "v.raw");
    REQUIRE(raw.size() == size_t(32) * 32 * 16 * 4);
    std::vector<float> v(raw.size() / 4);
    std::memcpy(v.data(), raw.data(), raw.size());
    const output::Frame atlas = read_exr(dir / "v.exr");
    REQUIRE(atlas.width == 4 * 32);  // 16 slices: 4 x 4
    for (int k = 0; k < 16; ++k)
        for (int y = 0; y < 32; ++y)
            for (int x = 0; x < 32; x += 7) REQUIRE(atlas.at(k % 4 * 32 + x, k / 4 * 32 + y) == v[(size_t(k) * 32 + y) * 32 + x]);
    // Along x (the slices' columns), every slice: the border step among the interior ones.
    double worst = -1e9;
    for (int k = 0; k < 16; k += 3) {
        output::Frame s;
        s.resize(32, 32);
        std::memcpy(s.data.data(), &v[size_t(k) * 32 * 32], 32 * 32 * sizeof(float));
        worst = std::max({worst, border_z(column_steps(s)), border_z(row_steps(s))});
    }
    CHECK(worst < 5.0);
}

TEST_CASE("export refuses bad input with one line and writes nothing", "[cli][export][errors]") {
    TempDir dir;
    write_file(dir / "loop.toml", loop_scene());
    write_file(dir / "free.toml", loop_scene(false, true));
    write_file(dir / "open.toml", loop_scene(true, false));
    const std::string loop = quote(dir / "loop.toml"), out = " -o " + quote(dir / "a.exr");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"export flipbook " + loop + " --loop --layout 4x5" + out, "--layout 4x5: 20 cells cannot hold 24 frames (at least 24 cells, e.g. 5x5)"},
        {"export flipbook " + quote(dir / "free.toml") + " --tileable" + out, "layer[0] has no period: add `period = [96, 64]`"},
        {"export flipbook " + quote(dir / "open.toml") + " --loop" + out, "layer[0] has no loop: add `loop = SECONDS`"},
        {"export flipbook " + loop + " --loop --frames 0-9" + out, "--frames 0-9 with --loop: a loop is 24 frames"},
        {"export flipbook " + loop + " --tileable --set camera.zoom=2" + out, "not a whole number of periods"},
        {"export flipbook " + loop + " -o " + quote(dir / "a.jpg"), "a.jpg: expected an image ending in .exr or .png"},
        {"export flipbook " + loop + " --loop --set limits.max_memory_mib=0.5" + out, "an atlas of 480x320 pixels (1 float channels) needs 1 MiB, over limits.max_memory_mib = 0.5"},
        {"export flowmap " + loop + " --layer 3" + out, "--layer 3: expected"},
        {"export flowmap " + loop + " --bits 12 -o " + quote(dir / "f.png"), "--bits 12: expected 8 or 16"},
        {"export volume --size 1x8x8" + out, "--size 1x8x8: expected N or WxHxD voxels"},
        {"export volume --size 16 --kernel gabor" + out, "--kernel gabor: expected one of cosine, gaussian"},
    };
    for (const auto& [args, message] : cases) {
        INFO(args);
        const Result r = run(dir, args);
        CHECK(r.status == 1);
        REQUIRE(r.err_lines().size() == 1);
        CHECK_THAT(r.err_lines()[0], Contains(message));
    }
    CHECK(dir.files() == std::vector<std::string>{"free.toml", "loop.toml", "open.toml"});
}
