// SPDX-License-Identifier: Apache-2.0
// Structure function, generalised Hurst exponent (Kaplan & Kuo 1996 eq. 21) with its sampling
// band over realizations, per-pixel variance maps (their Figs. 1-2) and 1-D profiles.

#include <cmath>
#include <limits>

#include "analysis/analysis.h"

namespace impulse::analysis {
namespace {

// Mean of (B(p + (dx, dy)) - B(p))^2 over the pairs inside the image, in double.
double mean_square_increment(const Image& im, int dx, int dy) {
    const int w = im.width - dx, h = im.height - dy;
    if (w <= 0 || h <= 0) return std::numeric_limits<double>::quiet_NaN();
    double sum = 0.0;
    for (int y = 0; y < h; ++y) {
        const float* a = im.data.data() + size_t(y) * im.width;
        const float* b = im.data.data() + size_t(y + dy) * im.width + dx;
        double row = 0.0;
        for (int x = 0; x < w; ++x) {
            const double d = double(b[x]) - double(a[x]);
            row += d * d;
        }
        sum += row;
    }
    return sum / (double(w) * h);
}

double sd(const std::vector<double>& v) {
    if (v.size() < 2) return 0.0;
    double m = 0.0, s = 0.0;
    for (double x : v) m += x;
    m /= double(v.size());
    for (double x : v) s += (x - m) * (x - m);
    return std::sqrt(s / double(v.size() - 1));
}

}  // namespace

std::vector<int> dyadic_lags(int max_lag) {
    std::vector<int> lags;
    for (int d = 1; d <= max_lag && d > 0; d *= 2) lags.push_back(d);
    return lags;
}

StructureFunction structure_function(const Image& image, std::span<const int> lags) {
    StructureFunction s;
    s.lags.assign(lags.begin(), lags.end());
    for (int d : lags) {
        s.fx.push_back(mean_square_increment(image, d, 0));
        s.fy.push_back(mean_square_increment(image, 0, d));
        s.diagonal.push_back(mean_square_increment(image, d, d));
        s.f.push_back(0.5 * (s.fx.back() + s.fy.back()));
    }
    return s;
}

std::vector<double> generalized_hurst(std::span<const double> f) {
    std::vector<double> H;
    for (size_t s = 0; s + 1 < f.size(); ++s)
        H.push_back(f[s] > 0 && f[s + 1] > 0 ? 0.5 * std::log2(f[s + 1] / f[s])  // eq. 21
                                             : std::numeric_limits<double>::quiet_NaN());
    return H;
}

void StructureAccumulator::add(const Image& image) {
    if (m_lags.empty()) {
        const int limit = std::min(image.width, image.height) - 1;
        m_lags = dyadic_lags(std::min(limit, 1 << std::min(m_max_s + 1, 30)));
    }
    m_each.push_back(structure_function(image, m_lags));
}

StructureSummary StructureAccumulator::summary() const {
    StructureSummary r;
    r.lags = m_lags;
    r.realizations = int(m_each.size());
    if (m_each.empty()) return r;
    const size_t L = m_lags.size();
    const double n = double(m_each.size());
    r.fx.assign(L, 0.0), r.fy.assign(L, 0.0), r.diagonal.assign(L, 0.0), r.f.assign(L, 0.0);
    for (const auto& e : m_each)
        for (size_t i = 0; i < L; ++i) {
            r.fx[i] += e.fx[i] / n, r.fy[i] += e.fy[i] / n;
            r.diagonal[i] += e.diagonal[i] / n, r.f[i] += e.f[i] / n;
        }
    r.hurst = generalized_hurst(r.f);
    r.hurst_x = generalized_hurst(r.fx);
    r.hurst_y = generalized_hurst(r.fy);
    r.hurst_diagonal = generalized_hurst(r.diagonal);
    // Band: the spread of the per-realization H(s) (the delta method's linearisation of eq. 21
    // about the pooled f: the pooled H(s) and the mean per-realization H(s) agree to first order).
    for (size_t s = 0; s + 1 < L; ++s) {
        std::vector<double> hs;
        for (const auto& e : m_each) hs.push_back(0.5 * std::log2(e.f[s + 1] / e.f[s]));
        r.hurst_stderr.push_back(sd(hs) / std::sqrt(n));
    }
    return r;
}

void PixelVariance::add(const Image& image) {
    if (m_n == 0) {
        m_w = image.width, m_h = image.height;
        m_sum.assign(image.data.size(), 0.0);
        m_sum2.assign(image.data.size(), 0.0);
    }
    for (size_t i = 0; i < m_sum.size(); ++i) {
        m_sum[i] += image.data[i];
        m_sum2[i] += double(image.data[i]) * image.data[i];
    }
    ++m_n;
}

Image PixelVariance::variance() const {
    Image v{m_w, m_h, std::vector<float>(m_sum.size())};
    const double n = m_n;
    for (size_t i = 0; i < m_sum.size(); ++i)
        v.data[i] = n > 1 ? float((m_sum2[i] - m_sum[i] * m_sum[i] / n) / (n - 1)) : 0.0f;
    return v;
}

std::vector<double> profile(const Image& image, bool along_x, int index) {
    std::vector<double> p;
    if (along_x)
        for (int x = 0; x < image.width; ++x) p.push_back(image.at(x, index));
    else
        for (int y = 0; y < image.height; ++y) p.push_back(image.at(index, y));
    return p;
}

}  // namespace impulse::analysis
