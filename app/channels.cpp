// SPDX-License-Identifier: Apache-2.0
// `impulse render --channels` (app/channels.h; docs/channels.md).

#include "app/channels.h"

#include <cctype>
#include <filesystem>

#include "numeric/errors.h"

namespace impulse::app {
namespace {

namespace fs = std::filesystem;

/// The EXR names of the plan's channels after R G B A: composite then per layer.
std::vector<std::string> exr_names(const scenes::Scene& sc, const scenes::ChannelSet& set) {
    std::vector<std::string> layers;
    for (size_t i = 0; i < sc.layers.size(); ++i)
        if (sc.layers[i].compose.visible)
            layers.push_back(sc.layers[i].compose.name.empty() ? "layer" + std::to_string(i)
                                                               : sc.layers[i].compose.name);
    std::vector<std::string> n = {"R", "G", "B", "A"};
    auto field = [&](bool on, const std::string& c) {
        if (!on) return;
        n.push_back(c);
        for (const auto& l : layers) n.push_back(l + "." + c);
    };
    field(set.value, "value");
    field(set.dx, "dx");
    field(set.dy, "dy");
    if (set.normal) n.insert(n.end(), {"N.X", "N.Y", "N.Z"});
    if (set.motion) n.insert(n.end(), {"forward.u", "forward.v", "backward.u", "backward.v"});
    return n;
}

std::string joined(const std::vector<std::string>& names) {
    std::string s;
    for (const auto& n : names) s += (s.empty() ? "" : " ") + n;
    return s;
}

}  // namespace

ChannelPlan plan_channels(const scenes::Scene& sc, const std::string& flag,
                          const std::string& output, bool video) {
    ChannelPlan p;
    if (flag.empty() && sc.output.channels.empty()) return p;
    p.active = true;
    if (!flag.empty()) {
        p.what = "--channels " + flag;
        p.set = scenes::parse_channels(flag, "--channels");
    } else {
        p.what = "output.channels";
        p.set = scenes::parse_channels(sc.output.channels, p.what);
    }
    std::string ext = fs::path(output).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (video)
        throw ValueError(p.what + ": " + output + " is a video of display colour (8 or 10 bits): " +
                         "it cannot hold field values, derivatives or motion vectors; write the "
                         "channels to an EXR sequence (f_####.exr)");
    p.names = exr_names(sc, p.set);
    if (ext == ".exr") return p;
    const bool only_normal = p.set.normal && !p.set.value && !p.set.dx && !p.set.dy && !p.set.motion;
    const bool only_value = p.set.value && !p.set.gradient() && !p.set.motion;
    if (only_normal) {
        p.names = {"R", "G", "B"};
        return p;
    }
    if (only_value) {
        p.names = {"Y"};
        return p;
    }
    throw ValueError(p.what + ": " + std::to_string(p.names.size()) + " channels (" +
                     joined(p.names) + "); a " + ext.substr(ext.empty() ? 0 : 1) +
                     " file holds at most 4 of display values: write them to an EXR (.exr), or "
                     "ask for normal alone (a normal map) or value alone");
}

void write_channel_frame(const scenes::Scene& sc, const ChannelPlan& plan,
                         const scenes::FrameChannels& ch, long long f, const std::string& target,
                         const output::ValueMapping& mapping, const output::Metadata& metadata) {
    const int w = sc.output.width, h = sc.output.height;
    const size_t n = size_t(w) * h;
    const double t = sc.frame_time(f);
    const bool bits16 = sc.output.bits == 16;
    if (plan.names.size() == 1)  // the field alone, as a plain render writes it
        return output::write_image(target, ch.value, mapping, metadata, bits16);
    std::vector<float> normals;
    if (plan.set.normal) scenes::normal_map(ch.dx, ch.dy, scenes::normal_relief(sc, t), normals);
    if (plan.names.size() == 3) {  // a normal map: N * 0.5 + 0.5 (OpenGL's, y up)
        for (float& v : normals) v = 0.5f * v + 0.5f;
        return output::write_named_channels(target, w, h, plan.names, normals, metadata, bits16);
    }
    // R G B A: the shaded colour premultiplied by the ramp's coverage (shade over black).
    output::Shading shading = sc.shading_at(t);
    for (int k = 0; k < 3; ++k) shading.top[k] = shading.bottom[k] = 0.0f;
    shading.background.clear();
    std::vector<float> rgb, alpha;
    output::shade(ch.value, mapping, shading, rgb);
    output::shading_alpha(ch.value, mapping, shading, alpha);
    std::vector<const float*> planes;  // one per name after R G B A, in order
    auto field = [&](bool on, const render::Frame& c, const std::vector<render::Frame>& per) {
        if (!on) return;
        planes.push_back(c.data.data());
        for (const auto& p : per) planes.push_back(p.data.data());
    };
    field(plan.set.value, ch.value, ch.layer_value);
    field(plan.set.dx, ch.dx, ch.layer_dx);
    field(plan.set.dy, ch.dy, ch.layer_dy);
    const size_t nn = plan.set.normal ? 3 : 0;
    const size_t nc = plan.names.size();
    std::vector<float> px(n * nc);
    for (size_t i = 0; i < n; ++i) {
        float* o = px.data() + i * nc;
        o[0] = rgb[3 * i], o[1] = rgb[3 * i + 1], o[2] = rgb[3 * i + 2], o[3] = alpha[i];
        size_t c = 4;
        for (const float* p : planes) o[c++] = p[i];
        for (size_t k = 0; k < nn; ++k) o[c++] = normals[3 * i + k];
        if (plan.set.motion)
            for (const auto& m : ch.motion) o[c++] = m.data[i];
    }
    output::write_named_channels(target, w, h, plan.names, px, metadata, false,
                                 sc.output.compression);
}

}  // namespace impulse::app
