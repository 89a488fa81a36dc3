// SPDX-License-Identifier: Apache-2.0
// The display mapping as text for a frame's metadata (output/display.h).

#include "output/display.h"

#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "numeric/errors.h"

namespace impulse::output {
namespace {

/// `v` with `digits` significant digits: 17 read back to the same double, 9 to the same float.
std::string number(double v, int digits = 17) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

std::string number(float v) { return number(double(v), 9); }

std::string triple(const float (&c)[3]) {
    return number(c[0]) + "," + number(c[1]) + "," + number(c[2]);
}

/// The numbers of `text` split at any of `separators` (strtod: reads what %.17g printed).
std::vector<double> numbers(const std::string& text, const std::string& separators, bool& ok) {
    std::vector<double> v;
    size_t start = 0;
    ok = !text.empty();
    while (ok && start <= text.size()) {
        const size_t end = text.find_first_of(separators, start);
        const std::string field = text.substr(start, end == std::string::npos ? end : end - start);
        char* stop = nullptr;
        const double x = std::strtod(field.c_str(), &stop);
        ok = !field.empty() && *stop == '\0';
        v.push_back(x);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return v;
}

}  // namespace

std::string format_display(const Display& d) {
    const Shading& s = d.shading;
    std::string ramp;
    for (const ColorStop& c : s.ramp)
        ramp += std::string(ramp.empty() ? "" : ";") + number(c.t) + ":" + number(c.r) + "," +
                number(c.g) + "," + number(c.b) + "," + number(c.a);
    return "lo=" + number(d.mapping.lo) + " hi=" + number(d.mapping.hi) +
           " relief=" + number(s.relief) + " azimuth=" + number(s.light_azimuth_deg) +
           " elevation=" + number(s.light_elevation_deg) + " ambient=" + number(s.ambient) +
           " top=" + triple(s.top) + " bottom=" + triple(s.bottom) + " ramp=" + ramp;
}

Display parse_display(const std::string& text, const std::string& what) {
    Display d;
    Shading& s = d.shading;
    double* scalars[] = {&d.mapping.lo,        &d.mapping.hi,          &s.relief,
                         &s.light_azimuth_deg, &s.light_elevation_deg, &s.ambient};
    const char* names[] = {"lo",      "hi",  "relief", "azimuth", "elevation",
                           "ambient", "top", "bottom", "ramp"};
    std::istringstream in(text);
    std::string field;
    for (int i = 0; i < 9; ++i) {
        const std::string key = std::string(names[i]) + "=";
        const auto bad = [&] {
            return ValueError(what + ": impulse:display field " + std::to_string(i + 1) + " \"" +
                              field.substr(0, 60) + "\": expected " + key + "NUMBER" +
                              (i == 6 || i == 7 ? ",G,B"
                               : i == 8         ? " (T:R,G,B,A;...)"
                                                : ""));
        };
        if (!(in >> field)) throw bad();
        if (i == 8 && field == key) break;  // no ramp: grey
        if (field.rfind(key, 0) != 0) throw bad();
        bool ok = false;
        const std::string value = field.substr(key.size());
        if (i < 6) {
            const std::vector<double> v = numbers(value, ",", ok);
            if (!ok || v.size() != 1) throw bad();
            *scalars[i] = v[0];
        } else if (i < 8) {
            const std::vector<double> v = numbers(value, ",", ok);
            if (!ok || v.size() != 3) throw bad();
            float* c = i == 6 ? s.top : s.bottom;
            for (int k = 0; k < 3; ++k) c[k] = float(v[size_t(k)]);
        } else {
            const std::vector<double> v = numbers(value, ":,;", ok);
            if (!ok || v.size() % 5 != 0) throw bad();
            for (size_t k = 0; k < v.size(); k += 5)
                s.ramp.push_back(
                    {v[k], float(v[k + 1]), float(v[k + 2]), float(v[k + 3]), float(v[k + 4])});
        }
    }
    if (in >> field)
        throw ValueError(what + ": impulse:display: unexpected \"" + field.substr(0, 60) +
                         "\" at the end");
    return d;
}

}  // namespace impulse::output
