// SPDX-License-Identifier: Apache-2.0
// `impulse analyze` output: the text report, JSON, and a self-contained HTML page whose plots
// are Vega specs (data inline) drawn by the chart library the page inlines (chart_library.cpp;
// design.md §6, "The report's plots drawn by Vega"); nothing is fetched. JSON through nlohmann-json.

#include "analysis/report.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <type_traits>

namespace impulse::analysis {
namespace {

std::string fmt(double v, int digits = 6) {
    if (std::isnan(v)) return "n/a";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

std::string fixed(double v, int decimals) {
    if (!std::isfinite(v)) return fmt(v);
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

std::string yes_no(bool b) { return b ? "yes" : "no"; }

std::string source_text(const AnalysisResult& r) {
    std::string s = r.kind == "image"      ? "one image"
                    : r.kind == "sequence" ? "image sequence"
                                           : "video";
    s += r.raw ? ", float (raw field values)"
               : ", " + std::to_string(r.bits) + "-bit (display values)";
    return s;
}

std::string frames_text(const AnalysisResult& r) {
    std::string s = std::to_string(r.frames) + (r.frames == 1 ? " frame" : " frames");
    if (r.frames > 1 || r.first_frame != 0)
        s += " (" + std::to_string(r.first_frame) + "-" +
             std::to_string(r.first_frame + r.frames - 1) + ")";
    return s;
}

std::string correlation_text(const AnalysisResult& r) {
    return "(mean " + fmt(r.tau_mean, 3) + ", variance " + fmt(r.tau_variance, 3) + ", spectrum " +
           fmt(r.tau_spectrum, 3) + "; " +
           (r.tau_source == "scene"    ? "from the scene's temporal envelopes)"
            : r.tau_source == "frames" ? "estimated from the frames)"
                                       : "all frames counted as one)");
}

/// "name = value < limit" or ">= limit": a verdict's number against its threshold.
std::string against(const std::string& name, double value, double limit, int decimals) {
    return name + " = " + fixed(value, 2) + (value < limit ? " < " : " >= ") +
           fixed(limit, decimals);
}

std::string z_text(double z, double limit) { return against("|z|", std::abs(z), limit, 0); }

std::string spectrum_threshold_text(const SpectrumTheory& s) {
    return against("max|z|", s.max_abs_z, s.threshold, 2) + ", Bonferroni limit for " +
           std::to_string(s.compared) + " annuli at family alpha 0.01";
}

/// "yes", "no" or "inconclusive" for a verdict.
std::string verdict_word(const Stationarity& st) {
    return st.verdict == "stationary" ? "yes" : st.verdict == "not stationary" ? "no" : "inconclusive";
}

std::string stationarity_verdict(const Stationarity& st) {
    const auto& L = st.level;
    const std::string not_applied =
        st.level_note.empty() ? "" : " (not applied: block means worth " +
                                         fmt(st.block_dof, 3) + " < " + fmt(st.min_block_dof, 3) +
                                         " degrees of freedom)";
    return "level of the frame variance: trend " +
           against("|z|", std::abs(L.z_trend), st.level_z_limit, 2) + ", " +
           std::to_string(L.blocks) + " blocks " + against("z", L.z_blocks, st.blocks_z_limit, 2) +
           not_applied + "; spectral drift " + against("max|z|", st.max_abs_z_corrected, st.z_threshold, 2) +
           " for " + std::to_string(st.drift.z.size()) +
           " annuli; each test at alpha " + fmt(st.family_alpha / 3.0, 2) + ", family " +
           fmt(st.family_alpha, 2) + "; a drift of the variance by " +
           fixed(100.0 * st.detectable_drift, 0) + " % over the frames is seen with power " +
           fixed(st.power, 1) + " (" + (st.detectable_drift <= st.drift_of_interest ? "<=" : ">") +
           " the " + fixed(100.0 * st.drift_of_interest, 0) + " % asked for)";
}

using Json = nlohmann::ordered_json;

// ---------------------------------------------------------------------------------------------
// Plots: data and Vega specs (design.md §6, "The report's plots drawn by Vega"); the page's
// script draws them with the Vega modules of Debian's libjs-vega (analysis/chart_library.cpp).

std::string esc(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '&')
            o += "&amp;";
        else if (c == '<')
            o += "&lt;";
        else if (c == '>')
            o += "&gt;";
        else if (c == '"')
            o += "&quot;";
        else
            o += c;
    }
    return o;
}

struct Series {
    std::string label;
    std::vector<double> x, y;
    std::string color = "#1f77b4";
    enum Kind { Line, Points, Bars } kind = Line;
    bool dashed = false;
};
struct Band {
    std::string label;
    std::vector<double> x, lo, hi;
    std::string color = "#d62728";
};
struct HLine {
    double y = 0;
    std::string label;
    std::string color = "#777";
};
struct Plot {
    std::string title, xlabel, ylabel;
    bool logx = false, logy = false;
    bool whole_x = false;  ///< x counts (frames, lags): ticks on whole numbers only
    std::vector<Series> series;
    std::vector<Band> bands;
    std::vector<HLine> hlines;
};

constexpr double kW = 560, kH = 240;  // the plotting area, CSS pixels

/// Whether (x, y) can be drawn: finite, and positive on a log axis.
bool drawable(const Plot& p, double x, double y) {
    return std::isfinite(x) && std::isfinite(y) && !(p.logx && x <= 0) && !(p.logy && y <= 0);
}

/// The axes' first view, [x0, x1, y0, y1] in data units: the range of everything drawn,
/// padded, at most 12 decades on a log y axis (a spectrum's zeros far below).
std::array<double, 4> initial_domain(const Plot& p) {
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    const auto take = [&](double x, double y) {
        if (!drawable(p, x, y)) return;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    };
    for (const auto& s : p.series)
        for (size_t i = 0; i < s.x.size(); ++i) take(s.x[i], s.y[i]);
    for (const auto& b : p.bands)
        for (size_t i = 0; i < b.x.size(); ++i) take(b.x[i], b.lo[i]), take(b.x[i], b.hi[i]);
    for (const auto& h : p.hlines)
        if (std::isfinite(x0)) take(x0, h.y);
    if (!std::isfinite(x0)) x0 = 1, x1 = 10, y0 = 1, y1 = 10;
    // Padding and the empty range in axis units (log10 on a log axis).
    const auto lift = [](double v, bool log) { return log ? std::log10(v) : v; };
    const auto ground = [](double v, bool log) { return log ? std::pow(10.0, v) : v; };
    double a0 = lift(x0, p.logx), a1 = lift(x1, p.logx), b0 = lift(y0, p.logy), b1 = lift(y1, p.logy);
    if (p.logy) b0 = std::max(b0, b1 - 12.0);
    if (a1 <= a0) a0 -= 0.5, a1 += 0.5;
    if (b1 <= b0) b0 -= 0.5 * std::max(1.0, std::abs(b0)), b1 += 0.5 * std::max(1.0, std::abs(b1));
    // Padded: 2 % in x, 4 % in y, so no point at an edge is drawn half.
    const double xpad = 0.02 * (a1 - a0), pad = 0.04 * (b1 - b0);
    return {ground(a0 - xpad, p.logx), ground(a1 + xpad, p.logx), ground(b0 - pad, p.logy),
            ground(b1 + pad, p.logy)};
}

/// A string as a literal of Vega's expression language (a JSON string is one).
std::string literal(const std::string& s) { return Json(s).dump(); }

/// The signals that zoom and pan a plot: the wheel zooms about the pointer (in log10 on a log
/// axis: zoomLog), a drag pans, a double click goes back to `domain`. `ydown`: y grows
/// downwards (the periodogram's rows), which turns a drag's vertical sign.
Json zoom_signals(const std::array<double, 4>& domain, bool logx, bool logy, bool ydown) {
    const std::string dy = ydown ? "y() - down[1]" : "down[1] - y()";
    Json signals = Json::array({
        {{"name", "down"},
         {"value", nullptr},
         {"on", {{{"events", "mousedown"}, {"update", "xy()"}},
                 {{"events", "window:mouseup"}, {"update", "null"}}}}},
        {{"name", "drag"},
         {"value", {0, 0}},
         {"on",
          {{{"events",
             {{{"source", "window"},
               {"type", "mousemove"},
               {"consume", true},
               {"between", {{{"type", "mousedown"}}, {{"source", "window"}, {"type", "mouseup"}}}}}}},
            {"update", "down ? [x() - down[0], " + dy + "] : [0, 0]"}}}}},
        {{"name", "anchor"},
         {"value", {0, 0}},
         {"on", {{{"events", "wheel"}, {"update", "[invert('x', x()), invert('y', y())]"}}}}},
        {{"name", "zoom"},
         {"value", 1},
         {"on",
          {{{"events", "wheel!"},
            {"force", true},
            {"update", "pow(1.001, event.deltaY * pow(16, event.deltaMode))"}}}}},
    });
    // Per axis: its first view (home), its domain when the drag began (start), its domain.
    const auto axis = [&](const std::string& a, int i, bool log, const std::string& size) {
        const std::string kind = log ? "Log" : "Linear", n = std::to_string(i);
        signals.push_back({{"name", a + "home"}, {"value", {domain[2 * i], domain[2 * i + 1]}}});
        signals.push_back({{"name", a + "start"},
                           {"value", nullptr},
                           {"on", {{{"events", "mousedown"}, {"update", "slice(" + a + "dom)"}}}}});
        signals.push_back(
            {{"name", a + "dom"},
             {"value", {domain[2 * i], domain[2 * i + 1]}},
             {"on",
              {{{"events", {{"signal", "drag"}}},
                {"update", "pan" + kind + "(" + a + "start, drag[" + n + "] / " + size + ")"}},
               {{"events", {{"signal", "zoom"}}},
                {"update", "zoom" + kind + "(" + a + "dom, anchor[" + n + "], zoom)"}},
               {{"events", "dblclick"}, {"update", a + "home"}}}}});
    };
    axis("x", 0, logx, "width");
    axis("y", 1, logy, "height");
    return signals;
}

/// An x or y scale on the zoomed domain.
Json axis_scale(const std::string& name, bool log, bool reverse = false) {
    Json s{{"name", name},
           {"type", log ? "log" : "linear"},
           {"domain", {{"signal", name + "dom"}}},
           {"range", name == "x" ? "width" : "height"},
           {"zero", false},
           {"nice", false}};
    if (reverse) s["reverse"] = true;
    return s;
}

/// The bottom and left axes with grid lines; a log axis labels its ticks as 1e-3, 2e-3 ...
Json axes(const std::string& xlabel, const std::string& ylabel, bool logx, bool logy,
          bool whole_x = false) {
    const auto axis = [](const char* orient, const char* scale, const std::string& title,
                         bool log) {
        Json a{{"orient", orient}, {"scale", scale}, {"title", title}, {"grid", true},
               {"gridColor", "#eee"}, {"labelOverlap", true}};
        // Five or more decades get a tick at each decade only; fewer get 2x and 5x ticks too.
        if (log) a["format"] = "~e", a["tickCount"] = 5;
        return a;
    };
    Json x = axis("bottom", "x", xlabel, logx);
    if (whole_x) x["tickMinStep"] = 1, x["format"] = "d";
    return Json::array({x, axis("left", "y", ylabel, logy)});
}

/// A tooltip: the series' name and each (label, expression) pair, numbers to 6 digits.
Json tooltip(const std::string& series,
             const std::vector<std::pair<std::string, std::string>>& fields) {
    std::string t = "{" + literal("series") + ": " + literal(series);
    for (const auto& [label, expr] : fields)
        t += ", " + literal(label) + ": format(" + expr + ", '.6~g')";
    return {{"signal", t + "}"}};
}

/// The marks of one series: bars, points or a line broken where a value cannot be drawn.
Json series_mark(const Plot& p, const Series& s, const std::string& data) {
    Json values = Json::array();
    // Bars: bar i spans [x[i], x[i + 1]], so x holds one more edge than there are bars.
    const size_t n = s.kind == Series::Bars && !s.x.empty() ? s.x.size() - 1 : s.x.size();
    for (size_t i = 0; i < n; ++i) {
        const bool ok = drawable(p, s.x[i], s.y[i]);
        if (s.kind == Series::Line)
            values.push_back({{"x", std::isfinite(s.x[i]) ? Json(s.x[i]) : Json(nullptr)},
                              {"y", ok ? Json(s.y[i]) : Json(nullptr)}});
        else if (ok && s.kind == Series::Points)
            values.push_back({{"x", s.x[i]}, {"y", s.y[i]}});
        else if (ok)
            values.push_back({{"x", s.x[i]}, {"x2", s.x[i + 1]}, {"y", s.y[i]}});
    }
    const std::string label = s.label.empty() ? p.ylabel : s.label;
    Json enc{{"x", {{"scale", "x"}, {"field", "x"}}}, {"y", {{"scale", "y"}, {"field", "y"}}}};
    Json mark{{"from", {{"data", data}}}, {"clip", true}};
    if (s.kind == Series::Bars) {
        mark["type"] = "rect";
        enc["x2"] = {{"scale", "x"}, {"field", "x2"}};
        enc["y2"] = p.logy ? Json{{"signal", "height"}} : Json{{"scale", "y"}, {"value", 0}};
        enc["fill"] = {{"value", s.color}};
        enc["fillOpacity"] = {{"value", 0.75}};
        enc["tooltip"] = tooltip(label, {{p.xlabel + " from", "datum.x"},
                                         {"to", "datum.x2"},
                                         {p.ylabel, "datum.y"}});
    } else if (s.kind == Series::Points) {
        mark["type"] = "symbol";
        enc["size"] = {{"value", 14}};
        enc["fill"] = {{"value", s.color}};
        enc["tooltip"] = tooltip(label, {{p.xlabel, "datum.x"}, {p.ylabel, "datum.y"}});
    } else {
        mark["type"] = "line";
        enc["defined"] = {{"signal", "datum.y !== null && datum.x !== null"}};
        enc["stroke"] = {{"value", s.color}};
        enc["strokeWidth"] = {{"value", 1.6}};
        if (s.dashed) enc["strokeDash"] = {{"value", {6, 4}}};
        enc["tooltip"] = tooltip(label, {{p.xlabel, "datum.x"}, {p.ylabel, "datum.y"}});
    }
    mark["encode"] = {{"update", enc}};
    return {{"data", {{"name", data}, {"values", values}}}, {"mark", mark}};
}

/// A shaded band between lo and hi.
Json band_mark(const Plot& p, const Band& b, const std::string& data) {
    Json values = Json::array();
    for (size_t i = 0; i < b.x.size(); ++i)
        if (drawable(p, b.x[i], b.lo[i]) && drawable(p, b.x[i], b.hi[i]))
            values.push_back({{"x", b.x[i]}, {"lo", b.lo[i]}, {"hi", b.hi[i]}});
    Json enc{{"x", {{"scale", "x"}, {"field", "x"}}},
             {"y", {{"scale", "y"}, {"field", "hi"}}},
             {"y2", {{"scale", "y"}, {"field", "lo"}}},
             {"fill", {{"value", b.color}}},
             {"fillOpacity", {{"value", 0.15}}},
             {"tooltip", tooltip(b.label, {{"from", "datum.lo"}, {"to", "datum.hi"}})}};
    return {{"data", {{"name", data}, {"values", values}}},
            {"mark", {{"type", "area"}, {"from", {{"data", data}}}, {"clip", true},
                      {"encode", {{"update", enc}}}}}};
}

/// A dashed horizontal line across the plot.
Json hline_mark(const HLine& h, const std::string& label) {
    Json enc{{"x", {{"value", 0}}},
             {"x2", {{"signal", "width"}}},
             {"y", {{"scale", "y"}, {"value", h.y}}},
             {"stroke", {{"value", h.color}}},
             {"strokeDash", {{"value", {5, 4}}}},
             {"tooltip", tooltip(label, {{"value", Json(h.y).dump()}})}};
    return {{"type", "rule"}, {"clip", true}, {"encode", {{"update", enc}}}};
}

/// The legend: an entry per named series, band and line, top right, in the plot's colours.
Json legend_parts(const Plot& p) {
    Json names = Json::array(), colors = Json::array();
    const auto add = [&](const std::string& label, const std::string& color) {
        if (!label.empty()) names.push_back(label), colors.push_back(color);
    };
    for (const auto& s : p.series) add(s.label, s.color);
    for (const auto& b : p.bands) add(b.label, b.color);
    for (const auto& h : p.hlines) add(h.label, h.color);
    return {{"scale",
             {{"name", "legend"}, {"type", "ordinal"}, {"domain", names}, {"range", colors}}},
            {"legend",
             {{"fill", "legend"},
              {"orient", "top-right"},
              {"symbolType", "square"},
              {"fillColor", "rgba(255,255,255,0.85)"},
              {"labelLimit", 320},
              {"padding", 4}}},
            {"entries", names.size()}};
}

/// A plot's Vega spec: its data inline, zoomable axes, marks with tooltips, a legend.
Json vega_spec(const Plot& p) {
    const auto domain = initial_domain(p);
    Json data = Json::array(), marks = Json::array();
    const auto add = [&](const Json& part) {
        data.push_back(part["data"]);
        marks.push_back(part["mark"]);
    };
    for (size_t i = 0; i < p.bands.size(); ++i)
        add(band_mark(p, p.bands[i], "band" + std::to_string(i)));
    for (const auto& h : p.hlines)
        if (!(p.logy && h.y <= 0) && std::isfinite(h.y))
            marks.push_back(hline_mark(h, h.label.empty() ? "reference" : h.label));
    for (size_t i = 0; i < p.series.size(); ++i)
        add(series_mark(p, p.series[i], "series" + std::to_string(i)));
    const Json legend = legend_parts(p);
    Json spec{{"description", p.title},
              {"title", {{"text", p.title}, {"fontSize", 13}}},
              {"width", kW},
              {"height", kH},
              {"padding", 6},
              {"autosize", "pad"},
              {"signals", zoom_signals(domain, p.logx, p.logy, false)},
              {"data", data},
              {"scales", {axis_scale("x", p.logx), axis_scale("y", p.logy), legend["scale"]}},
              {"axes", axes(p.xlabel, p.ylabel, p.logx, p.logy, p.whole_x)},
              {"marks", marks}};
    if (legend["entries"].get<size_t>() > 0) spec["legends"] = {legend["legend"]};
    return spec;
}

/// The 2-D periodogram as a heat map of log10 power over (kx, ky), ky growing downwards as the
/// image's rows do, 8 decades of colour below the largest cell.
Json heatmap_spec(const PeriodogramSummary& s, int w, int h) {
    const std::string title = "2-D periodogram, log10 power (centred; window: " + s.window + ")";
    double hi = -INFINITY;
    for (double v : s.heat)
        if (std::isfinite(v)) hi = std::max(hi, v);
    const double lo = std::isfinite(hi) ? hi - 8.0 : 0.0;
    if (!std::isfinite(hi)) hi = 1.0;
    // Cells as (column, row, value); their edges in cycles/pixel by a formula (a smaller page).
    // Display row r holds ky index r - h/2 (analysis/analyze.cpp centres the power).
    Json values = Json::array();
    for (int r = 0; r < s.heat_height; ++r)
        for (int c = 0; c < s.heat_width; ++c) {
            const double v = s.heat[size_t(r) * s.heat_width + c];
            // 1e-4 decades (0.02 % in power) is far below a colour step.
            values.push_back({{"c", c}, {"r", r},
                              {"v", std::isfinite(v) ? Json(std::round(v * 1e4) / 1e4) : Json(nullptr)}});
        }
    const std::string cw = std::to_string(s.heat_width), ch = std::to_string(s.heat_height);
    Json transform = Json::array(
        {{{"type", "formula"}, {"as", "kx0"}, {"expr", "-0.5 + datum.c / " + cw}},
         {{"type", "formula"}, {"as", "kx1"}, {"expr", "-0.5 + (datum.c + 1) / " + cw}},
         {{"type", "formula"}, {"as", "ky0"}, {"expr", "-0.5 + datum.r / " + ch}},
         {{"type", "formula"}, {"as", "ky1"}, {"expr", "-0.5 + (datum.r + 1) / " + ch}}});
    const Json colour = Json::array(
        {{{"test", "datum.v === null"}, {"value", "#000"}}, {{"scale", "color"}, {"field", "v"}}});
    Json enc{{"x", {{"scale", "x"}, {"field", "kx0"}}},
             {"x2", {{"scale", "x"}, {"field", "kx1"}}},
             {"y", {{"scale", "y"}, {"field", "ky0"}}},
             {"y2", {{"scale", "y"}, {"field", "ky1"}}},
             {"fill", colour},
             // Stroked in its own colour: no hairline seams between neighbouring cells.
             {"stroke", colour},
             {"strokeWidth", {{"value", 0.5}}},
             {"tooltip", {{"signal", "{'kx from': format(datum.kx0, '.4~g'), "
                                     "'ky from': format(datum.ky0, '.4~g'), "
                                     "'log10 power': datum.v === null ? 'none' : "
                                     "format(datum.v, '.4~g')}"}}}};
    const std::array<double, 4> domain{-0.5, 0.5, -0.5, 0.5};
    return {{"description", title},
            {"title", {{"text", title}, {"fontSize", 13},
                       {"subtitle", std::to_string(s.heat_width) + "x" + std::to_string(s.heat_height) +
                                        " cells over the " + std::to_string(w) + "x" +
                                        std::to_string(h) + " frequencies"}}},
            {"width", 300},
            {"height", 300},
            {"padding", 6},
            {"autosize", "pad"},
            {"signals", zoom_signals(domain, false, false, true)},
            {"data", {{{"name", "cells"}, {"values", values}, {"transform", transform}}}},
            {"scales", {axis_scale("x", false), axis_scale("y", false, true),
                        {{"name", "color"}, {"type", "linear"}, {"scheme", "viridis"},
                         {"domain", {lo, hi}}, {"clamp", true}, {"zero", false}}}},
            {"axes", axes("kx (cycles/pixel)", "ky (cycles/pixel)", false, false)},
            {"legends", {{{"fill", "color"}, {"type", "gradient"}, {"title", "log10 power"},
                          {"gradientLength", 280}}}},
            {"marks", {{{"type", "rect"}, {"from", {{"data", "cells"}}}, {"clip", true},
                        {"encode", {{"update", enc}}}}}}};
}

std::vector<double> iota_from(size_t n, double first) {
    std::vector<double> v(n);
    for (size_t i = 0; i < n; ++i) v[i] = first + double(i);
    return v;
}

/// A plot with its title and axis labels.
Plot titled(const std::string& title, const std::string& xlabel, const std::string& ylabel) {
    Plot p;
    p.title = title;
    p.xlabel = xlabel;
    p.ylabel = ylabel;
    return p;
}

const std::string kMeasured = "measured";
const std::string kTheoryRed = "#d62728";

/// The histogram against the Gaussian of the theory's mean and variance.
Json histogram_plot(const AnalysisResult& r) {
    const auto& T = r.theory;
    Plot p = titled("Histogram of values (64 bins over mean +- 4 sd)", "value", "pixels per bin");
    Series s;
    s.label = kMeasured;
    s.kind = Series::Bars;
    const auto& hg = r.histogram;
    const double bw = (hg.hi - hg.lo) / double(hg.counts.size());
    for (size_t i = 0; i <= hg.counts.size(); ++i) {
        s.x.push_back(hg.lo + bw * double(i));
        s.y.push_back(i < hg.counts.size() ? double(hg.counts[i]) : 0.0);
    }
    p.series.push_back(s);
    if (T && T->variance > 0) {
        Series g;
        g.label = "Gaussian, theory mean and variance";
        g.color = kTheoryRed;
        const double total = double(r.frames) * r.width * r.height;
        const double sd = std::sqrt(T->variance);
        for (int i = 0; i <= 256; ++i) {
            const double x = hg.lo + (hg.hi - hg.lo) * i / 256.0;
            const double z = (x - T->mean) / sd;
            g.x.push_back(x);
            g.y.push_back(total * bw * std::exp(-0.5 * z * z) /
                          (sd * std::sqrt(2 * std::numbers::pi)));
        }
        p.series.push_back(g);
    }
    return vega_spec(p);
}

Json radial_spectrum_plot(const AnalysisResult& r) {
    const auto& T = r.theory;
    Plot p = titled("Radially averaged power spectrum", "frequency |k| (cycles/pixel)",
                    "power (value^2 pixel^2)");
    p.logx = p.logy = true;
    Series s;
    s.label =
        kMeasured + " (" + std::to_string(r.frames) + (r.frames == 1 ? " frame)" : " frames)");
    s.kind = Series::Points;
    for (size_t b = 0; b < r.spectrum.power.size(); ++b)
        if (r.spectrum.count[b] > 0)
            s.x.push_back(r.spectrum.frequency[b]), s.y.push_back(r.spectrum.power[b]);
    p.series.push_back(s);
    if (T && T->spectrum) {
        Series t;
        t.label = "theory";
        t.color = kTheoryRed;
        for (size_t b = 0; b < r.spectrum.power.size(); ++b)
            if (r.spectrum.count[b] > 0)
                t.x.push_back(r.spectrum.frequency[b]), t.y.push_back(T->spectrum->power[b]);
        p.series.push_back(t);
    }
    return vega_spec(p);
}

/// z per annulus with the Bonferroni limits +-threshold; `title` and `ylabel` name the test.
Json z_plot(const std::string& title, const std::string& ylabel, Series s,
                   double threshold) {
    Plot p = titled(title, "frequency |k| (cycles/pixel)", ylabel);
    s.kind = Series::Points;
    p.series.push_back(s);
    p.hlines.push_back({threshold, "Bonferroni limit +-" + fixed(threshold, 2), "#777"});
    p.hlines.push_back({-threshold, "", "#777"});
    return vega_spec(p);
}

Json spectrum_z_plot(const AnalysisResult& r) {
    const SpectrumTheory& S = *r.theory->spectrum;
    Series s;
    s.label = "z";
    for (size_t b = 0; b < S.z.size(); ++b)
        if (std::isfinite(S.z[b])) s.x.push_back(r.spectrum.frequency[b]), s.y.push_back(S.z[b]);
    return z_plot("Spectrum against theory: z per annulus", "z (Wilson-Hilferty)", s, S.threshold);
}

Json autocovariance_plot(const AnalysisResult& r) {
    const auto& T = r.theory;
    Plot p = titled("Radial autocovariance", "lag (pixels)", "covariance (value^2)");
    p.whole_x = true;
    Series s;
    s.label = kMeasured;
    s.kind = Series::Points;
    s.x = iota_from(r.autocovariance.size(), 0);
    s.y = r.autocovariance;
    p.series.push_back(s);
    if (T && !T->autocovariance.empty()) {
        Series t;
        t.label = "theory";
        t.color = kTheoryRed;
        t.x = iota_from(T->autocovariance.size(), 0);
        t.y = T->autocovariance;
        p.series.push_back(t);
    }
    p.hlines.push_back({0.0, "", "#aaa"});
    return vega_spec(p);
}

/// One statistic per frame from frame `from` on, with the theory +- 2 sd of one frame.
Json per_frame_plot(const AnalysisResult& r, const std::string& title,
                           const std::string& ylabel, double (*get)(const FrameStats&),
                           double theory, double sd, size_t from) {
    const auto x = iota_from(size_t(r.frames), double(r.first_frame));
    Plot p = titled(title, "frame", ylabel);
    p.whole_x = true;
    Series s;
    s.label = kMeasured;
    for (size_t j = from; j < r.frame_stats.size(); ++j)
        s.x.push_back(x[j]), s.y.push_back(get(r.frame_stats[j]));
    p.series.push_back(s);
    if (std::isfinite(theory)) {
        if (sd > 0) {
            Band b;
            b.label = "theory +- 2 sd (one frame)";
            b.x = {x[from], x.back()};
            b.lo = {theory - 2 * sd, theory - 2 * sd};
            b.hi = {theory + 2 * sd, theory + 2 * sd};
            p.bands.push_back(b);
        }
        p.hlines.push_back({theory, "theory", kTheoryRed});
    }
    return vega_spec(p);
}

/// The per-frame mean, variance and difference variance (a sequence of frames).
void add_per_frame_plots(const AnalysisResult& r, std::vector<Json>& out) {
    const auto& T = r.theory;
    out.push_back(per_frame_plot(
        r, "Per-frame mean", "mean", [](const FrameStats& f) { return f.mean; }, T ? T->mean : NAN,
        T ? T->sd_frame_mean : 0.0, 0));
    out.push_back(per_frame_plot(
        r, "Per-frame variance", "variance", [](const FrameStats& f) { return f.variance; },
        T ? T->variance + T->sd_mean * T->sd_mean - T->sd_frame_mean * T->sd_frame_mean : NAN,
        T ? T->sd_frame_variance : 0.0, 0));
    out.push_back(per_frame_plot(
        r, "Per-frame difference variance (frame - previous)", "variance of the difference",
        [](const FrameStats& f) { return f.diff_variance; },
        T && T->diff_variance ? *T->diff_variance : NAN, 0.0, 1));
}

Json drift_plot(const Stationarity& st) {
    Series s;
    s.label = "z, corrected";
    s.x = st.drift.frequency;
    s.y = st.z_corrected;
    return z_plot("Spectral drift, first quarter against last: z per annulus",
                  "z (correlation-corrected)", s, st.z_threshold);
}

/// The report's plots, in order.
std::vector<Json> plots(const AnalysisResult& r) {
    std::vector<Json> out;
    out.push_back(histogram_plot(r));
    out.push_back(heatmap_spec(r.periodogram, r.width, r.height));
    out.push_back(radial_spectrum_plot(r));
    if (r.theory && r.theory->spectrum) out.push_back(spectrum_z_plot(r));
    out.push_back(autocovariance_plot(r));
    if (r.frames > 1) add_per_frame_plots(r, out);
    if (r.stationarity.available) out.push_back(drift_plot(r.stationarity));
    return out;
}

// ---------------------------------------------------------------------------------------------
// JSON

/// A finite number, or null (JSON has no NaN or infinity).
Json num(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

/// An array of numbers; integers stay integers, non-finite values become null.
template <class V>
Json nums(const V& values) {
    Json a = Json::array();
    for (const auto& v : values) {
        if constexpr (std::is_integral_v<std::decay_t<decltype(v)>>)
            a.push_back(v);
        else
            a.push_back(num(static_cast<double>(v)));
    }
    return a;
}

Json stationarity_json(const Stationarity& st) {
    Json j{{"available", st.available}};
    if (!st.available) {
        j["reason"] = st.reason;
        j["stationary"] = nullptr;
        return j;
    }
    j["trend"] = {{"slope", num(st.trend.slope)},   {"stderr", num(st.trend.stderr_slope)},
                  {"t", num(st.trend.t)},           {"blocks", st.trend_blocks},
                  {"limit", num(st.t_limit)}};
    j["spectral_drift"] = {{"quarter_frames", st.quarter},
                           {"max_abs_z", num(st.drift.max_abs_z)},
                           {"q_eff", num(st.q_eff)},
                           {"common_level_relative_variance", num(st.common_variance)},
                           {"max_abs_z_corrected", num(st.max_abs_z_corrected)},
                           {"threshold", num(st.z_threshold)},
                           {"z_corrected", nums(st.z_corrected)},
                           {"frequency", nums(st.drift.frequency)},
                           {"z", nums(st.drift.z)}};
    j["level"] = {{"model", st.level_model},
                  {"covariance", nums(st.level_covariance)},
                  {"mean", num(st.level.mean)},
                  {"slope", num(st.level.slope)},
                  {"sd_slope", num(st.level.sd_slope)},
                  {"z_trend", num(st.level.z_trend)},
                  {"z_trend_limit", num(st.level_z_limit)},
                  {"blocks", st.level.blocks},
                  {"chi2", num(st.level.chi2)},
                  {"dof", st.level.dof},
                  {"z_blocks", num(st.level.z_blocks)},
                  {"z_blocks_limit", num(st.blocks_z_limit)},
                  {"block_dof", num(st.block_dof)},
                  {"min_block_dof", num(st.min_block_dof)},
                  {"note", st.level_note}};
    j["family_alpha"] = num(st.family_alpha);
    j["power"] = num(st.power);
    j["detectable_drift"] = num(st.detectable_drift);
    j["drift_of_interest"] = num(st.drift_of_interest);
    j["verdict"] = st.verdict;
    j["stationary"] = st.stationary;
    return j;
}

Json theory_json(const TheoryComparison& T, const Moments& m) {
    Json j{{"scene", T.scene}, {"hash", T.hash}, {"zoom", num(T.zoom)}, {"mapped", T.mapped}};
    if (T.mapped) {
        j["range"] = {num(T.map_lo), num(T.map_hi)};
        j["clipped_fraction"] = num(T.clipped_fraction);
    }
    j["field_mean"] = num(T.field_mean);
    j["field_variance"] = num(T.field_variance);
    j["mean"] = {{"measured", num(m.mean)},  {"expected", num(T.mean)},
                 {"sd", num(T.sd_mean)},     {"sd_frame", num(T.sd_frame_mean)},
                 {"z", num(T.z_mean)},       {"limit", num(T.z_limit)},
                 {"agrees", T.mean_agrees}};
    j["variance"] = {{"measured", num(m.variance)}, {"expected", num(T.variance)},
                     {"sd", num(T.sd_variance)},    {"sd_frame", num(T.sd_frame_variance)},
                     {"z", num(T.z_variance)},      {"limit", num(T.z_limit)},
                     {"agrees", T.variance_agrees}};
    if (T.spectrum) {
        const SpectrumTheory& S = *T.spectrum;
        Json s{{"compared", S.compared}, {"max_abs_z", num(S.max_abs_z)},
               {"threshold", num(S.threshold)}};
        if (S.not_judged.empty()) {
            s["agrees"] = S.agrees;
        } else {
            s["agrees"] = nullptr;
            s["not_judged"] = S.not_judged;
        }
        j["spectrum"] = s;
    } else {
        j["spectrum"] = nullptr;
        j["no_spectrum"] = T.no_spectrum;
    }
    j["diff_variance"] = T.diff_variance ? num(*T.diff_variance) : Json(nullptr);
    return j;
}

Json structure_json(const StructureSummary& S) {
    Json hurst = Json::array();
    for (size_t s = 0; s < S.hurst.size(); ++s)
        hurst.push_back({{"s", s},
                         {"H", num(S.hurst[s])},
                         {"stderr", num(S.hurst_stderr[s])},
                         {"H_x", num(S.hurst_x[s])},
                         {"H_y", num(S.hurst_y[s])},
                         {"H_diagonal", num(S.hurst_diagonal[s])}});
    return {{"lags", nums(S.lags)},     {"f", nums(S.f)},
            {"fx", nums(S.fx)},         {"fy", nums(S.fy)},
            {"diagonal", nums(S.diagonal)}, {"realizations", S.realizations},
            {"hurst", hurst}};
}

/// "key          value": a text report line, the value in a column.
void put_line(std::ostream& o, const std::string& k, const std::string& v) {
    o << k << std::string(k.size() < 13 ? 13 - k.size() : 1, ' ') << v << "\n";
}

/// The input, its moments, histogram range, periodogram summary and frame correlation.
void put_measurements(std::ostream& o, const AnalysisResult& r) {
    const auto line = [&](const std::string& k, const std::string& v) { put_line(o, k, v); };
    const auto& m = r.moments;
    line("input", r.input + ": " + source_text(r));
    line("size", std::to_string(r.width) + "x" + std::to_string(r.height) + ", " + frames_text(r));
    line("mean", fmt(m.mean));
    line("variance", fmt(m.variance) + " (sd " + fmt(std::sqrt(m.variance)) + ")");
    line("skewness", fmt(m.skewness, 4));
    line("kurtosis", fmt(m.excess_kurtosis, 4) + " (excess)");
    line("min / max", fmt(m.min) + " / " + fmt(m.max));
    line("histogram", "64 bins over [" + fmt(r.histogram.lo, 4) + ", " + fmt(r.histogram.hi, 4) +
                          "), " + std::to_string(r.histogram.below) + " below, " +
                          std::to_string(r.histogram.above) + " above");
    const auto& p = r.periodogram;
    line("periodogram", "window " + p.window + " (" + (p.periodic ? "periodic" : "not periodic") +
                            ": wrap/interior step ratio x " + fmt(p.wrap_ratio_x, 3) + ", y " +
                            fmt(p.wrap_ratio_y, 3) + "), averaged over " +
                            std::to_string(r.frames) + (r.frames == 1 ? " frame" : " frames"));
    line("", "total power " + fmt(p.total_power) + ", centroid |k| " + fmt(p.centroid, 4) +
                 " cycles/px, peak " + fmt(p.peak_power, 4) + " at (" + fmt(p.peak_fx, 4) + ", " +
                 fmt(p.peak_fy, 4) + ")");
    line("", "anisotropy " + fmt(p.anisotropy, 3) + " (0 = isotropic), axis " +
                 fixed(p.orientation_deg, 1) + " deg from +x towards +y (image rows down)");
    if (r.frames > 1) line("correlation", "frames per independent frame " + correlation_text(r));
}

/// The stationarity tests' figures: variance trend, spectral drift, level of the variance.
void put_stationarity(std::ostream& o, const Stationarity& st) {
    put_line(o, "trend",
             "per-frame variance slope " + fmt(st.trend.slope, 4) + " per frame, stderr " +
                 fmt(st.trend.stderr_slope, 4) + ", t " + fixed(st.trend.t, 2) + " (" +
                 std::to_string(st.trend_blocks) + " blocks)");
    put_line(o, "drift",
             "first vs last " + std::to_string(st.quarter) + " frames: max|z| " +
                 fixed(st.drift.max_abs_z, 2) + " as if independent, " +
                 fixed(st.max_abs_z_corrected, 2) + " for " + fmt(st.q_eff, 3) +
                 " independent frames per quarter and a common level varying by " +
                 fmt(100 * std::sqrt(st.common_variance), 2) + " %");
    put_line(o, "level",
             "frame variance " + fmt(st.level.mean, 4) + ": trend z " + fixed(st.level.z_trend, 2) +
                 ", " + std::to_string(st.level.blocks) + " block means chi2 " +
                 fixed(st.level.chi2, 1) + " on " + std::to_string(st.level.dof) + " dof (z " +
                 fixed(st.level.z_blocks, 2) + "); covariance: " + st.level_model);
    if (!st.level_note.empty()) put_line(o, "", st.level_note);
}

/// The scene's closed-form theory beside the measured figures.
void put_theory(std::ostream& o, const AnalysisResult& r) {
    const auto line = [&](const std::string& k, const std::string& v) { put_line(o, k, v); };
    const auto& m = r.moments;
    const auto& T = *r.theory;
    o << "\ntheory       " << T.scene << " (hash " << T.hash << "), zoom " << fmt(T.zoom)
      << " px/unit\n";
    line("field", "mean " + fmt(T.field_mean) + ", variance " + fmt(T.field_variance) +
                      " (Campbell's theorem)");
    if (T.mapped)
        line("mapping", "display values v -> " + fmt(T.map_lo) + " + v * (" + fmt(T.map_hi) +
                            " - " + fmt(T.map_lo) + "); " + fixed(100 * T.clipped_fraction, 3) +
                            " % clipped");
    line("mean", "measured " + fmt(m.mean) + ", theory " + fmt(T.mean) + " +- " +
                     fmt(T.sd_mean, 3) + ", z " + fixed(T.z_mean, 2));
    line("variance", "measured " + fmt(m.variance) + ", theory " + fmt(T.variance) + " +- " +
                         fmt(T.sd_variance, 3) + ", z " + fixed(T.z_variance, 2));
    if (T.diff_variance && r.frames > 1) {
        double dv = 0;
        for (size_t j = 1; j < r.frame_stats.size(); ++j) dv += r.frame_stats[j].diff_variance;
        dv /= double(r.frame_stats.size() - 1);
        line("diff var",
             "measured " + fmt(dv) + " (mean over frames), theory " + fmt(*T.diff_variance));
    }
    if (T.spectrum)
        line("spectrum", "max|z| " + fixed(T.spectrum->max_abs_z, 2) + " over " +
                             std::to_string(T.spectrum->compared) + " annuli");
}

/// The verdicts against theory and on stationarity, H(s) and the notes.
void put_verdicts(std::ostream& o, const AnalysisResult& r) {
    if (r.theory) {
        const auto& T = *r.theory;
        o << "mean agrees with theory: " << yes_no(T.mean_agrees) << " ("
          << z_text(T.z_mean, T.z_limit) << ")\n";
        o << "variance agrees with theory: " << yes_no(T.variance_agrees) << " ("
          << z_text(T.z_variance, T.z_limit) << ")\n";
        if (T.spectrum && T.spectrum->not_judged.empty())
            o << "spectrum agrees with theory: " << yes_no(T.spectrum->agrees) << " ("
              << spectrum_threshold_text(*T.spectrum) << ")\n";
        else
            o << "spectrum agrees with theory: n/a ("
              << (T.spectrum ? T.spectrum->not_judged : T.no_spectrum) << ")\n";
    }
    const auto& st = r.stationarity;
    if (st.available)
        o << "stationary: " << verdict_word(st) << " (" << stationarity_verdict(st) << ")\n";
    else
        o << "stationary: n/a (" << st.reason << ")\n";
    if (r.structure) {
        const auto& S = *r.structure;
        std::string hs;
        for (size_t s = 0; s < S.hurst.size(); ++s)
            hs += (s ? ", " : "") + fmt(S.hurst[s], 3) +
                  (S.realizations > 1 ? " +- " + fmt(S.hurst_stderr[s], 2) : "");
        put_line(o, "H(s)",
                 "s = 0.." + std::to_string(S.hurst.size() - 1) + ": " + hs +
                     " (Kaplan & Kuo eq. 21, f along x and y)");
    }
    for (const auto& n : r.notes) o << "note: " << n << "\n";
}

void put_histogram_table(std::ostream& o, const AnalysisResult& r) {
    o << "\nhistogram (bin start, count)\n";
    const double bw = (r.histogram.hi - r.histogram.lo) / double(r.histogram.counts.size());
    uint64_t most = 1;
    for (auto c : r.histogram.counts) most = std::max(most, c);
    for (size_t i = 0; i < r.histogram.counts.size(); ++i) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "  %12.5g %10llu ", r.histogram.lo + bw * double(i),
                      static_cast<unsigned long long>(r.histogram.counts[i]));
        o << buf
          << std::string(size_t(40.0 * double(r.histogram.counts[i]) / double(most) + 0.5), '#')
          << "\n";
    }
}

void put_spectrum_table(std::ostream& o, const AnalysisResult& r) {
    const bool spec_theory = r.theory && r.theory->spectrum;
    o << "\nradial spectrum (annulus, frequency cycles/px, power, bins"
      << (spec_theory ? ", theory, ratio, z" : "") << ")\n";
    for (size_t b = 0; b < r.spectrum.power.size(); ++b) {
        if (r.spectrum.count[b] == 0) continue;
        char buf[160];
        std::snprintf(buf, sizeof buf, "  %4zu %9.6f %13.6g %7llu", b, r.spectrum.frequency[b],
                      r.spectrum.power[b], static_cast<unsigned long long>(r.spectrum.count[b]));
        o << buf;
        if (spec_theory) {
            const auto& S = *r.theory->spectrum;
            std::snprintf(buf, sizeof buf, " %13.6g %8s %7s", S.power[b],
                          fmt(S.ratio[b], 4).c_str(),
                          std::isfinite(S.z[b]) ? fixed(S.z[b], 2).c_str() : "-");
            o << buf;
        }
        o << "\n";
    }
}

void put_autocovariance_table(std::ostream& o, const AnalysisResult& r) {
    const bool acov_theory = r.theory && !r.theory->autocovariance.empty();
    o << "\nradial autocovariance (lag px, value" << (acov_theory ? ", theory" : "") << ")\n";
    for (size_t l = 0; l < r.autocovariance.size(); ++l) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "  %4zu %13.6g", l, r.autocovariance[l]);
        o << buf;
        if (acov_theory) {
            std::snprintf(buf, sizeof buf, " %13.6g", r.theory->autocovariance[l]);
            o << buf;
        }
        o << "\n";
    }
}

void put_frame_table(std::ostream& o, const AnalysisResult& r) {
    o << "\nper frame (frame, mean, variance, diff variance)\n";
    for (size_t j = 0; j < r.frame_stats.size(); ++j) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "  %6lld %13.6g %13.6g %13.6g\n",
                      r.first_frame + static_cast<long long>(j), r.frame_stats[j].mean,
                      r.frame_stats[j].variance, r.frame_stats[j].diff_variance);
        o << buf;
    }
}

/// A spec as JSON text that can stand inside a <script> element: `</` is written `<\/`, the
/// same string in JSON.
std::string script_json(const Json& spec) {
    std::string t = spec.dump(-1, ' ', false, Json::error_handler_t::replace);
    for (size_t at = t.find("</"); at != std::string::npos; at = t.find("</", at + 3))
        t.replace(at, 2, "<\\/");
    return t;
}

/// The page's script: registers the transforms with the dataflow (what Vega's own bundle does
/// on loading), draws each figure's spec as SVG, shows a hovered item's tooltip at once beside
/// the pointer (Vega's own handler sets the chart's title attribute, which the browser shows
/// late and does not follow the pointer with), and says on <body> when all are drawn
/// (data-ready) or what failed (data-error).
constexpr const char* kDrawPlots = R"js((function () {
  const body = document.body;
  const fail = (e) => {
    if (!body.dataset.error) body.dataset.error = String((e && e.message) || e);
  };
  try {
    const V = window.impulseVega;
    Object.assign(V['vega-dataflow'].transforms, V['vega-transforms'],
                  V['vega-view-transforms'], V['vega-encode']);
    const tip = document.body.appendChild(document.createElement('div'));
    tip.className = 'tip';
    const tooltip = (handler, event, item, value) => {
      tip.style.display = value ? 'block' : 'none';
      if (!value) return;
      tip.textContent = Object.entries(value).map(([k, v]) => k + ': ' + v).join('\n');
      // Right of and below the pointer, or left of and above it where the window ends.
      const right = event.clientX + 14 + tip.offsetWidth <= window.innerWidth;
      const below = event.clientY + 14 + tip.offsetHeight <= window.innerHeight;
      tip.style.left = event.pageX + (right ? 14 : -14 - tip.offsetWidth) + 'px';
      tip.style.top = event.pageY + (below ? 14 : -14 - tip.offsetHeight) + 'px';
    };
    const figures = Array.from(document.querySelectorAll('figure.plot'));
    window.impulseViews = figures.map((f) => new V['vega-view'].View(
        V['vega-parser'].parse(JSON.parse(f.querySelector('script.impulse-spec').textContent)),
        {renderer: 'svg', container: f.querySelector('.chart'), hover: true, tooltip}));
    Promise.all(window.impulseViews.map((v) => v.runAsync())).then(() => {
      body.dataset.plots = String(figures.length);
      body.dataset.ready = '1';
    }, fail);
  } catch (e) {
    fail(e);
  }
})();
)js";

}  // namespace

// ---------------------------------------------------------------------------------------------

std::string to_text(const AnalysisResult& r) {
    std::ostringstream o;
    put_measurements(o, r);
    if (r.stationarity.available) put_stationarity(o, r.stationarity);
    if (r.theory) put_theory(o, r);
    o << "\n";
    put_verdicts(o, r);
    // Tables.
    put_histogram_table(o, r);
    put_spectrum_table(o, r);
    put_autocovariance_table(o, r);
    if (r.frames > 1) put_frame_table(o, r);
    return o.str();
}

std::string to_json(const AnalysisResult& r) {
    const auto& m = r.moments;
    const auto& p = r.periodogram;
    Json j{{"input", r.input},   {"kind", r.kind},     {"values", r.raw ? "raw" : "display"},
           {"bits", r.bits},     {"width", r.width},   {"height", r.height},
           {"frames", r.frames}, {"first_frame", r.first_frame}};
    j["moments"] = {{"mean", num(m.mean)},
                    {"variance", num(m.variance)},
                    {"skewness", num(m.skewness)},
                    {"excess_kurtosis", num(m.excess_kurtosis)},
                    {"min", num(m.min)},
                    {"max", num(m.max)}};
    j["histogram"] = {{"lo", num(r.histogram.lo)},
                      {"hi", num(r.histogram.hi)},
                      {"bins", r.histogram.counts.size()},
                      {"counts", nums(r.histogram.counts)},
                      {"below", r.histogram.below},
                      {"above", r.histogram.above}};
    j["periodogram"] = {
        {"window", p.window},
        {"periodic", p.periodic},
        {"wrap_step_ratio", {num(p.wrap_ratio_x), num(p.wrap_ratio_y)}},
        {"total_power", num(p.total_power)},
        {"peak", {{"fx", num(p.peak_fx)}, {"fy", num(p.peak_fy)}, {"power", num(p.peak_power)}}},
        {"centroid_cpp", num(p.centroid)},
        {"anisotropy", num(p.anisotropy)},
        {"orientation_deg", num(p.orientation_deg)}};
    Json radial{{"frequency", nums(r.spectrum.frequency)},
                {"power", nums(r.spectrum.power)},
                {"count", nums(r.spectrum.count)}};
    if (r.theory && r.theory->spectrum) {
        const auto& S = *r.theory->spectrum;
        radial["theory"] = nums(S.power);
        radial["ratio"] = nums(S.ratio);
        radial["z"] = nums(S.z);
    }
    j["radial_spectrum"] = radial;
    Json acov{{"max_lag", r.max_lag}, {"value", nums(r.autocovariance)}};
    if (r.theory && !r.theory->autocovariance.empty())
        acov["theory"] = nums(r.theory->autocovariance);
    j["autocovariance"] = acov;
    std::vector<double> a, b, c;
    for (const auto& f : r.frame_stats)
        a.push_back(f.mean), b.push_back(f.variance), c.push_back(f.diff_variance);
    j["per_frame"] = {{"mean", nums(a)}, {"variance", nums(b)}, {"diff_variance", nums(c)}};
    j["frame_correlation"] = {{"source", r.tau_source},
                              {"mean", num(r.tau_mean)},
                              {"variance", num(r.tau_variance)},
                              {"spectrum", num(r.tau_spectrum)}};
    j["stationarity"] = stationarity_json(r.stationarity);
    j["theory"] = r.theory ? theory_json(*r.theory, m) : Json(nullptr);
    if (r.structure) j["structure"] = structure_json(*r.structure);
    j["notes"] = r.notes;
    // Invalid UTF-8 in a path or a note is replaced rather than thrown on.
    return j.dump(-1, ' ', false, Json::error_handler_t::replace) + "\n";
}

int html_plot_count(const AnalysisResult& r) {
    int n = 4;  // histogram, 2-D periodogram, radial spectrum, autocovariance
    if (r.theory && r.theory->spectrum) ++n;
    if (r.frames > 1) n += 3;
    if (r.stationarity.available) ++n;
    return n;
}

std::string to_html(const AnalysisResult& r, const std::string& chart_library) {
    const std::vector<Json> specs = plots(r);
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"impulse-plots\" content=\"" << specs.size() << "\">\n"
      << "<title>impulse analyze: " << esc(r.input) << "</title>\n<style>\n"
      << "body{font-family:system-ui,-apple-system,'DejaVu Sans',sans-serif;margin:24px auto;"
         "max-width:1400px;color:#222;background:#fafafa}\n"
      << "h1{font-size:20px} h2{font-size:16px;margin-top:28px}\n"
      << "table{border-collapse:collapse;font-size:13px;background:#fff}\n"
      << "td,th{border:1px solid #ddd;padding:3px 8px;text-align:left;vertical-align:top}\n"
      << "th{background:#f0f0f0}\n.yes{color:#1a7f37;font-weight:600}.no{color:#c62828;font-weight:"
         "600}"
         ".na{color:#777}\n"
      << ".plots{display:flex;flex-wrap:wrap;gap:12px}\n"
      << "figure{margin:0;border:1px solid #ddd;background:#fff;padding:4px}\n"
      << ".hint{font-size:13px;color:#555}\n"
      << ".tip{position:absolute;display:none;white-space:pre;pointer-events:none;background:#fff;"
         "border:1px solid #999;border-radius:3px;padding:4px 7px;font-size:12px;"
         "box-shadow:0 1px 4px rgba(0,0,0,.2)}\n"
      << "</style>\n"
      // First, so an error in the library or the specs is on the page (data-error) too.
      << "<script>window.addEventListener('error', (e) => { document.body && "
         "!document.body.dataset.error && (document.body.dataset.error = String(e.message)); "
         "});</script>\n"
      << "</head>\n<body>\n";
    o << "<h1>impulse analyze: " << esc(r.input) << "</h1>\n";

    const auto row = [&](const std::string& k, const std::string& v) {
        o << "<tr><th>" << esc(k) << "</th><td>" << v << "</td></tr>\n";
    };
    const auto verdict = [](bool b) {
        return std::string("<span class=\"") + (b ? "yes\">yes" : "no\">no") + "</span>";
    };
    o << "<h2>Summary</h2>\n<table>\n";
    const auto& m = r.moments;
    row("input", esc(r.input + ": " + source_text(r)));
    row("size",
        std::to_string(r.width) + "x" + std::to_string(r.height) + ", " + esc(frames_text(r)));
    row("mean", fmt(m.mean));
    row("variance", fmt(m.variance) + " (sd " + fmt(std::sqrt(m.variance)) + ")");
    row("skewness / excess kurtosis", fmt(m.skewness, 4) + " / " + fmt(m.excess_kurtosis, 4));
    row("min / max", fmt(m.min) + " / " + fmt(m.max));
    const auto& p = r.periodogram;
    row("periodogram", "window " + p.window + " (" + (p.periodic ? "periodic" : "not periodic") +
                           ", wrap/interior step ratio " + fmt(p.wrap_ratio_x, 3) + ", " +
                           fmt(p.wrap_ratio_y, 3) + "); total power " + fmt(p.total_power) +
                           "; centroid |k| " + fmt(p.centroid, 4) + " cycles/px; anisotropy " +
                           fmt(p.anisotropy, 3) + " (axis " + fixed(p.orientation_deg, 1) +
                           "&deg;)");
    if (r.frames > 1) row("frame correlation", esc(correlation_text(r)));
    const auto& st = r.stationarity;
    if (st.available) {
        row("trend of frame variance", "slope " + fmt(st.trend.slope, 4) + " per frame, stderr " +
                                           fmt(st.trend.stderr_slope, 4) + ", t " +
                                           fixed(st.trend.t, 2));
        row("spectral drift", "max|z| " + fixed(st.drift.max_abs_z, 2) + " (independent frames), " +
                                  fixed(st.max_abs_z_corrected, 2) + " for " + fmt(st.q_eff, 3) +
                                  " independent frames per quarter");
        row("stationary", (st.verdict == "inconclusive" ? "<span class=\"na\">inconclusive</span>"
                                                        : verdict(st.stationary)) +
                              " &mdash; " + esc(stationarity_verdict(st)));
    } else {
        row("stationary", "<span class=\"na\">n/a</span> (" + esc(st.reason) + ")");
    }
    if (r.theory) {
        const auto& T = *r.theory;
        row("scene", esc(T.scene) + " (hash " + esc(T.hash) + "), zoom " + fmt(T.zoom));
        if (T.mapped)
            row("display mapping", "v &rarr; " + fmt(T.map_lo) + " + v (" + fmt(T.map_hi) +
                                       " &minus; " + fmt(T.map_lo) + "), " +
                                       fixed(100 * T.clipped_fraction, 3) + " % clipped");
        row("mean vs theory", fmt(m.mean) + " vs " + fmt(T.mean) + " &plusmn; " +
                                  fmt(T.sd_mean, 3) + ", z " + fixed(T.z_mean, 2) + ": agrees " +
                                  verdict(T.mean_agrees) + " (" + esc(z_text(T.z_mean, T.z_limit)) +
                                  ")");
        row("variance vs theory", fmt(m.variance) + " vs " + fmt(T.variance) + " &plusmn; " +
                                      fmt(T.sd_variance, 3) + ", z " + fixed(T.z_variance, 2) +
                                      ": agrees " + verdict(T.variance_agrees) + " (" +
                                      esc(z_text(T.z_variance, T.z_limit)) + ")");
        if (T.spectrum && T.spectrum->not_judged.empty())
            row("spectrum vs theory", "agrees " + verdict(T.spectrum->agrees) + " (" +
                                          esc(spectrum_threshold_text(*T.spectrum)) + ")");
        else
            row("spectrum vs theory", "agrees <span class=\"na\">n/a</span> (" +
                                          esc(T.spectrum ? T.spectrum->not_judged : T.no_spectrum) +
                                          ")");
    }
    for (const auto& n : r.notes) row("note", esc(n));
    o << "</table>\n<h2>Plots</h2>\n<p class=\"hint\">Hover over a point, bar or line for its "
         "values; the wheel zooms about the pointer, a drag pans, a double click goes back.</p>\n"
         "<div class=\"plots\">\n";
    for (const auto& spec : specs)
        o << "<figure class=\"plot\"><div class=\"chart\"></div>"
          << "<script type=\"application/json\" class=\"impulse-spec\">\n"
          << script_json(spec) << "\n</script></figure>\n";
    o << "</div>\n<script>\n" << chart_library << "\n</script>\n<script>\n" << kDrawPlots
      << "</script>\n</body>\n</html>\n";
    return o.str();
}


}  // namespace impulse::analysis
