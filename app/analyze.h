// SPDX-License-Identifier: Apache-2.0
#pragma once
// `impulse analyze` on the command line: read a texture (one image, an image sequence or a
// video) and analyse it with analysis/analyze.h; print or write the reports of
// analysis/report.h. The analysis types and calls are re-exported here for the CLI's callers.

#include "analysis/analyze.h"
#include "analysis/report.h"

namespace impulse::app {

using analysis::AnalysisResult;
using analysis::AnalyzeOptions;
using analysis::analyze_frames;
using analysis::html_plot_count;
using analysis::load_chart_library;
using analysis::PeriodogramSummary;
using analysis::SpectrumTheory;
using analysis::Stationarity;
using analysis::TheoryComparison;
using analysis::to_html;
using analysis::to_json;
using analysis::to_text;

/// Reads the input and analyses it; with options.scene also compares with the scene's theory.
/// Deterministic. Throws IoError (missing or unreadable file, naming it), ValueError (unknown
/// input type, bad --frames, frames of different sizes) or SceneError.
AnalysisResult analyze_input(const AnalyzeOptions& options);

/// `impulse analyze`: analyse, print text or JSON, write the report atomically.
int run_analyze(const AnalyzeOptions& options);

}  // namespace impulse::app
