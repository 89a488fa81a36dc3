// SPDX-License-Identifier: Apache-2.0
// Sampling-error helpers of the theory comparison (analysis/theory.h).

#include "analysis/analysis.h"
#include "analysis/theory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "numeric/gaussian.h"

namespace impulse::analysis {

std::string format_number(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

double bonferroni_threshold(int m, double alpha) {
    return -numeric::normal_quantile_lower(alpha / (2.0 * std::max(1, m)));
}

double wilson_hilferty_z(double ratio, double shape) {
    const double v = 1.0 / (9.0 * shape);
    return (std::cbrt(std::max(ratio, 0.0)) - (1.0 - v)) / std::sqrt(v);
}

double effective_frames(size_t n, const std::vector<double>& r) {
    double f = 1.0;
    for (size_t l = 1; l < n && l < r.size(); ++l) f += 2.0 * (1.0 - double(l) / double(n)) * r[l];
    return std::clamp(double(n) / f, 1.0, double(n));
}

}  // namespace impulse::analysis
