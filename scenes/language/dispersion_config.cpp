// SPDX-License-Identifier: Apache-2.0
// [layer.dispersion]: Gabor waves that obey a dispersion relation. A Gabor impulse of
// wavenumber k (k = 2 pi frequency, radians per unit) is a wave packet: its carrier must
// advance at the phase speed omega(k) / k and its envelope travel at the group speed
// d omega / dk (Kinsman 1965 §3; deep water omega^2 = g k, phase speed sqrt(g / k), group speed
// half of it), so long swell outruns short ripples instead of every band sliding at one speed.
//
// The envelope's motion is a uniform flow at the group velocity along the waves' direction,
// added to the layer's flows. The carrier's advance relative to the envelope,
//     phi(t) = -(omega - k c_g) t = -Omega t,
// is the same for every impulse of the layer (one wavenumber), so the layer is rendered as a
// quadrature pair: cos(theta + phi0 + phi) = cos(phi) cos(theta + phi0) + sin(phi) cos(theta +
// phi0 + pi/2), i.e. the layer itself with weight cos(Omega t) and a twin with the kernel's phase
// + pi/2 and weight -sin(Omega t) drawing the same impulses (same process config). Weights
// rather than a keyframed kernel phase, because a perspective camera's kernel pyramid is built
// once; the pair's variance is the layer's at every t (cos^2 + sin^2 = 1).

#include <cmath>
#include <functional>
#include <numbers>

#include "scenes/detail/reader.h"
#include "scenes/scenes.h"

namespace impulse::scenes {

WaveDispersion dispersion_relation(double k, double gravity, double depth) {
    // omega^2 = g k tanh(k h) (linear waves over depth h; deep water h -> inf: g k);
    // c_g = d omega / dk = (c_p / 2) (1 + 2 k h / sinh(2 k h)).
    WaveDispersion w;
    const bool deep = !(depth > 0.0) || k * depth > 20.0;  // tanh(20) = 1 to 1e-17
    w.omega = std::sqrt(gravity * k * (deep ? 1.0 : std::tanh(k * depth)));
    const double c_p = w.omega / k;
    w.group_speed = deep ? 0.5 * c_p : 0.5 * c_p * (1.0 + 2.0 * k * depth / std::sinh(2.0 * k * depth));
    return w;
}

namespace detail {

namespace {

/// The waves' direction of travel: the kernel's orientation, plus a constant orientation
/// field's angle at the origin at t = 0 (the carrier varies along this direction).
double carrier_direction(const LayerConfig& L) {
    double theta = L.kernel.orientation;
    if (L.process.orientation == sim::OrientationMode::Field && L.process.orientation_field) {
        const double x = 0.0, y = 0.0;
        float a = 0.0f;
        L.process.orientation_field->angles(0.0, 1, &x, &y, &a);
        theta += a;
    }
    return theta;
}

}  // namespace

/// The layer's flows (read afresh for each caller: a flow may cache per frame) plus the group
/// velocity's uniform flow along direction a.
std::shared_ptr<sim::Flow> with_group_flow(const std::function<std::shared_ptr<sim::Flow>()>& flows,
                                           double speed, double a) {
    std::shared_ptr<sim::Flow> f = flows();
    auto sum = std::dynamic_pointer_cast<sim::FlowSum>(f);
    if (!sum) sum = std::make_shared<sim::FlowSum>();  // no [[layer.flow]]
    sum->push(sim::make_uniform_flow(speed * std::cos(a), speed * std::sin(a)));
    return sum;
}

void read_dispersion(Reader& layer, LayerConfig& L, std::vector<LayerConfig>& twins,
                     const std::function<std::shared_ptr<sim::Flow>()>& flows) {
    auto t = layer.table("dispersion");
    if (!t) return;
    const toml::node* n = layer.node("dispersion");
    if (L.kernel.type != kernels::KernelType::Gabor)
        layer.fail(n, "dispersion", "needs a gabor kernel (a carrier to move at the phase speed)");
    if (!L.kernel_keys.empty())
        layer.fail(n, "dispersion", "the kernel's keys cannot vary in time in a dispersive layer");
    if (L.process.lifetime_s <= 0)
        layer.fail(n, "dispersion", "waves move: set lifetime > 0 in this layer");
    if (L.marginal || L.compose.blend != Blend::Add || L.compose.warp || L.compose.orientation)
        layer.fail(n, "dispersion", "a dispersive layer is added as it is: no marginal, warp, "
                                    "orientation from a layer or blend other than add");
    const auto positive = [](double v) { return v > 0.0; };
    const double g = t->number("gravity", 9.81, positive, "an acceleration > 0 (texture units / s^2)");
    const double h = t->number("depth", 0.0, [](double v) { return v >= 0.0; },
                               "a depth >= 0 in texture units (0: deep water)");
    t->finish();
    const double k = 2.0 * std::numbers::pi * L.kernel.frequency;
    const WaveDispersion w = dispersion_relation(k, g, h);
    double rate = w.omega - k * w.group_speed;  // Omega: the carrier's advance on its envelope
    if (const double P = L.process.loop_s; P > 0) {
        // A looped layer repeats its births every P seconds: the carrier must come back too,
        // so Omega is rounded to whole turns per loop (2 pi m / P).
        const double turns = std::max(1.0, std::round(rate * P / (2.0 * std::numbers::pi)));
        const double rounded = 2.0 * std::numbers::pi * turns / P;
        if (std::abs(rounded - rate) > 0.05 * rate)
            layer.warn("dispersion", "the loop of " + std::to_string(P) + " s rounds the carrier's "
                       "rate " + std::to_string(rate) + " rad/s to " + std::to_string(rounded) +
                       " (whole turns per loop): a longer loop keeps it closer");
        rate = rounded;
    }
    const double a = carrier_direction(L);
    L.flow = with_group_flow(flows, w.group_speed, a);
    L.carrier_rate = rate;
    LayerConfig twin = L;
    twin.flow = with_group_flow(flows, w.group_speed, a);
    twin.kernel.phase += std::numbers::pi / 2.0;
    twin.carrier_quadrature = true;
    twin.compose.name.clear();
    twins.push_back(std::move(twin));
}

}  // namespace detail
}  // namespace impulse::scenes
