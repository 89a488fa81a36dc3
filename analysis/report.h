// SPDX-License-Identifier: Apache-2.0
#pragma once
// The reports of an analysis (analysis/analyze.h): text, JSON (nlohmann-json) and a
// self-contained HTML page whose plots Vega draws (the chart library inlined, analysis/chart_library.cpp).

#include <string>

#include "analysis/analyze.h"

namespace impulse::analysis {

/// Human-readable report (what `impulse analyze` prints by default).
std::string to_text(const AnalysisResult& result);
/// One JSON object with every number of the result (non-finite values as null).
std::string to_json(const AnalysisResult& result);
/// Self-contained HTML page: the summary table and the plots as Vega specs with their data,
/// drawn in the browser by `chart_library` (load_chart_library()), inlined once; nothing is
/// fetched. The plots show values on hover, zoom with the wheel, pan with a drag.
std::string to_html(const AnalysisResult& result, const std::string& chart_library);
/// Number of plots `to_html` writes for this result (one <figure class="plot"> each).
int html_plot_count(const AnalysisResult& result);

/// The folder the chart library is read from: $IMPULSE_VEGA_DIR when set, else the one
/// configured at build time (CMake's IMPULSE_VEGA_DIR, Debian's /usr/share/javascript/vega).
std::string chart_library_dir();
/// The chart library's script for `to_html`: Debian's libjs-vega modules from
/// chart_library_dir(), under a small loader. Throws IoError (one line naming the file and the
/// package libjs-vega) when a module is missing or empty.
std::string load_chart_library();

}  // namespace impulse::analysis
