// SPDX-License-Identifier: Apache-2.0
// Multi-rate evaluation: the lattice rule from the kernel's spectrum and the cubic B-spline
// reconstruction (docs/multirate.md).

#include "render/lattice.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>

#include "numeric/check.h"
namespace impulse::render {
namespace {

constexpr double kPi = std::numbers::pi;
/// The cubic B-spline prefilter's pole, z = sqrt(3) - 2 (Unser, Aldroubi & Eden 1991).
constexpr double kPole = -0.26794919243112270;

/// The cubic B-spline beta3 at t in [0, 1): its weights on the nodes j - 1, j, j + 1, j + 2 for
/// a point at j + t.
std::array<double, 4> bspline_weights(double t) {
    const double u = 1.0 - t;
    return {u * u * u / 6.0, (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
            (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0, t * t * t / 6.0};
}

/// The interpolating cubic spline's response to e^{i w n} at n + tau, over e^{i w (n + tau)}:
/// G(w, tau) = e^{-i w tau} sum_j beta3(tau - j) e^{i w j} / B(w), B(w) = (2 + cos w) / 3 the
/// prefilter's inverse (docs/multirate.md §2).
std::complex<double> response(double w, double tau) {
    const auto b = bspline_weights(tau);
    std::complex<double> sum = 0.0;
    for (int j = -1; j <= 2; ++j) sum += b[size_t(j + 1)] * std::polar(1.0, w * j);
    return sum * std::polar(1.0, -w * tau) / ((2.0 + std::cos(w)) / 3.0);
}

/// The phase-averaged response and squared response over tau = p / h, p = 0 .. h - 1.
struct PhaseResponse {
    std::complex<double> mean;
    double mean_sq = 0.0;
};
PhaseResponse phase_response(double w, int h) {
    PhaseResponse r;
    for (int p = 0; p < h; ++p) {
        const auto g = response(w, double(p) / h);
        r.mean += g;
        r.mean_sq += std::norm(g);
    }
    r.mean /= double(h);
    r.mean_sq /= h;
    return r;
}

/// The largest phase-averaged squared response over a period of w (it is 2 pi periodic):
/// bounds the error of frequencies beyond the quadrature by (1 + A_max)^2.
double max_mean_sq(int h) {
    double a = 0.0;
    for (int i = 0; i <= 256; ++i) a = std::max(a, phase_response(2.0 * kPi * i / 256.0, h).mean_sq);
    return a;
}

/// The quadrature grid of lattice_error: midpoint rule with step dk < 1 / (2 R + 24 h s), so that
/// the sum is exact for |H|^2 (its inverse transform, the kernel's autocorrelation, vanishes
/// beyond 2R) and for the interpolator's error (whose spatial reach is a few lattice spacings,
/// decaying as |z|^n): Poisson summation (docs/multirate.md §3).
struct Quadrature {
    int n = 0;
    double K = 0.0, dk = 0.0;
};
Quadrature quadrature(const kernels::Kernel& kernel, double units_per_pixel, int h_max) {
    const auto& p = kernel.params();
    const double R = kernel.radius();
    Quadrature q;
    q.dk = 1.0 / (2.0 * R + 24.0 * h_max * units_per_pixel);
    // Up to one cycle per pixel (past the pixels' Nyquist frequency the truth aliases too, but
    // the error of each frequency is what it is), or to 24 cycles across the kernel's narrow
    // width beyond its carrier, where a kernel's spectrum is its tail: the energy past K is
    // bounded (LatticeError::beyond) rather than integrated.
    const double K = std::min(1.0 / units_per_pixel, 24.0 * p.aspect / R + p.frequency);
    // Grid kernels pay n^2 x their samples a point.
    const int n_max = kernel.is_grid() ? 96 : 1024;
    q.n = std::min(n_max, 2 * static_cast<int>(std::ceil(K / q.dk)));
    q.K = 0.5 * q.n * q.dk;
    return q;
}

/// One turn of the kernel on the quadrature grid: |H|^2 and the fraction of int |H|^2 beyond it.
struct Turn {
    std::vector<double> P;
    double beyond = 0.0;
};
Turn turn(const kernels::Kernel& kernel, const Quadrature& q, std::vector<double> grid) {
    Turn t{std::move(grid), 0.0};
    double inside = 0.0;
    for (double p : t.P) inside += p;
    inside *= q.dk * q.dk;
    const double total = kernel.integral_sq();
    // Exact up to the quadrature's rounding where the grid holds all the energy.
    t.beyond = (total - inside) / total;
    if (t.beyond < 1e-12) t.beyond = 0.0;
    return t;
}

bool turns_matter(const kernels::Kernel& kernel) {
    return kernel.has_carrier() || kernel.is_grid() || kernel.params().aspect != 1.0;
}

/// Evaluates the error of spacing after spacing on the same grids (one per turn of the
/// kernel, each the largest over the turns).
class ErrorModel {
public:
    ErrorModel(const kernels::Kernel& kernel, double units_per_pixel, int h_max, int margin)
        : m_kernel(kernel), m_s(units_per_pixel), m_margin(margin),
          m_q(quadrature(kernel, units_per_pixel, h_max)) {
        // The turns share the envelope's transform table (Kernel::power_spectrum_grids).
        const int turns = turns_matter(kernel) ? 8 : 1;
        std::vector<double> rotations;
        for (int t = 0; t < turns; ++t) rotations.push_back(0.5 * kPi * t / turns);
        auto grids = kernel.power_spectrum_grids(m_q.K, m_q.n, rotations);
        for (auto& g : grids) m_turns.push_back(turn(kernel, m_q, std::move(g)));
    }
    LatticeError at(int h) const {
        const size_t n = size_t(m_q.n);
        std::vector<double> gr(n), gi(n), A(n);  // the phase-averaged G, split, and A
        for (size_t i = 0; i < n; ++i) {
            const double k = -m_q.K + (double(i) + 0.5) * m_q.dk;
            const PhaseResponse r = phase_response(2.0 * kPi * k * h * m_s, h);
            gr[i] = r.mean.real(), gi[i] = r.mean.imag(), A[i] = r.mean_sq;
        }
        const double a = max_mean_sq(h);
        // The 8-bit noise floor in |H|^2's units: kQuantisationDensity of the variance per
        // (cycle/px)^2 is that times s^2 per (cycle/unit)^2 (docs/multirate.md §5).
        // A frequency's error may reach kSpectralFidelity of its power, or the floor where
        // that is more: err <= max(fidelity P, floor), i.e. err / max(P, floor / fidelity)
        // <= fidelity.
        const double floor = kQuantisationDensity * m_s * m_s * m_kernel.integral_sq() /
                             kSpectralFidelity;
        // The turns side by side, each into its own slot, then taken in order: the same
        // numbers for any thread count.
        std::vector<LatticeError> per_turn(m_turns.size());
        tbb::parallel_for(size_t(0), m_turns.size(), [&](size_t ti) {
            const Turn& t = m_turns[ti];
            LatticeError& e = per_turn[ti];
            double sum = 0.0, worst = 0.0;
            for (size_t j = 0; j < n; ++j) {
                const double* P = t.P.data() + j * n;
                // 1 - 2 Re(G_i G_j) + A_i A_j, with Re(G_i G_j) = gr_i gr_j - gi_i gi_j
                const double cr = 2.0 * gr[j], ci = 2.0 * gi[j], ca = A[j];
                double row = 0.0;
                for (size_t i = 0; i < n; ++i) {
                    const double err = P[i] * (1.0 - cr * gr[i] + ci * gi[i] + ca * A[i]);
                    row += err;
                    const double against = std::max(P[i], floor);
                    if (err > worst * against) worst = err / against;  // rarely: no division a point
                }
                sum += row;
            }
            const double interp = std::max(0.0, sum * m_q.dk * m_q.dk / m_kernel.integral_sq());
            e.interpolation = std::max(e.interpolation, std::sqrt(interp));
            e.beyond = std::max(e.beyond, std::sqrt(t.beyond) * (1.0 + a));
            // The energy past the quadrature (a truncated kernel's tail, spread thin beyond 24
            // cycles across it) is bounded in the rms error (beyond), not per frequency.
            e.spectral = std::max(e.spectral, worst);
        });
        LatticeError e;
        for (const LatticeError& t : per_turn) {
            e.interpolation = std::max(e.interpolation, t.interpolation);
            e.beyond = std::max(e.beyond, t.beyond);
            e.spectral = std::max(e.spectral, t.spectral);
        }
        e.boundary = 3.0 * std::pow(std::abs(kPole), m_margin);
        return e;
    }

private:
    const kernels::Kernel& m_kernel;
    double m_s;
    int m_margin;
    Quadrature m_q;
    std::vector<Turn> m_turns;
};

void check_tolerance(double tolerance) {
    if (!(tolerance >= 0.0 && tolerance <= kMaxLatticeTolerance)) {
        std::ostringstream s;
        s << "tolerance = " << tolerance << ": expected a fraction of the layer's sd in [0, "
          << kMaxLatticeTolerance << "]";
        throw ValueError(s.str());
    }
}

/// In-place cubic B-spline prefilter of the w columns of an n-row array (row k at c + k w), all
/// columns at once so the compiler vectorises the recursion across the row (Unser et al. 1991:
/// causal then anticausal first-order recursions with pole z, gain 6; the causal start sums
/// the first samples, the anticausal one is the mirror-symmetric closed form). The margin
/// nodes absorb the start's error (|z|^margin at the view).
void prefilter_across(float* c, int w, int n) {
    if (n < 2) return;
    const float z = static_cast<float>(kPole);
    auto row = [&](int k) { return c + size_t(k) * w; };
    std::vector<float> start(size_t(w), 0.0f);
    float zk = 1.0f;
    for (int k = 0; k < std::min(n, 16); ++k, zk *= z)
        for (int i = 0; i < w; ++i) start[size_t(i)] += zk * row(k)[i];
    std::copy(start.begin(), start.end(), row(0));
    for (int k = 1; k < n; ++k) {
        float* r = row(k);
        const float* p = row(k - 1);
        for (int i = 0; i < w; ++i) r[i] += z * p[i];
    }
    const float g = z / (z * z - 1.0f);
    for (int i = 0; i < w; ++i) row(n - 1)[i] = g * (row(n - 1)[i] + z * row(n - 2)[i]);
    for (int k = n - 2; k >= 0; --k) {
        float* r = row(k);
        const float* p = row(k + 1);
        for (int i = 0; i < w; ++i) r[i] = z * (p[i] - r[i]);
    }
    for (size_t i = 0; i < size_t(w) * n; ++i) c[i] *= 6.0f;
}

/// The rows' prefilter, 16 rows at a time: each block transposed so that its rows are the
/// columns of a 16-wide array, filtered across (vectorised), and put back. Every sample goes
/// through the same operations in the same order as a row filtered alone.
void prefilter_rows(Frame& f) {
    constexpr int kBlock = 16;
    const int w = f.width, n = f.height;
    if (w < 2) return;
    tbb::parallel_for(0, (n + kBlock - 1) / kBlock, [&](int b) {
        const int r0 = b * kBlock, rows = std::min(kBlock, n - r0);
        std::vector<float> t(size_t(w) * kBlock, 0.0f);
        for (int j = 0; j < rows; ++j) {
            const float* src = f.data.data() + size_t(r0 + j) * w;
            for (int k = 0; k < w; ++k) t[size_t(k) * kBlock + j] = src[k];
        }
        prefilter_across(t.data(), kBlock, w);
        for (int j = 0; j < rows; ++j) {
            float* dst = f.data.data() + size_t(r0 + j) * w;
            for (int k = 0; k < w; ++k) dst[k] = t[size_t(k) * kBlock + j];
        }
    });
}

/// One row of the pass along x: pixel i = n h + p takes node n's four-node stencil (from `c`,
/// the node before the pixel's first) with phase p's weights. H is h at compile time for the
/// common spacings (the loop over p unrolled, so the compiler vectorises across n), 0 for any.
template <int H>
void reconstruct_row(const float* c, const std::vector<std::array<float, 4>>& weights, int h,
                     int W, float* t) {
    const int hh = H > 0 ? H : h;
    const int whole = W / hh;  // nodes whose h pixels all lie in the row
    for (int n = 0; n < whole; ++n) {
        const float* q = c + n;
        for (int p = 0; p < hh; ++p) {
            const auto& w = weights[size_t(p)];
            t[n * hh + p] = ((w[0] * q[0] + w[1] * q[1]) + w[2] * q[2]) + w[3] * q[3];
        }
    }
    for (int i = whole * hh; i < W; ++i) {
        const auto& w = weights[size_t(i - whole * hh)];
        const float* q = c + whole;
        t[i] = ((w[0] * q[0] + w[1] * q[1]) + w[2] * q[2]) + w[3] * q[3];
    }
}

}  // namespace

double LatticeError::total() const {
    return std::sqrt(interpolation * interpolation + beyond * beyond + boundary * boundary);
}

LatticeError lattice_error(const kernels::Kernel& kernel, double units_per_pixel, int h,
                           int margin) {
    return ErrorModel(kernel, units_per_pixel, h, margin).at(h);
}

int lattice_margin(double tolerance) {
    check_tolerance(tolerance);
    if (tolerance == 0.0) return 0;
    const int m = static_cast<int>(std::ceil(std::log(tolerance / 20.0) / std::log(-kPole)));
    return std::max(4, m) + 2;
}

LatticeRule choose_lattice(const kernels::Kernel& kernel, double units_per_pixel,
                           double tolerance, bool keep_spectrum, double max_bytes) {
    check_tolerance(tolerance);
    LatticeRule rule;
    // A grid kernel's spectrum is a sum over its samples at every frequency (n^2 x the
    // quadrature's points, minutes for a 257^2 design): such kernels are drawn directly until
    // their spectrum is tabulated by FFT (docs/multirate.md §4).
    if (tolerance == 0.0 || kernel.is_grid()) return rule;
    // Spacings up to a third of the kernel's radius: the spectrum asks for about a seventh
    // (Gaussians h ~ sigma / 2 = R / 7.4, docs/multirate.md §5), and the quadrature's points
    // grow with the largest spacing tried (dk = 1 / (2R + 24 h_max s)): trying spacings up to
    // the radius made the rule 4-8x dearer at every scene load for nothing.
    const int h_max = std::min(kMaxLatticeSpacing,
                               static_cast<int>(std::floor(kernel.radius() / (3.0 * units_per_pixel))));
    std::vector<int> spacings;
    for (int h : {2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64})
        if (h <= h_max) spacings.push_back(h);
    if (spacings.empty()) return rule;
    const int margin = lattice_margin(tolerance);
    const Quadrature q = quadrature(kernel, units_per_pixel, spacings.back());
    const double turns = turns_matter(kernel) ? 8.0 : 1.0;
    if (turns * double(q.n) * q.n * sizeof(double) > max_bytes) {
        rule.over_memory = true;
        return rule;
    }
    const ErrorModel model(kernel, units_per_pixel, spacings.back(), margin);
    for (int h : spacings) {  // the error grows with h: stop at the first over the tolerance
        const LatticeError e = model.at(h);
        const double total = e.total(), spectral = keep_spectrum ? e.spectral : 0.0;
        if (total > tolerance || spectral > kSpectralFidelity) {
            rule.next_error = total, rule.next_spectral = spectral;
            break;
        }
        rule.spacing = h, rule.margin = margin, rule.predicted_error = total;
        rule.spectral_error = spectral;
    }
    return rule;
}

View lattice_view(const View& view, const LatticeRule& rule) {
    if (rule.spacing == 1 && rule.margin == 0) return view;
    const int h = rule.spacing, m = rule.margin;
    View v;
    v.scale = view.scale * h;
    // Node n on pixel n h's centre: x0 + (n h + 1/2) s = v.x0 + (n + m + 1/2) h s.
    v.x0 = view.x0 + (0.5 - 0.5 * h - double(m) * h) * view.scale;
    v.y0 = view.y0 + (0.5 - 0.5 * h - double(m) * h) * view.scale;
    v.width = (view.width - 1) / h + 1 + 2 * m;
    v.height = (view.height - 1) / h + 1 + 2 * m;
    return v;
}

void add_reconstruction(Frame& nodes, const LatticeRule& rule, const View& view, Frame& out) {
    const int h = rule.spacing, m = rule.margin, W = view.width, H = view.height;
    const int wn = nodes.width;
    prefilter_rows(nodes);
    prefilter_across(nodes.data.data(), nodes.width, nodes.height);
    std::vector<std::array<float, 4>> weights(static_cast<size_t>(h));
    for (int p = 0; p < h; ++p) {
        const auto w = bspline_weights(double(p) / h);
        for (int k = 0; k < 4; ++k) weights[size_t(p)][size_t(k)] = static_cast<float>(w[size_t(k)]);
    }
    // Along x on the node rows the pixels need (m - 1 .. (H - 1) / h + m + 2), then along y.
    const int r0 = m - 1, rows = (H - 1) / h + 4;
    // The node frame covers the taps: 4 rows and columns from m - 1 around every pixel's node
    // (lattice_view's margin), and the output is the view.
    IMPULSE_DCHECK(m >= 1 && h >= 1);
    IMPULSE_DCHECK(nodes.height >= r0 + rows && nodes.width >= m - 1 + (W - 1) / h + 4);
    IMPULSE_DCHECK(out.width == W && out.height == H && out.data.size() == size_t(W) * H);
    std::vector<float> across(static_cast<size_t>(rows) * W);
    tbb::parallel_for(0, rows, [&](int r) {
        const float* c = nodes.data.data() + size_t(r0 + r) * wn + (m - 1);
        float* t = across.data() + size_t(r) * W;
        switch (h) {
            case 2: return reconstruct_row<2>(c, weights, h, W, t);
            case 3: return reconstruct_row<3>(c, weights, h, W, t);
            case 4: return reconstruct_row<4>(c, weights, h, W, t);
            default: return reconstruct_row<0>(c, weights, h, W, t);
        }
    });
    tbb::parallel_for(0, H, [&](int j) {
        const auto& w = weights[size_t(j % h)];
        const float* a = across.data() + size_t(j / h) * W;
        const float *b = a + W, *c = b + W, *d = c + W;
        float* o = out.data.data() + size_t(j) * W;
        for (int i = 0; i < W; ++i) o[i] += ((w[0] * a[i] + w[1] * b[i]) + w[2] * c[i]) + w[3] * d[i];
    });
}

void accumulate_lattice(const kernels::Kernel& kernel, const sim::Impulses& impulses,
                        const View& view, const LatticeRule& rule, Frame& out,
                        const EvalOptions& options) {
    if (rule.spacing == 1) return accumulate(kernel, impulses, view, out, options);
    const View lattice = lattice_view(view, rule);
    Frame nodes;
    nodes.resize(lattice.width, lattice.height);
    accumulate(kernel, impulses, lattice, nodes, options);
    add_reconstruction(nodes, rule, view, out);
}

}  // namespace impulse::render
