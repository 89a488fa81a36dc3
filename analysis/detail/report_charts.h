// SPDX-License-Identifier: Apache-2.0
#pragma once
// The HTML report's plots (report_charts.cpp), for report.cpp.

#include <string>
#include <vector>

#include "analysis/analyze.h"

namespace impulse::analysis {

/// The report's plots in order, each a Vega spec with its data as JSON text that can stand
/// inside a <script> element; html_plot_count(r) of them.
std::vector<std::string> plot_specs(const AnalysisResult& r);

/// The page's script: draws each <figure class="plot">'s spec (its <script class="impulse-spec">)
/// into its <div class="chart"> with the inlined library, shows hovered values in a <div
/// class="tip">, and sets <body data-ready="1"> when all are drawn or data-error to what failed.
const char* draw_plots_script();

}  // namespace impulse::analysis
