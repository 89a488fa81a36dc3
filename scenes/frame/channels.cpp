// SPDX-License-Identifier: Apache-2.0
// The channels of a frame (scenes/channels.h): names, what each scene can give, normals and
// motion vectors (docs/channels.md).

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "numeric/errors.h"
#include "scenes/detail/channels.h"
#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes {
namespace {

void add_channel(ChannelSet& set, const std::string& name, const std::string& what) {
    if (name == "value") set.value = true;
    else if (name == "dx") set.dx = true;
    else if (name == "dy") set.dy = true;
    else if (name == "normal") set.normal = true;
    else if (name == "motion") set.motion = true;
    else {
        std::vector<std::string> names(kChannelNames.begin(), kChannelNames.end());
        const auto near = detail::nearest(name, names);
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        throw ValueError(what + ": unknown channel \"" + name + "\"" +
                         (near ? " (did you mean \"" + *near + "\"?)" : "") +
                         ": expected one of " + list);
    }
}

}  // namespace

ChannelSet parse_channels(const std::vector<std::string>& names, const std::string& what) {
    ChannelSet set;
    if (names.empty()) throw ValueError(what + ": expected at least one channel name");
    for (const auto& n : names) add_channel(set, n, what);
    return set;
}

ChannelSet parse_channels(const std::string& list, const std::string& what) {
    std::vector<std::string> names;
    std::stringstream s(list);
    for (std::string n; std::getline(s, n, ',');) names.push_back(n);
    if (!list.empty() && list.back() == ',') names.push_back("");
    return parse_channels(names, what + " " + list);
}

void normal_map(const numeric::Frame& dx, const numeric::Frame& dy, double relief,
                std::vector<float>& xyz) {
    xyz.resize(dx.data.size() * 3);
    for (size_t i = 0; i < dx.data.size(); ++i) {
        // The surface z = relief f(x, y) with y up: its normal is (-dz/dx, -dz/dy_up, 1), and
        // dz/dy_up = -relief df/dy for y down the rows.
        const double nx = -relief * dx.data[i], ny = relief * dy.data[i];
        const double inv = 1.0 / std::sqrt(nx * nx + ny * ny + 1.0);
        xyz[3 * i] = static_cast<float>(nx * inv);
        xyz[3 * i + 1] = static_cast<float>(ny * inv);
        xyz[3 * i + 2] = static_cast<float>(inv);
    }
}

double normal_relief(const Scene& scene, double t_s) {
    const double r = scene.shading_keys.relief.value(t_s);
    return r != 0.0 ? r : 1.0;
}

std::string camera_text(const Scene& scene, double t) {
    const CameraConfig& c = scene.camera;
    std::ostringstream s;
    s.precision(17);
    if (c.type == CameraConfig::Type::Orthographic) {
        const render::View v = c.view(scene.output.width, scene.output.height, t);
        s << "orthographic x0=" << v.x0 << " y0=" << v.y0 << " scale=" << v.scale;
    } else {
        s << "perspective x=" << c.position_x.value(t) << " y=" << c.position_y.value(t)
          << " height=" << c.altitude.value(t) << " pitch=" << c.pitch.value(t)
          << " heading=" << c.heading.value(t) << " fov=" << c.fov.value(t)
          << " plane=" << (c.plane == render::Plane::Ground ? "ground" : "sky");
    }
    s << " size=" << scene.output.width << "x" << scene.output.height;
    return s.str();
}

namespace detail {

void check_channels(const Scene& scene, const ChannelSet& set, const std::string& what) {
    auto refuse = [&](const std::string& why) {
        throw SceneError(scene.path + ": " + what + ": " + why + " (docs/channels.md)");
    };
    const bool perspective = scene.camera.type == CameraConfig::Type::Perspective;
    if ((set.gradient() || set.motion) && perspective)
        refuse("derivatives, normals and motion vectors are made for orthographic cameras only");
    if (set.gradient() && scene.camera.antialiased())
        refuse("the camera filters the kernels (camera.antialias, a zoom below 1): the exact "
               "derivatives are of the unfiltered field; render with camera.antialias = \"off\"");
    if (set.gradient() && scene.transform.type != output::FieldTransform::Type::None)
        refuse("derivatives through shading.transform (marble, wood) are not made");
    for (size_t i = 0; i < scene.layers.size(); ++i) {
        const LayerConfig& l = scene.layers[i];
        if (!l.compose.visible) continue;
        const std::string name = "layer[" + std::to_string(i) + "]";
        if (set.motion && l.source) refuse(name + " is a " + std::string(l.source->kind()) +
                                           " source layer: its motion vectors are not made");
        if (!set.gradient()) continue;
        if (l.source) refuse(name + " is a " + std::string(l.source->kind()) +
                             " source layer: its derivatives are not made");
        if (l.marginal) refuse(name + " is shaped (marginal): its derivatives are not made");
        if (l.compose.warp) refuse(name + " is warped: its derivatives are not made");
        if (l.compose.blend != Blend::Add)
            refuse(name + " blend = \"" + std::string(kBlendNames[size_t(l.compose.blend)]) +
                   "\": derivatives are made for added layers only");
    }
}

void motion_vectors(const Scene& scene, int64_t frame, const std::vector<size_t>& layers,
                    std::array<numeric::Frame, 4>& out) {
    const auto& o = scene.output;
    const double t = scene.frame_time(frame), dt = 1.0 / o.fps;
    const render::View v0 = scene.camera.view(o.width, o.height, t);
    const render::View vf = scene.camera.view(o.width, o.height, t + dt);
    const render::View vb = scene.camera.view(o.width, o.height, t - dt);
    // The layers' velocities weighted by their share of the variance (opacity^2 Var), so the
    // composite moves with what dominates it; a layer without a flow stands still.
    std::vector<double> weight;
    double total = 0.0;
    for (size_t i : layers) {
        const double op = scene.layers[i].compose.opacity.value(t);
        weight.push_back(op * op * layer_theory(scene.layers[i], t).variance);
        total += weight.back();
    }
    for (auto& f : out) f.resize(o.width, o.height);
    tbb::parallel_for(0, o.height, [&](int y) {
        const size_t n = size_t(o.width);
        std::vector<double> px(n), py(n, v0.y0 + (y + 0.5) * v0.scale), vx(n, 0.0), vy(n, 0.0);
        for (size_t x = 0; x < n; ++x) px[x] = v0.x0 + (double(x) + 0.5) * v0.scale;
        std::vector<double> lx(n), ly(n);
        for (size_t k = 0; k < layers.size(); ++k) {
            const LayerConfig& l = scene.layers[layers[k]];
            if (!l.flow || !(weight[k] > 0.0)) continue;
            std::fill(lx.begin(), lx.end(), 0.0), std::fill(ly.begin(), ly.end(), 0.0);
            l.flow->add(scene.layer_time(layers[k], frame), n, px.data(), py.data(), lx.data(),
                        ly.data(), nullptr, nullptr);
            for (size_t x = 0; x < n; ++x)
                vx[x] += weight[k] / total * lx[x], vy[x] += weight[k] / total * ly[x];
        }
        for (size_t x = 0; x < n; ++x) {
            const size_t i = size_t(y) * n + x;
            // Where the texture point of the pixel is one frame later (earlier), seen by the
            // camera then: the flow to first order in dt, the camera exactly.
            const double fx = (px[x] + vx[x] * dt - vf.x0) / vf.scale - 0.5;
            const double fy = (py[x] + vy[x] * dt - vf.y0) / vf.scale - 0.5;
            const double bx = (px[x] - vx[x] * dt - vb.x0) / vb.scale - 0.5;
            const double by = (py[x] - vy[x] * dt - vb.y0) / vb.scale - 0.5;
            out[0].data[i] = static_cast<float>(fx - double(x));
            out[1].data[i] = static_cast<float>(-(fy - double(y)));  // v up (Nuke)
            out[2].data[i] = static_cast<float>(bx - double(x));
            out[3].data[i] = static_cast<float>(-(by - double(y)));
        }
    });
}

}  // namespace detail
}  // namespace impulse::scenes
