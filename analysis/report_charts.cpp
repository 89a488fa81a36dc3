// SPDX-License-Identifier: Apache-2.0
// The HTML report's plots (design.md §6, "The report's plots drawn by Vega"): each one's data
// and a Vega spec with zoomable axes, tooltips and a legend, and the page's script that draws
// them with the Vega modules of Debian's libjs-vega, which the page inlines
// (analysis/chart_library.cpp). The text, JSON and page around them are in report.cpp.

#include "analysis/detail/report_charts.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <utility>

namespace impulse::analysis {
namespace {

using Json = nlohmann::ordered_json;

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
    char limit[64];
    std::snprintf(limit, sizeof limit, "Bonferroni limit +-%.2f", threshold);
    p.hlines.push_back({threshold, limit, "#777"});
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

std::vector<std::string> plot_specs(const AnalysisResult& r) {
    std::vector<std::string> specs;
    for (const Json& spec : plots(r)) specs.push_back(script_json(spec));
    return specs;
}

const char* draw_plots_script() { return kDrawPlots; }

}  // namespace impulse::analysis
