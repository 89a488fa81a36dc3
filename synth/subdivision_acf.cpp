// SPDX-License-Identifier: Apache-2.0
// Autocorrelations for generalized stochastic subdivision: the kernels library's named models,
// expressions and tables, made anisotropic by stretching or by a separable product (Lewis 1987
// §6.2), and the estimate from data (Lewis 1987 eq. 15).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>

#include "kernels/spectral.h"
#include "synth/subdivision.h"
#include "numeric/errors.h"

namespace impulse::synth {
namespace {

namespace K = impulse::kernels;

std::string num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

double parse_param(const std::string& key, const std::string& value) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || end != value.c_str() + value.size() || !std::isfinite(v))
        throw ValueError("--param " + key + "=" + value + ": expected a finite number");
    return v;
}

/// The keys each source reads; the others are refused (a typo must not pass silently).
std::vector<std::string> model_keys(K::SpectralModel m) {
    switch (m) {
        case K::SpectralModel::Markaussian:
            return {"variance", "length", "exponent"};
        case K::SpectralModel::Matern:
            return {"variance", "length", "nu"};
        case K::SpectralModel::OscillatoryMarkov:
        case K::SpectralModel::OscillatoryGaussian:
            return {"variance", "length", "omega"};
        // Defined by a spectrum (frequencies in cycles per output sample), band-limited to
        // `nyquist` (default 0.5, the finest level's).
        case K::SpectralModel::Lorentzian:
            return {"variance", "k0", "nyquist"};
        case K::SpectralModel::Bandpass:
            return {"variance", "f0", "width", "nyquist"};
        case K::SpectralModel::Power:
            return {"variance", "slope", "k_low", "k_high", "nyquist"};
        default:
            return {"variance", "length"};
    }
}

struct Anisotropy {
    double aspect = 1, angle = 0;  // angle in radians
    bool separable = false;
};

/// R(x, y) from a radial profile R(r): swept (isotropic, Lewis 1987 eq. 13), stretched along
/// `angle`, or separable R(u) R(v) / R(0) in the rotated frame. A linear change of variables
/// and a product of non-negative definite functions stay non-negative definite.
Acf from_profile(std::function<double(double)> profile, const std::string& name,
                 const Anisotropy& an) {
    const double c = std::cos(an.angle), s = std::sin(an.angle);
    const double r0 = profile(0.0);
    Acf acf;
    acf.name = name;
    if (an.separable)
        acf.R = [profile, c, s, r0, an](double x, double y) {
            const double u = c * x + s * y, v = -s * x + c * y;
            return profile(std::abs(u) / an.aspect) * profile(std::abs(v)) / r0;
        };
    else if (an.aspect == 1)
        acf.R = [profile](double x, double y) { return profile(std::hypot(x, y)); };
    else
        acf.R = [profile, c, s, an](double x, double y) {
            const double u = c * x + s * y, v = -s * x + c * y;
            return profile(std::hypot(u / an.aspect, v));
        };
    return acf;
}

}  // namespace

Acf make_acf(const std::string& model, const std::vector<AcfParam>& params) {
    std::map<std::string, std::string> given;
    for (const auto& [k, v] : params) {
        if (given.count(k)) throw ValueError("--param " + k + ": given twice");
        given[k] = v;
    }
    std::vector<std::string> keys = {"aspect", "angle", "separable"};
    Anisotropy an;
    std::function<double(double)> profile;
    std::string name = model;
    std::shared_ptr<const K::Expression> xy;  // an expression of x and y
    if (model == "expression") {
        keys.push_back("expr");
        if (!given.count("expr"))
            throw ValueError(
                "--acf expression: expected --param expr=TEXT (R of r, or of x and y)");
        auto e = std::make_shared<const K::Expression>(given["expr"],
                                                       std::vector<std::string>{"r", "x", "y"});
        name = "expression \"" + given["expr"] + "\"";
        if (e->uses("x") || e->uses("y"))
            xy = e;
        else
            profile = [e](double r) {
                const double v[3] = {r, 0, 0};
                return e->evaluate(v);
            };
    } else if (model == "table") {
        keys.push_back("file");
        if (!given.count("file"))
            throw ValueError("--acf table: expected --param file=PATH (CSV rows r,R)");
        profile = K::table_autocorrelation(given["file"]).function;
        name = given["file"];
    } else {
        const auto m = K::spectral_model_from_string(model);
        if (!m) {
            std::string list;
            for (auto n : K::kSpectralModelNames) list += std::string(n) + ", ";
            throw ValueError("--acf " + model + ": unknown model: expected one of " + list +
                             "expression, table");
        }
        K::ModelParams mp;
        mp.model = *m;
        double nyquist = 0.5;
        for (const auto& k : model_keys(*m)) {
            keys.push_back(k);
            if (!given.count(k)) continue;
            const double v = parse_param(k, given[k]);
            if (k == "variance") mp.variance = v;
            if (k == "length") mp.length = v;
            if (k == "exponent") mp.exponent = v;
            if (k == "nu") mp.nu = v;
            if (k == "omega") mp.omega = v;
            if (k == "k0") mp.k0 = v;
            if (k == "f0") mp.f0 = v;
            if (k == "width") mp.width = v;
            if (k == "slope") mp.slope = v;
            if (k == "k_low") mp.k_low = v;
            if (k == "k_high") mp.k_high = v;
            if (k == "nyquist") nyquist = v;
        }
        // validates (ValueError); a spectrum-defined model through its inverse transform
        profile = K::defined_by_autocorrelation(*m)
                      ? K::model_autocorrelation(mp).function
                      : K::autocorrelation_of_spectrum(K::model_spectrum(mp, nyquist), nyquist).function;
    }
    for (const auto& [k, v] : given)
        if (std::find(keys.begin(), keys.end(), k) == keys.end()) {
            std::string list;
            for (const auto& s : keys) list += (list.empty() ? "" : ", ") + s;
            throw ValueError("--param " + k + "=" + v + ": unknown key for --acf " + model +
                             " (expected " + list + ")");
        }
    if (given.count("aspect")) {
        an.aspect = parse_param("aspect", given["aspect"]);
        if (!(an.aspect >= 1))
            throw ValueError("--param aspect=" + given["aspect"] +
                             ": expected >= 1 (the correlation length along `angle` over the one "
                             "across it)");
    }
    if (given.count("angle"))
        an.angle = parse_param("angle", given["angle"]) * std::numbers::pi / 180;
    if (given.count("separable")) {
        const double s = parse_param("separable", given["separable"]);
        if (s != 0 && s != 1)
            throw ValueError("--param separable=" + given["separable"] + ": expected 0 or 1");
        an.separable = s == 1;
    }
    if (xy) {
        if (given.count("aspect") || given.count("angle") || given.count("separable"))
            throw ValueError(
                "--param aspect/angle/separable: an expression of x and y is "
                "already 2-D: write the anisotropy into it");
        Acf acf;
        acf.name = name;
        acf.R = [xy](double x, double y) {
            const double v[3] = {std::hypot(x, y), x, y};
            return xy->evaluate(v);
        };
        return acf;
    }
    if (an.aspect != 1 || an.separable)
        name += " (aspect " + num(an.aspect) + ", angle " + num(an.angle * 180 / std::numbers::pi) +
                (an.separable ? ", separable)" : ")");
    return from_profile(profile, name, an);
}

// ---------------------------------------------------------------------------------------------
// Estimate from data (Lewis 1987 eq. 15)

namespace {

/// Lewis 1987 eq. 15: R^(r, c) = 1 / ((H - |r|)(W - |c|)) sum (p[i, j] - m)(p[i + r, j + c] - m).
double eq15(const std::vector<double>& p, int w, int h, double mean, int dr, int dc) {
    double sum = 0;
    for (int i = 0; i + dr < h; ++i)
        for (int j = 0; j + dc < w; ++j)
            sum += (p[size_t(i) * w + j] - mean) * (p[size_t(i + dr) * w + j + dc] - mean);
    return sum / (double(h - dr) * (w - dc));
}

/// Least-squares line through (log d, log(-log(R / R0))): exponent and length of
/// R0 exp(-(d / l)^a), from the lags whose normalised estimate lies in (0.02, 0.98).
bool fit_markaussian(const std::vector<std::pair<double, double>>& pts, double& length,
                     double& exponent) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = 0;
    for (const auto& [d, rho] : pts) {
        if (!(rho > 0.02 && rho < 0.98)) continue;
        const double x = std::log(d), y = std::log(-std::log(rho));
        sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
    }
    if (n == 0) return false;
    const double den = n * sxx - sx * sx;
    if (!(den > 1e-9 * n * n)) {  // one lag (along x, y or both): a Markov fit through it
        exponent = 1;
        length = std::exp((sx - sy) / n);
        return true;
    }
    exponent = std::clamp((n * sxy - sx * sy) / den, 0.1, 2.0);
    // y = a x - a log l, so log l = (a mean(x) - mean(y)) / a.
    length = std::exp((exponent * sx / n - sy / n) / exponent);
    return true;
}

}  // namespace

AcfEstimate estimate_acf(const std::vector<double>& data, int w, int h, int factor) {
    AcfEstimate e;
    double sum = 0;
    for (double v : data) sum += v;
    e.mean = sum / double(data.size());
    e.variance = eq15(data, w, h, e.mean, 0, 0);
    if (!(e.variance > 0))
        throw ValueError(
            "the data are constant: no autocorrelation can be estimated from them "
            "(give one with --acf)");
    const int max_x = std::min(16, (w - 1) / 2), max_y = h > 1 ? std::min(16, (h - 1) / 2) : 0;
    std::vector<std::pair<double, double>> pts;
    // The fit uses each direction's lags up to the first whose estimate falls below 5 % of
    // R(0): beyond, eq. 15 is mostly sampling noise.
    bool open_x = true, open_y = true;
    for (int l = 0; l <= max_x; ++l) {
        e.along_x.push_back(eq15(data, w, h, e.mean, 0, l));
        open_x = open_x && e.along_x.back() > 0.05 * e.variance;
        if (l > 0 && open_x) pts.push_back({double(l) * factor, e.along_x.back() / e.variance});
    }
    for (int l = 0; l <= max_y; ++l) {
        e.along_y.push_back(eq15(data, w, h, e.mean, l, 0));
        open_y = open_y && e.along_y.back() > 0.05 * e.variance;
        if (l > 0 && open_y) pts.push_back({double(l) * factor, e.along_y.back() / e.variance});
    }
    if (!fit_markaussian(pts, e.length, e.exponent)) {
        // Uncorrelated at the data's spacing: correlated over less than one data sample.
        e.exponent = 1;
        e.length = 0.25 * factor;
    }
    const double v = e.variance, l = e.length, a = e.exponent;
    e.acf.R = [v, l, a](double x, double y) {
        return v * std::exp(-std::pow(std::hypot(x, y) / l, a));
    };
    std::ostringstream s;
    s << "estimated autocorrelation (Lewis 1987 eq. 15, lags in input samples): mean " << e.mean
      << ", R(0) " << e.variance << "; R(lag, 0) / R(0):";
    for (size_t i = 1; i < e.along_x.size() && i <= 8; ++i) s << " " << e.along_x[i] / v;
    if (e.along_y.size() > 1) {
        s << "; R(0, lag) / R(0):";
        for (size_t i = 1; i < e.along_y.size() && i <= 8; ++i) s << " " << e.along_y[i] / v;
    }
    s << "\nfitted: markaussian variance=" << v << " length=" << l << " exponent=" << a
      << " (R = variance exp(-(r / length)^exponent), r in output samples)";
    e.summary = s.str();
    e.acf.name = "markaussian fitted to the data (variance " + num(v) + ", length " + num(l) +
                 ", exponent " + num(a) + ")";
    return e;
}

}  // namespace impulse::synth
