// SPDX-License-Identifier: Apache-2.0
#pragma once
// The display mapping (value range and shading) as one line of text, so a frame written as raw
// floats (EXR) carries what turns it into the picture `impulse render` would have shown, and
// `impulse encode` assembles the same video later, on another machine. Part of impulse::output;
// included by output/output.h.

#include <string>

#include "output/image.h"
#include "output/shading.h"

namespace impulse::output {

/// A frame's display mapping: its value range and its shading (at the frame's time).
struct Display {
    ValueMapping mapping;
    Shading shading;
};

/// `display` as "lo=... hi=... relief=... azimuth=... elevation=... ambient=... top=r,g,b
/// bottom=r,g,b ramp=t:r,g,b,a;..." with every number printed so it reads back to the same bits
/// (17 significant digits for doubles, 9 for floats).
std::string format_display(const Display& display);
/// The inverse of format_display, bit for bit. Throws ValueError naming the first field that
/// does not parse (`what` prefixes the message, e.g. the file it came from).
Display parse_display(const std::string& text, const std::string& what);

}  // namespace impulse::output
