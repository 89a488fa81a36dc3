// SPDX-License-Identifier: Apache-2.0
#pragma once
// The reports of an analysis (analysis/analyze.h): text, JSON (nlohmann-json) and a
// self-contained HTML page with SVG plots.

#include <string>

#include "analysis/analyze.h"

namespace impulse::analysis {

/// Human-readable report (what `impulse analyze` prints by default).
std::string to_text(const AnalysisResult& result);
/// One JSON object with every number of the result (non-finite values as null).
std::string to_json(const AnalysisResult& result);
/// Self-contained HTML page (inline CSS and SVG, no scripts): summary table and plots.
std::string to_html(const AnalysisResult& result);
/// Number of <svg> plots `to_html` draws for this result.
int html_plot_count(const AnalysisResult& result);

}  // namespace impulse::analysis
