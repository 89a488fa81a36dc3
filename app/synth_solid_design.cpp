// SPDX-License-Identifier: Apache-2.0
#include "app/synth_solid_design.h"

#include <CLI/CLI.hpp>

#include <charconv>

#include "kernels/kernels.h"
#include "numeric/errors.h"
#include "synth/synth.h"

namespace impulse::app {
namespace {

namespace K = kernels;

double number(const std::string& option, const std::string& text, const std::string& expected) {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || text.empty() || !std::isfinite(v))
        throw ValueError(option + " " + text + ": expected " + expected);
    return v;
}

K::ModelParams model_params(const SynthSolidOptions& o) {
    const auto m = K::spectral_model_from_string(o.model);
    if (!m) {
        std::string list;
        for (auto n : K::kSpectralModelNames) list += (list.empty() ? "" : ", ") + std::string(n);
        throw ValueError("--model " + o.model + ": expected one of " + list);
    }
    K::ModelParams p;
    p.model = *m;
    p.variance = number("--variance", o.variance, "a variance > 0");
    p.length = o.length.empty() ? 8.0 : number("--length", o.length, "a length > 0 (texture units)");
    p.nu = number("--nu", o.nu, "a smoothness in (0, 50]");
    p.exponent = number("--exponent", o.exponent, "an exponent in (0, 2]");
    p.omega = number("--omega", o.omega, "an angular frequency >= 0 (radians per unit)");
    return p;
}

}  // namespace

void add_solid_design_options(CLI::App& s, SynthSolidOptions& o) {
    s.add_option("--model", o.model,
                 "designed kernels: markov, gaussian, markaussian, matern, oscillatory_markov, "
                 "oscillatory_gaussian (their 3-D spectra)");
    s.add_option("--expression", o.expression,
                 "designed kernels: the 3-D spectrum S(k) (--kernel spectrum) or correlation R(r) "
                 "(--kernel autocorrelation), k in cycles per unit");
    s.add_option("--table", o.table, "--kernel spectrum: a CSV of k,S rows (the 3-D spectrum)");
    s.add_option("--variance", o.variance, "--model: R(0) (default 1)");
    s.add_option("--nu", o.nu, "--model matern: smoothness (default 1.5)");
    s.add_option("--exponent", o.exponent, "--model markaussian: exponent (default 1.4)");
    s.add_option("--omega", o.omega, "--model oscillatory_*: radians per unit (default 0.5)");
    s.add_option("--nyquist", o.nyquist, "designed kernels: band limit, cycles per unit (default 0.5)");
    s.add_option("--rolloff", o.rolloff, "designed kernels: roll-off fraction of nyquist (default 0.2)");
    s.add_option("--energy", o.energy, "designed kernels: energy kept inside the radius (default 0.99)");
    s.add_option("--window", o.window, "designed kernels: hann (default), gaussian or none");
}

bool is_designed_kernel(const std::string& kernel) {
    return kernel == "spectrum" || kernel == "autocorrelation";
}

K::KernelParams solid_design_kernel(const SynthSolidOptions& o, double radius, double density,
                                    std::ostringstream& desc) {
    const bool acf = o.kernel == "autocorrelation";
    const int given = !o.model.empty() + !o.expression.empty() + !o.table.empty();
    if (given != 1)
        throw ValueError("--kernel " + o.kernel + ": expected exactly one of --model, --expression" +
                         (acf ? "" : ", --table"));
    if (acf && !o.table.empty())
        throw ValueError("--table " + o.table + ": a table gives a spectrum: use --kernel spectrum");
    K::DesignOptions d;
    d.dims = 3;
    d.radius = radius;
    d.nyquist = number("--nyquist", o.nyquist, "a frequency > 0 (cycles per unit)");
    d.rolloff = number("--rolloff", o.rolloff, "a fraction in [0, 0.9]");
    d.energy = number("--energy", o.energy, "a fraction in (0, 1)");
    size_t w = 0;
    while (w < K::kDesignWindowNames.size() && K::kDesignWindowNames[w] != o.window) ++w;
    if (w == K::kDesignWindowNames.size())
        throw ValueError("--window " + o.window + ": expected one of none, hann, gaussian");
    d.window = static_cast<K::DesignWindow>(w);
    K::DesignedKernel k;
    if (acf) {
        const K::Autocorrelation a = o.model.empty() ? K::expression_autocorrelation(o.expression)
                                                     : K::model_autocorrelation(model_params(o));
        if (!o.model.empty() && !K::defined_by_autocorrelation(model_params(o).model))
            throw ValueError("--model " + o.model + ": defined by a spectrum, use --kernel spectrum");
        k = K::kernel_from_autocorrelation(a, d);
    } else {
        const K::Spectrum sp = !o.model.empty()      ? K::model_spectrum(model_params(o), d.nyquist, 3)
                               : !o.table.empty()    ? K::table_spectrum(o.table)
                                                     : K::expression_spectrum(o.expression);
        k = K::kernel_from_spectrum(sp, d);
    }
    desc << " --kernel " << o.kernel << (o.model.empty() ? "" : " --model " + o.model)
         << (o.expression.empty() ? "" : " --expression \"" + o.expression + "\"")
         << (o.table.empty() ? "" : " --table " + o.table) << " --nyquist " << o.nyquist
         << " (designed radius " << k.report.radius << ")";
    return synth::solid_designed_kernel(k.params, density);
}

}  // namespace impulse::app
