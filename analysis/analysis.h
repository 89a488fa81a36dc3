// SPDX-License-Identifier: Apache-2.0
#pragma once
// impulse::analysis — estimators that check a texture against theory: moments, histogram,
// periodogram (2-D and radially averaged), autocorrelation, per-frame and stationarity
// statistics. Depends on FFTW only; knows nothing of kernels, sim or render.

#include "analysis/analyze.h"     // frames of a texture measured, compared with a theory
#include "analysis/estimators.h"  // moments, histogram, periodogram, autocorrelation
#include "analysis/report.h"      // text, JSON and HTML reports
#include "analysis/structure.h"   // structure function, generalised Hurst exponent
#include "analysis/theory.h"      // what the analysis needs from a closed-form theory
