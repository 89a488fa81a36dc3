// SPDX-License-Identifier: Apache-2.0
// `impulse analyze` output: the text report, JSON, and a self-contained HTML page whose plots
// are Vega specs with their data (report_charts.cpp) drawn by the chart library the page
// inlines (chart_library.cpp; design.md §6, "The report's plots drawn by Vega"); nothing is
// fetched. JSON through nlohmann-json.

#include "analysis/report.h"

#include "analysis/detail/report_charts.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
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

/// Text for HTML: & < > " escaped.
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

std::string to_html(const AnalysisResult& r, const std::string& chart_library) {
    const std::vector<std::string> specs = plot_specs(r);
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
          << spec << "\n</script></figure>\n";
    o << "</div>\n<script>\n" << chart_library << "\n</script>\n<script>\n" << draw_plots_script()
      << "</script>\n</body>\n</html>\n";
    return o.str();
}


}  // namespace impulse::analysis
