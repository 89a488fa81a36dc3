// SPDX-License-Identifier: Apache-2.0
// `impulse analyze`: the same numbers as the analysis estimators called directly, agreement with
// the closed-form theory on rendered scenes (and disagreement with a wrong scene), JSON and HTML
// output, and one-line errors for bad input. Frames are rendered here with a fixed seed, so every
// statistical verdict is deterministic; the thresholds are the tool's own (|z| < 4, Bonferroni
// over annuli at family alpha 0.01), not tuned here.

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "analysis/analysis.h"
#include "app/analyze.h"
#include "app/commands.h"
#include "output/output.h"
#include "render/render.h"
#include "scenes/scenes.h"
#include "tests/support.h"
#include "numeric/errors.h"

namespace {

namespace fs = std::filesystem;
using namespace impulse::test;
using Catch::Matchers::Contains;
using impulse::analysis::Image;
using impulse::app::AnalysisResult;
using impulse::app::AnalyzeOptions;

/// Renders frames first..last of a scene (text plus overrides) into `pattern` (or one file).
void render_scene(const std::string& text, const std::vector<std::string>& sets,
                  const std::string& pattern, int first, int last) {
    impulse::scenes::Renderer r(impulse::scenes::load_scene_string(text, "test.toml", sets));
    const auto mapping = r.mapping();
    impulse::render::Frame f;
    for (int i = first; i <= last; ++i) {
        r.render(i, f);
        const std::string name = impulse::app::expand_pattern(pattern, i);
        impulse::output::write_image(name.empty() ? pattern : name, f, mapping, {});
    }
}

Image read_image(const std::string& path) {
    impulse::render::Frame f = impulse::output::read_image(path);
    Image im;
    im.width = f.width;
    im.height = f.height;
    im.data = std::move(f.data);
    return im;
}

// The built-in still scene's layer (cosine kernel, radius 16, 16 impulses per kernel area) on a
// 256 x 256 torus: the frame is one period, so no window is needed.
const char* kStill = R"(# still test scene
[output]
size = [256, 256]
[[layer]]
seed = 7
density = 16.0
period = [256, 256]
[layer.kernel]
type = "cosine"
radius = 16.0
)";

// Animated, periodic, no flow: 0.5 s Hann lifetimes at 30 fps.
const char* kAnimated = R"(# animated test scene
[output]
size = [96, 96]
frames = 60
fps = 30
[[layer]]
seed = 11
density = 16.0
lifetime = 0.5
period = [96, 96]
[layer.kernel]
type = "cosine"
radius = 6.0
)";

/// A scene file on disk for --scene.
std::string write_scene(const TempDir& dir, const std::string& name, const std::string& text) {
    const std::string path = dir / name;
    std::ofstream(path) << text;
    return path;
}

// ---------------------------------------------------------------------------------------------
// A minimal JSON checker: accepts exactly the JSON grammar (RFC 8259) and records the keys.

class JsonChecker {
public:
    explicit JsonChecker(const std::string& text) : m_s(text) {}
    bool valid() {
        skip();
        if (!value()) return false;
        skip();
        return m_i == m_s.size();
    }
    bool has_key(const std::string& k) const {
        for (const auto& key : m_keys)
            if (key == k) return true;
        return false;
    }

private:
    void skip() {
        while (m_i < m_s.size() && std::isspace(static_cast<unsigned char>(m_s[m_i]))) ++m_i;
    }
    bool literal(const char* word) {
        const std::string w(word);
        if (m_s.compare(m_i, w.size(), w) != 0) return false;
        m_i += w.size();
        return true;
    }
    bool string(std::string* out) {
        if (m_i >= m_s.size() || m_s[m_i] != '"') return false;
        ++m_i;
        std::string v;
        while (m_i < m_s.size() && m_s[m_i] != '"') {
            if (static_cast<unsigned char>(m_s[m_i]) < 0x20) return false;
            if (m_s[m_i] == '\\') {
                ++m_i;
                if (m_i >= m_s.size()) return false;
                if (m_s[m_i] == 'u') {
                    for (int k = 0; k < 4; ++k)
                        if (++m_i >= m_s.size() ||
                            !std::isxdigit(static_cast<unsigned char>(m_s[m_i])))
                            return false;
                } else if (std::string("\"\\/bfnrt").find(m_s[m_i]) == std::string::npos) {
                    return false;
                }
            }
            v += m_s[m_i++];
        }
        if (m_i >= m_s.size()) return false;
        ++m_i;
        if (out) *out = v;
        return true;
    }
    bool number() {
        const size_t start = m_i;
        if (m_i < m_s.size() && m_s[m_i] == '-') ++m_i;
        if (m_i >= m_s.size() || !std::isdigit(static_cast<unsigned char>(m_s[m_i]))) return false;
        if (m_s[m_i] == '0')
            ++m_i;
        else
            while (m_i < m_s.size() && std::isdigit(static_cast<unsigned char>(m_s[m_i]))) ++m_i;
        if (m_i < m_s.size() && m_s[m_i] == '.') {
            ++m_i;
            if (m_i >= m_s.size() || !std::isdigit(static_cast<unsigned char>(m_s[m_i])))
                return false;
            while (m_i < m_s.size() && std::isdigit(static_cast<unsigned char>(m_s[m_i]))) ++m_i;
        }
        if (m_i < m_s.size() && (m_s[m_i] == 'e' || m_s[m_i] == 'E')) {
            ++m_i;
            if (m_i < m_s.size() && (m_s[m_i] == '+' || m_s[m_i] == '-')) ++m_i;
            if (m_i >= m_s.size() || !std::isdigit(static_cast<unsigned char>(m_s[m_i])))
                return false;
            while (m_i < m_s.size() && std::isdigit(static_cast<unsigned char>(m_s[m_i]))) ++m_i;
        }
        return m_i > start;
    }
    bool value() {
        skip();
        if (m_i >= m_s.size()) return false;
        const char c = m_s[m_i];
        if (c == '{') {
            ++m_i;
            skip();
            if (m_i < m_s.size() && m_s[m_i] == '}') return ++m_i, true;
            for (;;) {
                skip();
                std::string k;
                if (!string(&k)) return false;
                m_keys.push_back(k);
                skip();
                if (m_i >= m_s.size() || m_s[m_i++] != ':') return false;
                if (!value()) return false;
                skip();
                if (m_i >= m_s.size()) return false;
                if (m_s[m_i] == ',') {
                    ++m_i;
                    continue;
                }
                return m_s[m_i++] == '}';
            }
        }
        if (c == '[') {
            ++m_i;
            skip();
            if (m_i < m_s.size() && m_s[m_i] == ']') return ++m_i, true;
            for (;;) {
                if (!value()) return false;
                skip();
                if (m_i >= m_s.size()) return false;
                if (m_s[m_i] == ',') {
                    ++m_i;
                    continue;
                }
                return m_s[m_i++] == ']';
            }
        }
        if (c == '"') return string(nullptr);
        if (c == 't') return literal("true");
        if (c == 'f') return literal("false");
        if (c == 'n') return literal("null");
        return number();
    }

    std::string m_s;  // a copy: the checker may be built from a temporary
    size_t m_i = 0;
    std::vector<std::string> m_keys;
};

size_t count(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
    return n;
}

}  // namespace

TEST_CASE("analyze reports the analysis estimators' own numbers", "[app][analyze]") {
    TempDir dir;
    const std::string pattern = dir / "f_####.exr";
    render_scene(kAnimated, {"output.frames=20"}, pattern, 0, 19);

    AnalyzeOptions opt;
    opt.input = pattern;
    const AnalysisResult r = impulse::app::analyze_input(opt);

    std::vector<Image> frames;
    for (int i = 0; i < 20; ++i)
        frames.push_back(read_image(impulse::app::expand_pattern(pattern, i)));
    REQUIRE(r.kind == "sequence");
    REQUIRE(r.raw);
    REQUIRE(r.frames == 20);
    REQUIRE(r.width == 96);
    REQUIRE(r.height == 96);
    // A torus frame: periodic, so the periodogram is taken without a window.
    REQUIRE(r.periodogram.periodic);
    REQUIRE(r.periodogram.window == "none");

    std::vector<float> all;
    for (const auto& f : frames) all.insert(all.end(), f.data.begin(), f.data.end());
    const auto m = impulse::analysis::moments(all);
    CHECK(r.moments.mean == m.mean);
    CHECK(r.moments.variance == m.variance);
    CHECK(r.moments.skewness == m.skewness);
    CHECK(r.moments.excess_kurtosis == m.excess_kurtosis);
    CHECK(r.moments.min == m.min);
    CHECK(r.moments.max == m.max);

    const double sd = std::sqrt(m.variance);
    const auto h = impulse::analysis::histogram(all, m.mean - 4 * sd, m.mean + 4 * sd, 64);
    CHECK(r.histogram.counts == h.counts);
    CHECK(r.histogram.below == h.below);
    CHECK(r.histogram.above == h.above);

    std::vector<impulse::analysis::Periodogram> ps;
    for (const auto& f : frames)
        ps.push_back(impulse::analysis::periodogram(f, impulse::analysis::Window::None));
    const auto radial = impulse::analysis::radial_average(impulse::analysis::average(ps));
    CHECK(r.spectrum.power == radial.power);
    CHECK(r.spectrum.frequency == radial.frequency);
    CHECK(r.spectrum.count == radial.count);

    REQUIRE(r.max_lag == 96 / 4);
    std::vector<double> acov(size_t(r.max_lag) + 1, 0.0);
    for (const auto& f : frames) {
        const auto a = impulse::analysis::radial_autocovariance(
            impulse::analysis::autocovariance(f), f.width, f.height, r.max_lag);
        for (size_t i = 0; i < a.size(); ++i) acov[i] += a[i];
    }
    for (double& v : acov) v *= 1.0 / 20.0;
    CHECK(r.autocovariance == acov);

    const auto fs_direct = impulse::analysis::frame_stats(frames);
    REQUIRE(r.frame_stats.size() == fs_direct.size());
    std::vector<double> variances;
    for (size_t i = 0; i < fs_direct.size(); ++i) {
        CHECK(r.frame_stats[i].mean == fs_direct[i].mean);
        CHECK(r.frame_stats[i].variance == fs_direct[i].variance);
        CHECK(r.frame_stats[i].diff_variance == fs_direct[i].diff_variance);
        variances.push_back(fs_direct[i].variance);
    }
    REQUIRE(r.stationarity.available);
    const auto t = impulse::analysis::trend(variances, 10);
    CHECK(r.stationarity.trend.slope == t.slope);
    CHECK(r.stationarity.trend.stderr_slope == t.stderr_slope);
    CHECK(r.stationarity.trend.t == t.t);
    const std::span<const Image> span(frames);
    const auto drift = impulse::analysis::spectral_drift(span.first(5), span.last(5));
    CHECK(r.stationarity.quarter == 5);
    CHECK(r.stationarity.drift.z == drift.z);
    CHECK(r.stationarity.drift.max_abs_z == drift.max_abs_z);
}

TEST_CASE("analyze windows a frame that is not periodic", "[app][analyze]") {
    TempDir dir;
    const std::string path = dir / "still.exr";
    // A 128 x 96 view of the plane without a periodic domain: edges do not wrap.
    std::string plane = kStill;
    plane.erase(plane.find("period = [256, 256]\n"), std::string("period = [256, 256]\n").size());
    render_scene(plane, {"output.size=[128,96]"}, path, 0, 0);
    AnalyzeOptions opt;
    opt.input = path;
    const AnalysisResult r = impulse::app::analyze_input(opt);
    REQUIRE_FALSE(r.periodogram.periodic);
    REQUIRE(r.periodogram.window == "hann");
    const Image f = read_image(path);
    const auto p = impulse::analysis::periodogram(f, impulse::analysis::Window::Hann);
    CHECK(r.spectrum.power == impulse::analysis::radial_average(p).power);
    CHECK(r.frames == 1);
    CHECK_FALSE(r.stationarity.available);
}

TEST_CASE("analyze --scene agrees with the theory of a rendered still scene",
          "[app][analyze][stats]") {
    TempDir dir;
    const std::string image = dir / "still.exr";
    render_scene(kStill, {}, image, 0, 0);
    const std::string scene = write_scene(dir, "still.toml", kStill);

    AnalyzeOptions opt;
    opt.input = image;
    opt.scene = scene;
    const AnalysisResult r = impulse::app::analyze_input(opt);
    REQUIRE(r.theory);
    const auto& T = *r.theory;
    INFO("mean z " << T.z_mean << ", variance z " << T.z_variance);
    CHECK(T.mean_agrees);
    CHECK(T.variance_agrees);
    REQUIRE(T.spectrum);
    INFO("spectrum max|z| " << T.spectrum->max_abs_z << " (limit " << T.spectrum->threshold << ")");
    CHECK(T.spectrum->compared == 127);
    CHECK(T.spectrum->agrees);
    // The autocovariance theory follows the measurement at lag 0 (the variance) and vanishes
    // beyond twice the kernel radius.
    REQUIRE(T.autocovariance.size() == r.autocovariance.size());
    CHECK(T.autocovariance[40] == Approx(-T.sd_frame_mean * T.sd_frame_mean));

    SECTION("a wrong scene (radius 12 instead of 16) does not agree") {
        // Same density, so the variance (lambda int h^2 at fixed impulses per kernel area) is the
        // same: only the spectrum can tell, and it must.
        opt.sets = {"layer.0.kernel.radius=12"};
        const AnalysisResult wrong = impulse::app::analyze_input(opt);
        REQUIRE(wrong.theory);
        REQUIRE(wrong.theory->spectrum);
        INFO("spectrum max|z| " << wrong.theory->spectrum->max_abs_z);
        CHECK_FALSE(wrong.theory->spectrum->agrees);
        CHECK(wrong.theory->spectrum->max_abs_z > 10 * wrong.theory->spectrum->threshold);
    }
    SECTION("a wrong density does not agree in variance") {
        opt.sets = {"layer.0.density=8"};
        const AnalysisResult wrong = impulse::app::analyze_input(opt);
        REQUIRE(wrong.theory);
        CHECK_FALSE(wrong.theory->variance_agrees);
    }
}

TEST_CASE("analyze maps 8-bit display values back through the scene's range",
          "[app][analyze][stats]") {
    TempDir dir;
    // A range wide enough (about +-5.4 sd) that nothing clips: then the 8-bit rounding, white
    // noise of variance step^2 / 12, is all that separates the file from the field.
    const std::string text = kStill;
    const std::vector<std::string> sets = {"output.range=[-9,9]"};
    const std::string image = dir / "still.png";
    render_scene(text, sets, image, 0, 0);
    AnalyzeOptions opt;
    opt.input = image;
    opt.scene = write_scene(dir, "still.toml", text);
    opt.sets = sets;
    const AnalysisResult r = impulse::app::analyze_input(opt);
    REQUIRE_FALSE(r.raw);
    CHECK(r.bits == 8);
    REQUIRE(r.theory);
    CHECK(r.theory->mapped);
    CHECK(r.theory->map_lo == -9.0);
    CHECK(r.theory->map_hi == 9.0);
    CHECK(r.theory->mean_agrees);
    CHECK(r.theory->variance_agrees);
    REQUIRE(r.theory->spectrum);
    CHECK(r.theory->spectrum->not_judged.empty());
    CHECK(r.theory->spectrum->agrees);

    SECTION("the default range clips, and the spectrum is then not judged") {
        const std::string clipped = dir / "clipped.png";
        render_scene(text, {}, clipped, 0, 0);
        opt.input = clipped;
        opt.sets = {};
        const AnalysisResult c = impulse::app::analyze_input(opt);
        REQUIRE(c.theory);
        CHECK(c.theory->clipped_fraction > 1e-3);
        CHECK(c.theory->mean_agrees);      // censored-Gaussian theory of the mean
        CHECK(c.theory->variance_agrees);  // and of the variance
        REQUIRE(c.theory->spectrum);
        CHECK_THAT(c.theory->spectrum->not_judged, Contains("clipped"));
        CHECK_THAT(impulse::app::to_text(c), Contains("spectrum agrees with theory: n/a"));
    }
}

TEST_CASE("analyze --scene on an animated sequence: theory and stationarity",
          "[app][analyze][stats]") {
    TempDir dir;
    const std::string pattern = dir / "a_%03d.exr";
    render_scene(kAnimated, {}, pattern, 0, 59);
    AnalyzeOptions opt;
    opt.input = pattern;
    opt.scene = write_scene(dir, "anim.toml", kAnimated);
    const AnalysisResult r = impulse::app::analyze_input(opt);
    REQUIRE(r.frames == 60);
    REQUIRE(r.tau_source == "scene");
    REQUIRE(r.theory);
    CHECK(r.theory->mean_agrees);
    CHECK(r.theory->variance_agrees);
    REQUIRE(r.theory->spectrum);
    CHECK(r.theory->spectrum->agrees);
    // Frame-difference variance without flow: 2 sigma^2 (1 - rho(1/fps)) from the Hann envelope.
    REQUIRE(r.theory->diff_variance);
    double dv = 0;
    for (size_t j = 1; j < r.frame_stats.size(); ++j) dv += r.frame_stats[j].diff_variance;
    dv /= double(r.frame_stats.size() - 1);
    CHECK(dv == Approx(*r.theory->diff_variance).epsilon(0.1));
    REQUIRE(r.stationarity.available);
    INFO("t " << r.stationarity.trend.t << ", drift " << r.stationarity.max_abs_z_corrected);
    CHECK(r.stationarity.stationary);
    CHECK_THAT(impulse::app::to_text(r), Contains("stationary: yes"));

    SECTION("--frames and --max-frames select frames") {
        opt.frames = "10-40";
        opt.max_frames = 12;
        const AnalysisResult s = impulse::app::analyze_input(opt);
        CHECK(s.first_frame == 10);
        CHECK(s.frames == 12);
        CHECK(s.frame_stats[0].mean == r.frame_stats[10].mean);
    }
    SECTION("a camera zoom that grows over the sequence is not stationary") {
        const std::string zoomed = dir / "z_%03d.exr";
        const std::vector<std::string> zoom = {"camera.zoom={keys=[[0.0,1.0],[2.0,1.6]]}"};
        render_scene(kAnimated, zoom, zoomed, 0, 59);
        AnalyzeOptions z;
        z.input = zoomed;
        const AnalysisResult nz = impulse::app::analyze_input(z);
        REQUIRE(nz.stationarity.available);
        INFO("t " << nz.stationarity.trend.t << ", drift " << nz.stationarity.max_abs_z_corrected);
        CHECK_FALSE(nz.stationarity.stationary);
        CHECK_THAT(impulse::app::to_text(nz), Contains("stationary: no"));
    }
}

TEST_CASE("analyze output: JSON parses, HTML has one Vega spec per plot", "[app][analyze]") {
    TempDir dir;
    const std::string pattern = dir / "f_####.exr";
    render_scene(kAnimated, {"output.frames=12"}, pattern, 0, 11);
    AnalyzeOptions opt;
    opt.input = pattern;
    opt.scene = write_scene(dir, "anim.toml", kAnimated);
    const AnalysisResult r = impulse::app::analyze_input(opt);

    const std::string json = impulse::app::to_json(r);
    JsonChecker checker(json);
    REQUIRE(checker.valid());
    for (const char* key : {"input",
                            "width",
                            "height",
                            "frames",
                            "moments",
                            "mean",
                            "variance",
                            "skewness",
                            "excess_kurtosis",
                            "min",
                            "max",
                            "histogram",
                            "counts",
                            "periodogram",
                            "radial_spectrum",
                            "frequency",
                            "power",
                            "count",
                            "theory",
                            "ratio",
                            "z",
                            "autocovariance",
                            "per_frame",
                            "diff_variance",
                            "stationarity",
                            "trend",
                            "slope",
                            "stderr",
                            "t",
                            "spectral_drift",
                            "max_abs_z",
                            "threshold",
                            "stationary",
                            "agrees"})
        CHECK(checker.has_key(key));
    CHECK(count(json, "{") == count(json, "}"));
    CHECK(count(json, "[") == count(json, "]"));

    // The page with a stand-in for the chart library (the browser test, tests/web/
    // test_analyze_report.py, draws it with Debian's): one figure and one Vega spec per plot,
    // each spec valid JSON, zoomable, with tooltips; log axes on the radial spectrum only.
    const std::string library = "/* the chart library */";
    const std::string html = impulse::app::to_html(r, library);
    const int plots = impulse::app::html_plot_count(r);
    CHECK(plots == 9);  // histogram, 2-D periodogram, spectrum, spectrum z, autocovariance,
                        // mean, variance, difference variance, drift
    CHECK(int(count(html, "<figure class=\"plot\">")) == plots);
    CHECK_THAT(html, Contains("<meta name=\"impulse-plots\" content=\"9\">"));
    CHECK(count(html, library) == 1);  // inlined once
    const std::string open = "<script type=\"application/json\" class=\"impulse-spec\">\n";
    std::vector<std::string> specs;
    for (size_t at = html.find(open); at != std::string::npos; at = html.find(open, at + 1)) {
        const size_t from = at + open.size();
        specs.push_back(html.substr(from, html.find("\n</script>", from) - from));
    }
    REQUIRE(int(specs.size()) == plots);
    int log_plots = 0;
    for (const auto& spec : specs) {
        CAPTURE(spec.substr(0, 200));
        JsonChecker parsed(spec);
        CHECK(parsed.valid());
        CHECK_THAT(spec, Contains("\"description\":") && Contains("\"title\":") &&
                             Contains("\"name\":\"zoom\"") &&
                             Contains("\"tooltip\":"));
        CHECK(spec.find("</") == std::string::npos);  // cannot end its <script> early
        const bool logx = count(spec, "{\"name\":\"x\",\"type\":\"log\"") == 1,
                   logy = count(spec, "{\"name\":\"y\",\"type\":\"log\"") == 1;
        CHECK(logx == logy);
        if (logx) {
            ++log_plots;
            CHECK_THAT(spec, Contains("Radially averaged power spectrum") && Contains("zoomLog") &&
                                 Contains("panLog"));
        }
    }
    CHECK(log_plots == 1);
    // Nothing from the network: no address outside the (stand-in) library.
    CHECK(count(html, "http://") == 0);
    CHECK(count(html, "https://") == 0);

    // A single image without a scene: histogram, 2-D periodogram, spectrum, autocovariance.
    AnalyzeOptions one;
    one.input = impulse::app::expand_pattern(pattern, 0);
    const AnalysisResult single = impulse::app::analyze_input(one);
    CHECK(impulse::app::html_plot_count(single) == 4);
    CHECK(int(count(impulse::app::to_html(single, library), "<figure class=\"plot\">")) == 4);
    JsonChecker single_json(impulse::app::to_json(single));
    CHECK(single_json.valid());
}

TEST_CASE("analyze refuses bad input with one line naming it", "[app][analyze]") {
    TempDir dir;
    AnalyzeOptions opt;
    const auto message = [&]() -> std::string {
        try {
            impulse::app::analyze_input(opt);
        } catch (const impulse::Error& e) {
            return e.what();
        }
        return "(no error)";
    };

    opt.input = dir / "missing.exr";
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::IoError);
    CHECK_THAT(message(), Contains("missing.exr") && Contains("no such file"));

    opt.input = dir / "missing_####.exr";
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::IoError);
    CHECK_THAT(message(), Contains("missing_0000.exr"));

    opt.input = dir / "missing.mp4";
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::IoError);

    opt.input = dir / "notes.xyz";
    std::ofstream(opt.input) << "not an image\n";
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::ValueError);
    CHECK_THAT(message(), Contains("notes.xyz") && Contains("unknown input type"));
    CHECK(message().find('\n') == std::string::npos);

    opt.input = dir / "broken.exr";
    std::ofstream(opt.input) << "this is not an OpenEXR file\nsecond line\n";
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::IoError);
    CHECK_THAT(message(), Contains("broken.exr"));
    CHECK(message().find('\n') == std::string::npos);

    const std::string image = dir / "tiny.exr";
    impulse::render::Frame f;
    f.resize(4, 4);
    impulse::output::write_image(image, f, {}, {});
    opt.input = image;
    CHECK_THROWS_AS(impulse::app::analyze_input(opt), impulse::ValueError);
    CHECK_THAT(message(), Contains("at least 8x8"));

    render_scene(kStill, {"output.size=[32,32]"}, dir / "small.exr", 0, 0);
    opt.input = dir / "small.exr";
    opt.frames = "3";
    CHECK_THAT(message(), Contains("--frames 3") && Contains("one image"));
    opt.frames = "";
    opt.sets = {"layer.0.density=4"};
    CHECK_THAT(message(), Contains("--set") && Contains("needs --scene"));
    opt.sets = {};
    opt.scene = dir / "nope.toml";
    CHECK_THROWS(impulse::app::analyze_input(opt));
}

TEST_CASE("impulse analyze on the command line", "[app][analyze][cli]") {
    TempDir dir;
    const std::string image = dir / "s.exr";
    render_scene(kStill, {"output.size=[64,64]", "layer.0.period=[64,64]"}, image, 0, 0);
    const std::string out = dir / "out.txt", err = dir / "err.txt", report = dir / "r.html";
    const auto run = [&](const std::string& args, const std::string& env = "") {
        const std::string cmd = env + "'" + IMPULSE_BINARY + "' analyze " + args + " > '" +
                                out + "' 2> '" + err + "' < /dev/null";
        const int raw = std::system(cmd.c_str());
        return WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
    };
    CHECK(run("'" + image + "' --json --report '" + report + "'") == 0);
    JsonChecker json(read_file(out));
    CHECK(json.valid());
    CHECK(fs::exists(report));
    CHECK(count(read_file(report), "<figure class=\"plot\">") == 4);
    CHECK(count(read_file(report), "impulseModule = 'vega-view';") == 1);  // Debian's, inlined
    // Only the report is left in the directory (no temporary file).
    int files = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(fs::path(report).parent_path()))
        ++files;
    CHECK(files == 4);  // s.exr, out.txt, err.txt, r.html

    CHECK(run("'" + image + "'") == 0);
    CHECK_THAT(read_file(out), Contains("variance") && Contains("radial spectrum"));

    CHECK(run("'" + (dir / "missing.exr") + "'") == 1);
    const std::string e = read_file(err);
    CHECK_THAT(e, Contains("missing.exr"));
    CHECK(count(e, "\n") == 1);

    CHECK(run("'" + image + "' --report '" + (dir / "no/such/dir/r.html") + "'") == 1);
    CHECK_THAT(read_file(err), Contains("does not exist"));

    // Without the chart library: one line naming the file and the package, nothing written,
    // before the analysis.
    fs::create_directories(dir / "vega");
    const std::string missing = dir / "missing.html";
    CHECK(run("'" + image + "' --report '" + missing + "'", "IMPULSE_VEGA_DIR='" +
              (dir / "no-vega") + "' ") == 1);
    CHECK_THAT(read_file(err), Contains("no-vega/vega-util.min.js: cannot be read") &&
                                   Contains("libjs-vega"));
    CHECK(count(read_file(err), "\n") == 1);
    CHECK(!fs::exists(missing));
    std::ofstream(dir / "vega/vega-util.min.js").flush();  // an empty module
    CHECK(run("'" + image + "' --report '" + missing + "'", "IMPULSE_VEGA_DIR='" +
              (dir / "vega") + "' ") == 1);
    CHECK_THAT(read_file(err), Contains("vega/vega-util.min.js: empty") && Contains("libjs-vega"));
    CHECK(!fs::exists(missing));

    // A corrupt video: one line, ours (libav's own "moov atom not found" line came first).
    std::ofstream(dir / "broken.mp4") << "this is not an MP4 file, no moov atom here\n";
    CHECK(run("'" + (dir / "broken.mp4") + "'") == 1);
    const std::string v = read_file(err);
    CHECK_THAT(v, Catch::StartsWith("error: ") && Contains("broken.mp4"));
    CHECK(count(v, "\n") == 1);
}
