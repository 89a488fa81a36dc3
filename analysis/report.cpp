// SPDX-License-Identifier: Apache-2.0
// `impulse analyze` output: the text report, JSON, and a self-contained HTML page whose plots
// are SVG drawn here (no scripts, no network). JSON through nlohmann-json.

#include "analysis/report.h"

#include <nlohmann/json.hpp>

#include <algorithm>
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
// SVG plots

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
    std::vector<Series> series;
    std::vector<Band> bands;
    std::vector<HLine> hlines;
};

constexpr double kW = 680, kH = 320, kL = 78, kR = 20, kT = 34, kB = 48;

std::vector<double> linear_ticks(double lo, double hi) {
    const double span = hi - lo;
    const double raw = span / 6.0;
    const double mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * mag >= raw) {
            step = m * mag;
            break;
        }
    std::vector<double> t;
    for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step)
        t.push_back(std::abs(v) < 1e-12 * span ? 0.0 : v);
    return t;
}

/// A plot's data range in axis units (log10 on a log axis), padded, and its map to SVG pixels.
struct PlotArea {
    static constexpr double pw = kW - kL - kR, ph = kH - kT - kB;  // the frame's size
    bool logx = false, logy = false;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;

    double X(double x) const { return kL + ((logx ? std::log10(x) : x) - x0) / (x1 - x0) * pw; }
    double Y(double y) const {
        double v = logy ? std::log10(y) : y;
        v = std::clamp(v, y0, y1);
        return kT + (y1 - v) / (y1 - y0) * ph;
    }
    /// Whether (x, y) can be drawn: finite, and positive on a log axis.
    bool ok(double x, double y) const {
        return std::isfinite(x) && std::isfinite(y) && !(logx && x <= 0) && !(logy && y <= 0);
    }
};

/// The range of everything drawn (non-positive values are left out on log axes).
PlotArea plot_area(const Plot& p) {
    PlotArea a;
    a.logx = p.logx, a.logy = p.logy;
    double &x0 = a.x0, &x1 = a.x1, &y0 = a.y0, &y1 = a.y1;
    const auto take = [&](double x, double y) {
        if (!std::isfinite(x) || !std::isfinite(y)) return;
        if (p.logx && x <= 0) return;
        if (p.logy && y <= 0) return;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    };
    for (const auto& s : p.series)
        for (size_t i = 0; i < s.x.size(); ++i) take(s.x[i], s.y[i]);
    for (const auto& b : p.bands)
        for (size_t i = 0; i < b.x.size(); ++i) take(b.x[i], b.lo[i]), take(b.x[i], b.hi[i]);
    for (const auto& h : p.hlines)
        if (std::isfinite(x0)) take(x0, h.y);
    if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
    if (p.logx) x0 = std::log10(x0), x1 = std::log10(x1);
    if (p.logy) {
        y0 = std::log10(y0), y1 = std::log10(y1);
        y0 = std::max(y0, y1 - 12.0);  // at most 12 decades
    }
    if (x1 <= x0) x0 -= 0.5, x1 += 0.5;
    if (y1 <= y0) y0 -= 0.5 * std::max(1.0, std::abs(y0)), y1 += 0.5 * std::max(1.0, std::abs(y1));
    const double pad = 0.04 * (y1 - y0);
    y0 -= pad, y1 += pad;
    return a;
}

/// Tick values and labels over [lo, hi] in axis units: decades on a log axis (at most about
/// `decades` of them labelled), else round linear steps.
std::vector<std::pair<double, std::string>> axis_ticks(double lo, double hi, bool log,
                                                       int decades) {
    std::vector<std::pair<double, std::string>> t;
    if (log) {
        const int step = std::max(1, int(std::ceil((hi - lo) / decades)));
        for (int d = int(std::ceil(lo)); d <= int(std::floor(hi)); d += step)
            t.push_back({std::pow(10.0, d), "1e" + std::to_string(d)});
        if (t.size() < 2)
            for (double v : linear_ticks(std::pow(10.0, lo), std::pow(10.0, hi)))
                if (v > 0) t.push_back({v, fmt(v, 3)});
    } else {
        for (double v : linear_ticks(lo, hi)) t.push_back({v, fmt(v, 4)});
    }
    return t;
}

/// The SVG header, the title, the grid with its tick labels, the frame and the axis labels.
void draw_axes(std::ostream& o, const Plot& p, const PlotArea& a) {
    constexpr double pw = PlotArea::pw, ph = PlotArea::ph;
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << kW << ' ' << kH
      << "\" width=\"" << kW << "\" height=\"" << kH << "\" role=\"img\">\n";
    o << "<title>" << esc(p.title) << "</title>\n";
    o << "<rect x=\"0\" y=\"0\" width=\"" << kW << "\" height=\"" << kH << "\" fill=\"#fff\"/>\n";
    o << "<text x=\"" << kW / 2 << "\" y=\"20\" text-anchor=\"middle\" class=\"pt\">"
      << esc(p.title) << "</text>\n";
    o << "<g class=\"ax\">\n";
    for (const auto& [v, label] : axis_ticks(a.x0, a.x1, p.logx, 8)) {
        const double x = a.X(v);
        if (x < kL - 0.5 || x > kW - kR + 0.5) continue;
        o << "<line x1=\"" << x << "\" y1=\"" << kT << "\" x2=\"" << x << "\" y2=\"" << kT + ph
          << "\" class=\"grid\"/><text x=\"" << x << "\" y=\"" << kT + ph + 16
          << "\" text-anchor=\"middle\">" << esc(label) << "</text>\n";
    }
    for (const auto& [v, label] : axis_ticks(a.y0, a.y1, p.logy, 7)) {
        const double y = a.Y(v);
        if ((p.logy ? std::log10(v) : v) < a.y0 || (p.logy ? std::log10(v) : v) > a.y1) continue;
        o << "<line x1=\"" << kL << "\" y1=\"" << y << "\" x2=\"" << kL + pw << "\" y2=\"" << y
          << "\" class=\"grid\"/><text x=\"" << kL - 6 << "\" y=\"" << y + 4
          << "\" text-anchor=\"end\">" << esc(label) << "</text>\n";
    }
    o << "<rect x=\"" << kL << "\" y=\"" << kT << "\" width=\"" << pw << "\" height=\"" << ph
      << "\" fill=\"none\" stroke=\"#333\"/>\n";
    o << "<text x=\"" << kL + pw / 2 << "\" y=\"" << kH - 8 << "\" text-anchor=\"middle\">"
      << esc(p.xlabel) << "</text>\n";
    o << "<text transform=\"translate(16," << kT + ph / 2
      << ") rotate(-90)\" text-anchor=\"middle\">" << esc(p.ylabel) << "</text>\n</g>\n";
}

/// A shaded band between lo and hi (the hi edge left to right, the lo edge back).
void draw_band(std::ostream& o, const Band& b, const PlotArea& a) {
    std::ostringstream pts;
    size_t used = 0;
    for (size_t i = 0; i < b.x.size(); ++i)
        if (a.ok(b.x[i], b.hi[i])) pts << a.X(b.x[i]) << ',' << a.Y(b.hi[i]) << ' ', ++used;
    for (size_t i = b.x.size(); i-- > 0;)
        if (a.ok(b.x[i], b.lo[i])) pts << a.X(b.x[i]) << ',' << a.Y(b.lo[i]) << ' ', ++used;
    if (used >= 3)
        o << "<polygon points=\"" << pts.str() << "\" fill=\"" << b.color
          << "\" fill-opacity=\"0.15\" stroke=\"none\"/>\n";
}

/// Bars from the axis (or the bottom of a log axis) to y[i], over [x[i], x[i + 1]].
void draw_bars(std::ostream& o, const Series& s, const PlotArea& a) {
    for (size_t i = 0; i + 1 < s.x.size(); ++i) {
        if (!a.ok(s.x[i], s.y[i])) continue;
        const double xa = a.X(s.x[i]), xb = a.X(s.x[i + 1]);
        const double yt = a.Y(s.y[i]),
                     yb = a.Y(a.logy ? std::pow(10.0, a.y0) : std::max(a.y0, 0.0));
        o << "<rect x=\"" << xa << "\" y=\"" << std::min(yt, yb) << "\" width=\""
          << std::max(0.0, xb - xa - 0.5) << "\" height=\"" << std::abs(yb - yt) << "\" fill=\""
          << s.color << "\" fill-opacity=\"0.75\"/>\n";
    }
}

void draw_points(std::ostream& o, const Series& s, const PlotArea& a) {
    o << "<g fill=\"" << s.color << "\">";
    for (size_t i = 0; i < s.x.size(); ++i)
        if (a.ok(s.x[i], s.y[i]))
            o << "<circle cx=\"" << a.X(s.x[i]) << "\" cy=\"" << a.Y(s.y[i]) << "\" r=\"1.8\"/>";
    o << "</g>\n";
}

/// A polyline, broken where a value cannot be drawn.
void draw_line(std::ostream& o, const Series& s, const PlotArea& a) {
    std::ostringstream pts;
    size_t count = 0;
    const auto flush = [&]() {
        if (count >= 2)
            o << "<polyline points=\"" << pts.str() << "\" fill=\"none\" stroke=\"" << s.color
              << "\" stroke-width=\"1.6\"" << (s.dashed ? " stroke-dasharray=\"6,4\"" : "")
              << "/>\n";
        pts.str("");
        count = 0;
    };
    for (size_t i = 0; i < s.x.size(); ++i) {
        if (!a.ok(s.x[i], s.y[i])) {
            flush();
            continue;
        }
        pts << a.X(s.x[i]) << ',' << a.Y(s.y[i]) << ' ';
        ++count;
    }
    flush();
}

/// Bands, reference lines, series.
void draw_data(std::ostream& o, const Plot& p, const PlotArea& a) {
    for (const auto& b : p.bands) draw_band(o, b, a);
    for (const auto& h : p.hlines) {
        if (p.logy && h.y <= 0) continue;
        const double y = a.Y(h.y);
        o << "<line x1=\"" << kL << "\" y1=\"" << y << "\" x2=\"" << kL + PlotArea::pw << "\" y2=\""
          << y << "\" stroke=\"" << h.color << "\" stroke-dasharray=\"5,4\"/>\n";
    }
    for (const auto& s : p.series) {
        if (s.kind == Series::Bars)
            draw_bars(o, s, a);
        else if (s.kind == Series::Points)
            draw_points(o, s, a);
        else
            draw_line(o, s, a);
    }
}

/// Legend, top right on a translucent panel sized to its longest label (~6.2 px a character).
void draw_legend(std::ostream& o, const Plot& p) {
    size_t longest = 0, entries = 0;
    const auto measure = [&](const std::string& label) {
        if (!label.empty()) longest = std::max(longest, label.size()), ++entries;
    };
    for (const auto& s : p.series) measure(s.label);
    for (const auto& b : p.bands) measure(b.label);
    for (const auto& h : p.hlines) measure(h.label);
    const double lw = 34 + 6.2 * double(longest);
    const double lx = kL + PlotArea::pw - lw;
    if (entries)
        o << "<rect x=\"" << lx - 4 << "\" y=\"" << kT + 3 << "\" width=\"" << lw << "\" height=\""
          << 15 * entries + 6 << "\" fill=\"#fff\" fill-opacity=\"0.85\"/>\n";
    double ly = kT + 14;
    const auto legend = [&](const std::string& label, const std::string& color, bool box) {
        if (label.empty()) return;
        if (box)
            o << "<rect x=\"" << lx << "\" y=\"" << ly - 8 << "\" width=\"18\" height=\"9\" fill=\""
              << color << "\" fill-opacity=\"0.3\"/>";
        else
            o << "<line x1=\"" << lx << "\" y1=\"" << ly - 4 << "\" x2=\"" << lx + 18 << "\" y2=\""
              << ly - 4 << "\" stroke=\"" << color << "\" stroke-width=\"2.5\"/>";
        o << "<text x=\"" << lx + 24 << "\" y=\"" << ly << "\" class=\"lg\">" << esc(label)
          << "</text>\n";
        ly += 15;
    };
    for (const auto& s : p.series) legend(s.label, s.color, s.kind == Series::Bars);
    for (const auto& b : p.bands) legend(b.label, b.color, true);
    for (const auto& h : p.hlines) legend(h.label, h.color, false);
}

std::string svg_plot(const Plot& p) {
    const PlotArea a = plot_area(p);
    std::ostringstream o;
    draw_axes(o, p, a);
    draw_data(o, p, a);
    draw_legend(o, p);
    o << "</svg>\n";
    return o.str();
}

/// Viridis-like colour ramp on [0, 1] (five anchors of matplotlib's viridis, linear between).
std::string ramp(double t) {
    static const double a[5][3] = {
        {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
    t = std::clamp(t, 0.0, 1.0) * 4.0;
    const int i = std::min(3, int(t));
    const double f = t - i;
    char buf[16];
    std::snprintf(buf, sizeof buf, "#%02x%02x%02x", int(a[i][0] + f * (a[i + 1][0] - a[i][0])),
                  int(a[i][1] + f * (a[i + 1][1] - a[i][1])),
                  int(a[i][2] + f * (a[i + 1][2] - a[i][2])));
    return buf;
}

std::string svg_heatmap(const PeriodogramSummary& s, int w, int h) {
    const std::string title = "2-D periodogram, log10 power (centred; window: " + s.window + ")";
    double hi = -INFINITY;
    for (double v : s.heat)
        if (std::isfinite(v)) hi = std::max(hi, v);
    const double lo = std::isfinite(hi) ? hi - 8.0 : 0.0;
    const double side = 300, x0 = 150, y0 = 34;
    const double cw = side / s.heat_width, ch = side / s.heat_height;
    std::ostringstream o;
    o << "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 " << kW << " 380\" width=\"" << kW
      << "\" height=\"380\" role=\"img\">\n<title>" << esc(title) << "</title>\n";
    o << "<rect x=\"0\" y=\"0\" width=\"" << kW << "\" height=\"380\" fill=\"#fff\"/>\n";
    o << "<text x=\"" << kW / 2 << "\" y=\"20\" text-anchor=\"middle\" class=\"pt\">" << esc(title)
      << "</text>\n<g shape-rendering=\"crispEdges\">";
    for (int r = 0; r < s.heat_height; ++r)
        for (int c = 0; c < s.heat_width; ++c) {
            const double v = s.heat[size_t(r) * s.heat_width + c];
            o << "<rect x=\"" << x0 + c * cw << "\" y=\"" << y0 + r * ch << "\" width=\""
              << cw + 0.05 << "\" height=\"" << ch + 0.05 << "\" fill=\""
              << (std::isfinite(v) ? ramp((v - lo) / (hi - lo)) : std::string("#000")) << "\"/>";
        }
    o << "</g>\n<g class=\"ax\">";
    o << "<rect x=\"" << x0 << "\" y=\"" << y0 << "\" width=\"" << side << "\" height=\"" << side
      << "\" fill=\"none\" stroke=\"#333\"/>";
    // kx from -0.5 (left) to 0.5, ky from -0.5 (top) to 0.5: display row r holds ky index r - h/2.
    for (double f : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
        const double x = x0 + (f + 0.5) * side, y = y0 + (f + 0.5) * side;
        o << "<text x=\"" << x << "\" y=\"" << y0 + side + 16 << "\" text-anchor=\"middle\">" << f
          << "</text><text x=\"" << x0 - 6 << "\" y=\"" << y + 4 << "\" text-anchor=\"end\">" << f
          << "</text>";
    }
    o << "<text x=\"" << x0 + side / 2 << "\" y=\"" << y0 + side + 34
      << "\" text-anchor=\"middle\">kx (cycles/pixel)</text>";
    o << "<text transform=\"translate(" << x0 - 48 << "," << y0 + side / 2
      << ") rotate(-90)\" text-anchor=\"middle\">ky (cycles/pixel)</text>";
    // Colour bar.
    const double bx = x0 + side + 40;
    for (int i = 0; i < 50; ++i)
        o << "<rect x=\"" << bx << "\" y=\"" << y0 + side - (i + 1) * side / 50
          << "\" width=\"16\" height=\"" << side / 50 + 0.2 << "\" fill=\"" << ramp((i + 0.5) / 50)
          << "\"/>";
    for (int d = 0; d <= 8; d += 2)
        o << "<text x=\"" << bx + 22 << "\" y=\"" << y0 + side - d / 8.0 * side + 4 << "\">"
          << fmt(lo + d, 3) << "</text>";
    o << "<text x=\"" << bx + 70 << "\" y=\"" << y0 + 12 << "\">" << w << "x" << h
      << " bins</text></g>\n</svg>\n";
    return o.str();
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
std::string histogram_plot(const AnalysisResult& r) {
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
    return svg_plot(p);
}

std::string radial_spectrum_plot(const AnalysisResult& r) {
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
    return svg_plot(p);
}

/// z per annulus with the Bonferroni limits +-threshold; `title` and `ylabel` name the test.
std::string z_plot(const std::string& title, const std::string& ylabel, Series s,
                   double threshold) {
    Plot p = titled(title, "frequency |k| (cycles/pixel)", ylabel);
    s.kind = Series::Points;
    p.series.push_back(s);
    p.hlines.push_back({threshold, "Bonferroni limit +-" + fixed(threshold, 2), "#777"});
    p.hlines.push_back({-threshold, "", "#777"});
    return svg_plot(p);
}

std::string spectrum_z_plot(const AnalysisResult& r) {
    const SpectrumTheory& S = *r.theory->spectrum;
    Series s;
    s.label = "z";
    for (size_t b = 0; b < S.z.size(); ++b)
        if (std::isfinite(S.z[b])) s.x.push_back(r.spectrum.frequency[b]), s.y.push_back(S.z[b]);
    return z_plot("Spectrum against theory: z per annulus", "z (Wilson-Hilferty)", s, S.threshold);
}

std::string autocovariance_plot(const AnalysisResult& r) {
    const auto& T = r.theory;
    Plot p = titled("Radial autocovariance", "lag (pixels)", "covariance (value^2)");
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
    return svg_plot(p);
}

/// One statistic per frame from frame `from` on, with the theory +- 2 sd of one frame.
std::string per_frame_plot(const AnalysisResult& r, const std::string& title,
                           const std::string& ylabel, double (*get)(const FrameStats&),
                           double theory, double sd, size_t from) {
    const auto x = iota_from(size_t(r.frames), double(r.first_frame));
    Plot p = titled(title, "frame", ylabel);
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
    return svg_plot(p);
}

/// The per-frame mean, variance and difference variance (a sequence of frames).
void add_per_frame_plots(const AnalysisResult& r, std::vector<std::string>& out) {
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

std::string drift_plot(const Stationarity& st) {
    Series s;
    s.label = "z, corrected";
    s.x = st.drift.frequency;
    s.y = st.z_corrected;
    return z_plot("Spectral drift, first quarter against last: z per annulus",
                  "z (correlation-corrected)", s, st.z_threshold);
}

/// The report's plots, in order.
std::vector<std::string> plots(const AnalysisResult& r) {
    std::vector<std::string> out;
    out.push_back(histogram_plot(r));
    out.push_back(svg_heatmap(r.periodogram, r.width, r.height));
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

std::string to_html(const AnalysisResult& r) {
    const std::vector<std::string> svgs = plots(r);
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"impulse-plots\" content=\"" << svgs.size() << "\">\n"
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
      << "figure{margin:0;border:1px solid #ddd;background:#fff}\n"
      << "svg text{font-size:11px;fill:#333} svg text.pt{font-size:13px;font-weight:600}"
         " svg text.lg{font-size:11px} svg .grid{stroke:#eee}\n"
      << "</style>\n</head>\n<body>\n";
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
    o << "</table>\n<h2>Plots</h2>\n<div class=\"plots\">\n";
    for (const auto& s : svgs) o << "<figure>\n" << s << "</figure>\n";
    o << "</div>\n</body>\n</html>\n";
    return o.str();
}


}  // namespace impulse::analysis
