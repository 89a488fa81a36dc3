// SPDX-License-Identifier: Apache-2.0
// [[layer]] source = "solid": a 2-D slice z = z0 + velocity t through sparse-convolution solid
// noise (synth/solid.h; Lewis 1989 §4) as a layer source, so solid noise is composited, shaded
// and animated like other layers (animation by moving through the noise, L89 §5.3). With
// dims = 4 the slice also advances along the noise's fourth axis at `rate` units per second.
// A slice of an isotropic 3-D field has the field's one-point statistics: mean 0 and
// Campbell's variance lambda E[a^2] int h^2 d^3x, and (3-D) the 2-D spectrum
// S_2(k) = int S_3(k, k_z) dk_z, the projection of the volume's (docs/solid.md "Slices").
// Under a perspective camera a gaussian slice is drawn as the 2-D impulses of the cells that
// reach the plane through the impulse layers' pipeline (docs/perspective.md §10).

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <iomanip>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "numeric/errors.h"
#include "scenes/detail/loader.h"
#include "scenes/detail/source.h"
#include "synth/synth.h"

namespace impulse::scenes::detail {
namespace {

// Impulses a perspective frame of a slice may generate (about 3 GB of impulses and work items).
constexpr double kMaxSliceImpulses = 1e8;

/// The cell columns (cx, cy) (side R) that hold the impulses of `region` moved by (ox, oy),
/// ascending; BudgetError when their impulses near the plane (2 R of the column's height at
/// `per_cell` impulses per cell) would exceed kMaxSliceImpulses.
std::vector<std::array<int64_t, 2>> slice_columns(const numeric::Region& region, double ox,
                                                   double oy, double R, double per_cell) {
    std::vector<std::array<int64_t, 2>> columns;
    double count = 0.0;
    for (const numeric::Box& b : region.boxes) {
        if (!(b.x1 >= b.x0 && b.y1 >= b.y0)) continue;
        const double nx = std::floor((b.x1 + ox) / R) - std::floor((b.x0 + ox) / R) + 1.0;
        const double ny = std::floor((b.y1 + oy) / R) - std::floor((b.y0 + oy) / R) + 1.0;
        count += nx * ny * 2.0 * per_cell;
    }
    if (count > kMaxSliceImpulses) {
        std::ostringstream s;
        s << std::setprecision(3) << "a perspective frame of the solid slice needs about "
          << count << " impulses, over " << kMaxSliceImpulses
          << " (raise camera.cutoff or layer.solid.radius)";
        throw BudgetError(s.str());
    }
    for (const numeric::Box& b : region.boxes) {
        if (!(b.x1 >= b.x0 && b.y1 >= b.y0)) continue;
        const auto x0 = int64_t(std::floor((b.x0 + ox) / R)), x1 = int64_t(std::floor((b.x1 + ox) / R));
        const auto y0 = int64_t(std::floor((b.y0 + oy) / R)), y1 = int64_t(std::floor((b.y1 + oy) / R));
        for (int64_t cx = x0; cx <= x1; ++cx)
            for (int64_t cy = y0; cy <= y1; ++cy) columns.push_back({cx, cy});
    }
    std::sort(columns.begin(), columns.end());  // overlapping boxes: each column once
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    return columns;
}

/// The slice's impulses as impulses of the plane moved by (dx, dy): for a gaussian kernel
/// h(sqrt(r^2 + d2)) = exp(-d2 / 2 sigma^2) exp(-r^2 / 2 sigma^2), so impulse i is the 2-D
/// gaussian kernel with weight a_i exp(-d2_i / 2 sigma^2) (docs/perspective.md eq. 10.1).
sim::Impulses plane_impulses(const synth::SliceImpulses& s, double dx, double dy, double sigma) {
    sim::Impulses imp;
    const size_t n = s.size();
    imp.x.resize(n), imp.y.resize(n), imp.weight.resize(n), imp.theta.assign(n, 0.0f);
    const double c = -0.5 / (sigma * sigma);
    for (size_t i = 0; i < n; ++i) {
        imp.x[i] = s.x[i] + dx, imp.y[i] = s.y[i] + dy;
        imp.weight[i] = static_cast<float>(double(s.a[i]) * std::exp(c * double(s.d2[i])));
    }
    return imp;
}

class SolidSource final : public LayerSource {
public:
    SolidSource(const synth::SolidParams& p, std::string_view kernel_name, double z0,
                double velocity, double rate)
        : m_noise(p), m_kernel_name(kernel_name), m_z0(z0), m_velocity(velocity), m_rate(rate) {
        if (p.dims == 3) m_slice.emplace(m_noise);
    }
    std::string_view kind() const override { return "solid"; }
    /// A gaussian kernel's slices keep their shape (docs/perspective.md §10); the others change
    /// it with the distance to the plane and are refused.
    bool perspective() const override { return m_noise.params().kernel.type == kernels::KernelType::Gaussian; }
    std::string no_perspective_reason() const override {
        return "a solid layer with kernel = \"" + m_kernel_name +
               "\" is seen through an orthographic camera only (its slices change shape with the "
               "distance to the plane); kernel = \"gaussian\" is drawn in perspective too";
    }
    void add_perspective(const PixelFootprints& px, double dx, double dy, double t_s,
                         numeric::Frame& out) const override {
        if (!px.view || !px.coords)
            throw ValueError("solid layer: add_perspective needs the camera's pixel coordinates");
        const kernels::KernelPyramid& pyr = pyramid(px.aa.cutoff);
        const double R = m_noise.kernel().radius();
        const double per_cell = m_noise.theory().lambda * R * R * R;
        // The field is f(x - d): the impulses of f over the region moved by -d, drawn at +d.
        const auto columns = slice_columns(render::perspective_region(pyr, *px.view, px.aa), -dx,
                                           -dy, R, per_cell);
        synth::SliceImpulses s;
        m_noise.slice_impulses(columns, m_z0 + m_velocity * t_s, m_rate * t_s, s);
        const sim::Impulses imp = plane_impulses(s, dx, dy, m_noise.params().kernel.sigma);
        render::accumulate_perspective(pyr, imp, *px.view, *px.coords, out, px.aa, {}, nullptr,
                                       &m_workspace);
    }
    void add(const numeric::View& v, double t_s, numeric::Frame& out) const override {
        std::vector<synth::SolidPoint> pts(size_t(v.width) * v.height);
        const double z = m_z0 + m_velocity * t_s, w = m_rate * t_s;
        for (int j = 0; j < v.height; ++j)
            for (int i = 0; i < v.width; ++i)
                pts[size_t(j) * v.width + i] = {v.x0 + (i + 0.5) * v.scale, v.y0 + (j + 0.5) * v.scale, z, w};
        std::vector<float> values;
        m_noise.evaluate(pts, values);
        for (size_t k = 0; k < values.size(); ++k) out.data[k] += values[k];
    }
    Theory theory(double) const override { return {0.0, m_noise.theory().variance}; }
    /// The points of a view and their values, made per frame by `add`.
    double memory_bytes(double pixels, bool) const override {
        return pixels * double(sizeof(synth::SolidPoint) + sizeof(float));
    }
    double correlation_length() const override { return m_noise.kernel().radius(); }
    /// The slice's 2-D spectrum (projection-slice); 4-D noise states its variance only.
    std::optional<double> power_spectrum(double k_cycles) const override {
        if (!m_slice) return std::nullopt;
        return (*m_slice)(k_cycles);
    }
    std::string no_spectrum_reason() const override {
        return m_slice ? "" : "4-D solid noise states its variance only (the slice spectrum is "
                              "derived for 3-D noise)";
    }

private:
    /// The 2-D kernel's pyramid for a cut-off (levels down to a quarter of it, as the impulse
    /// layers' pipeline builds them), built on first use and kept.
    const kernels::KernelPyramid& pyramid(double cutoff) const {
        const std::lock_guard<std::mutex> lock(m_mutex);
        auto& built = m_pyramids[cutoff];
        if (!built) {
            kernels::PyramidParams params;
            params.min_sd_fraction = std::min(1e-3, 0.25 * cutoff);
            built = std::make_unique<const kernels::KernelPyramid>(
                kernels::Kernel(m_noise.params().kernel), params);
        }
        return *built;
    }

    synth::SolidNoise m_noise;
    std::string m_kernel_name;
    std::optional<synth::SolidSliceSpectrum> m_slice;
    double m_z0, m_velocity, m_rate;
    mutable std::mutex m_mutex;
    mutable std::map<double, std::unique_ptr<const kernels::KernelPyramid>> m_pyramids;
    mutable render::PerspectiveWorkspace m_workspace;  ///< lent to each frame (safe to share)
};

/// A kernel designed from a 3-D spectrum or isotropic correlation (kernel = "spectrum" or
/// "autocorrelation"), scaled so the noise at `density` has that spectrum. Band-limited to
/// nyquist (default the pixel Nyquist frequency 0.5 zoom), so the slice does not alias.
kernels::KernelParams read_solid_design(Reader& t, bool acf, double density, double zoom,
                                        const std::filesystem::path& base) {
    namespace K = kernels;
    K::DesignOptions o;
    o.dims = 3;
    o.nyquist = 0.5 * zoom;
    o.window = static_cast<K::DesignWindow>(t.choice("window", K::kDesignWindowNames, 1));
    o.radius = t.number("radius", 0.0, kPositive, "a radius > 0 (texture units)");
    const K::DesignedKernel d = read_design(t, acf, base, o);
    // Campbell in 3-D: kappa_4 / kappa_2^2 = (E[a^4] / E[a^2]^2) / (lambda V_eff), 9/5 for
    // uniform amplitudes, V_eff = (int h^2)^2 / int h^4 over space.
    const double lambda = density / (4.0 / 3.0 * std::numbers::pi * std::pow(d.params.radius, 3));
    const double kurtosis = 1.8 / (lambda * d.report.effective_area);
    if (kurtosis > 1.0) {
        std::ostringstream s;
        s << std::setprecision(3) << "the designed kernel is peaked: at density " << density
          << " the noise's excess kurtosis is " << kurtosis << " and it looks speckled; density >= "
          << std::ceil(density * kurtosis / 0.3) << " brings it to 0.3";
        t.warn("density", s.str());
    }
    return synth::solid_designed_kernel(d.params, density);
}

}  // namespace

std::shared_ptr<const LayerSource> read_solid_source(std::optional<Reader> t, uint64_t seed,
                                                     const std::filesystem::path& base,
                                                     double zoom, bool perspective) {
    synth::SolidParams p;
    p.kernel.radius = 16.0;
    p.seed = seed;
    double z0 = 0.0, velocity = 0.0, rate = 0.0;
    std::string_view kernel_name = "cosine";
    if (t) {
        static constexpr std::array<std::string_view, 4> kKernels = {"cosine", "gaussian", "spectrum",
                                                                     "autocorrelation"};
        const size_t kernel = t->choice("kernel", kKernels, 0);
        kernel_name = kKernels[kernel];
        p.density = t->number("density", 16.0, [](double d) { return d > 0.0 && d <= 1000.0; },
                              "impulses per kernel volume 4/3 pi R^3, in (0, 1000]");
        p.dims = static_cast<int>(t->integer("dims", 3, 3, 4));
        if (kernel >= 2) {
            if (p.dims != 3)
                t->fail(t->node("dims"), "dims",
                        "a kernel designed from a 3-D spectrum or correlation needs dims = 3");
            p.kernel = read_solid_design(*t, kernel == 3, p.density, zoom, base);
        } else {
            p.kernel.type = kernel == 0 ? kernels::KernelType::Cosine : kernels::KernelType::Gaussian;
            p.kernel.radius = t->number("radius", 16.0, [](double r) { return r >= 1e-3 && r <= 1e6; },
                                        "a kernel radius in [1e-3, 1e6] texture units");
            p.kernel.sigma = p.kernel.radius / 3.0;
            // Point samples of a kernel spanning few pixels alias (the slice is not band-limited);
            // a perspective camera filters a gaussian by the footprint and refuses the others.
            if (p.kernel.radius * zoom < 2.0 && !perspective)
                t->warn("radius", "radius = " + num(p.kernel.radius) + " texture units is " +
                                      num(p.kernel.radius * zoom) + " pixels at zoom " + num(zoom) +
                                      ", under 2: the slice aliases (its spectrum reaches past the "
                                      "pixel Nyquist frequency); raise radius or use kernel = "
                                      "\"spectrum\", band-limited to nyquist");
        }
        auto finite = [](double x) { return std::abs(x) <= 1e12; };
        z0 = t->number("z0", 0.0, finite, "a finite z in texture units, within +-1e12");
        velocity = t->number("velocity", 0.0, finite, "texture units per second along z, within +-1e12");
        rate = t->number("rate", 0.0, finite, "units per second along the fourth axis, within +-1e12");
        if (rate != 0.0 && p.dims != 4)
            t->fail(t->node("rate"), "rate", "rate moves along the fourth axis: set dims = 4");
        t->finish();
    }
    return std::make_shared<const SolidSource>(p, kernel_name, z0, velocity, rate);
}

}  // namespace impulse::scenes::detail
