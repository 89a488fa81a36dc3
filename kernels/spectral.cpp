// SPDX-License-Identifier: Apache-2.0
// Kernels from a spectrum or an autocorrelation (Lewis 1986 §3: the field's spectrum is the
// kernel's |H|^2, so h = F^-1[sqrt(S)]; Lewis 1986 §2 and 1987: an autocorrelation must be
// non-negative definite, i.e. its spectrum S = F[R] >= 0).
//
// 2-D transforms of isotropic functions are Hankel transforms, G(k) = 2 pi int g(r) J0(2 pi k r)
// r dr (the same formula in both directions with the convention H(k) = int h e^{-2 pi i k.x}).

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>

#include "numeric/fft.h"
#include "kernels/kernels.h"
#include "kernels/quadrature.h"
#include "numeric/errors.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;
/// S below -kNegativeThreshold * max S is a real negative lobe, not quadrature noise.
constexpr double kNegativeThreshold = 1e-6;
/// R is integrated out to where |R| < kAcfTail R(0).
constexpr double kAcfTail = 1e-9;
constexpr double kAcfMaxRadius = 4096.0;
/// The taper of DesignWindow::Hann/Gaussian covers the outer (1 - kTaperStart) of the radius.
constexpr double kTaperStart = 0.8;

std::string num(double v) {
    std::ostringstream s;
    s << std::setprecision(4) << v;
    return s.str();
}

void require(bool ok, const std::string& key, double value, const char* expected) {
    if (!ok || !std::isfinite(value))
        throw ValueError(key + " = " + num(value) + ": expected " + expected);
}

/// Gauss–Legendre nodes and weights.
struct Nodes {
    std::vector<double> x, w;
    void add(double a, double b, int panels) {
        const double* gx = detail::gl_nodes();
        const double* gw = detail::gl_weights();
        const double h = (b - a) / panels;
        for (int p = 0; p < panels; ++p) {
            const double mid = a + (p + 0.5) * h;
            for (int i = 0; i < detail::kGlPoints; ++i) {
                x.push_back(mid + 0.5 * h * gx[i]);
                w.push_back(0.5 * h * gw[i]);
            }
        }
    }
};

/// Raised-cosine roll-off of sqrt(S): 1 up to the pass band kp, 0 from K on.
double rolloff(double k, double K, double kp) {
    if (k <= kp) return 1.0;
    if (k >= K) return 0.0;
    return 0.5 + 0.5 * std::cos(kPi * (k - kp) / (K - kp));
}

/// Radial window of a designed kernel of radius R whose taper starts at a.
double window_weight(DesignWindow w, double r, double R, double a) {
    if (r > R) return 0.0;
    if (w == DesignWindow::None || r <= a) return 1.0;
    if (w == DesignWindow::Hann) return 0.5 + 0.5 * std::cos(kPi * (r - a) / (R - a));
    const double s = (R - a) / 3.0;  // Gaussian: 3 sigma over the taper (1.1 % at R)
    return std::exp(-0.5 * (r - a) * (r - a) / (s * s));
}

double sinc(double x) { return x == 0.0 ? 1.0 : std::sin(kPi * x) / (kPi * x); }

/// The radial transform of an isotropic function in the plane or in space (both directions,
/// with H(k) = int h e^{-2 pi i k.x}): G(k) = int g(r) basis(2 pi k r) shell(r) dr, the shell
/// 2 pi r and basis J0 in 2-D (Hankel), the shell 4 pi r^2 and basis sin x / x in 3-D (the
/// Hankel transform of order 1/2: G(k) = (2 / k) int g(r) sin(2 pi k r) r dr).
struct Radial {
    int dims = 2;
    /// Quadrature weight w times the shell measure at x (2-D: the expression order of the
    /// original 2-D code, so 2-D designs keep their bits).
    double shell(double w, double x) const {
        return dims == 2 ? 2 * kPi * w * x : 4 * kPi * w * x * x;
    }
    double basis(double x) const {
        if (dims == 2) return detail::bessel_j0(x);
        return x == 0.0 ? 1.0 : std::sin(x) / x;
    }
};

/// A sample of a spectrum, for the negativity report.
struct SpectrumSample {
    double k, theta, s;
};

/// Throws when samples fall below -kNegativeThreshold * smax, listing the most negative values
/// (at most three, one per negative lobe). `ordered`: samples are consecutive along k, and a lobe
/// is a run of consecutive negative samples; otherwise lobes are told apart by a distance of at
/// least `separation` in the frequency plane (a sample and its mirror -k count as one).
void refuse_negative(const std::vector<SpectrumSample>& samples, double smax, bool ordered,
                     double separation, const std::string& what, bool show_theta) {
    const double limit = -kNegativeThreshold * smax;
    std::vector<SpectrumSample> lobes;
    if (ordered) {
        for (size_t i = 0; i < samples.size(); ++i) {
            if (!(samples[i].s < limit)) continue;
            SpectrumSample low = samples[i];
            for (; i < samples.size() && samples[i].s < limit; ++i)
                if (samples[i].s < low.s) low = samples[i];
            lobes.push_back(low);
        }
    } else {
        for (const auto& s : samples)
            if (s.s < limit) lobes.push_back(s);
    }
    if (lobes.empty()) return;
    std::stable_sort(lobes.begin(), lobes.end(),
                     [](const auto& a, const auto& b) { return a.s < b.s; });
    std::vector<SpectrumSample> shown;
    for (const auto& b : lobes) {
        bool near = false;
        for (const auto& s : shown) {
            const double bx = b.k * std::cos(b.theta), by = b.k * std::sin(b.theta);
            const double sx = s.k * std::cos(s.theta), sy = s.k * std::sin(s.theta);
            near |= !ordered && (std::hypot(bx - sx, by - sy) < separation ||
                                 std::hypot(bx + sx, by + sy) < separation);
        }
        if (!near) shown.push_back(b);
        if (shown.size() == 3) break;
    }
    std::ostringstream m;
    m << what << ": ";
    for (size_t i = 0; i < shown.size(); ++i) {
        m << (i ? ", " : "") << "S(" << num(shown[i].k);
        if (show_theta) m << ", theta = " << num(shown[i].theta);
        m << ") = " << num(shown[i].s);
    }
    m << " (a power spectrum must be >= 0; values below -" << kNegativeThreshold
      << " max S = " << num(limit) << " are not numerical noise)";
    throw ValueError(m.str());
}

void require_finite_sample(const std::string& name, double k, double s) {
    if (!std::isfinite(s))
        throw ValueError(name + ": S(" + num(k) + ") = " + num(s) +
                         ": expected a finite number (a spectrum must be finite; add a low-"
                         "frequency cut-off such as (k^2 + 0.01^2)^(-d/2))");
}

// ---------------------------------------------------------------------------------------------
// Models

double markov_s(double k, double l) {
    return 2 * kPi * l * l * std::pow(1 + std::pow(2 * kPi * l * k, 2), -1.5);
}

/// int_0^inf |k| g(k - f0) dk + int_0^inf k g(k + f0) dk for g(x) = exp(-x^2 / (2 w^2)): the
/// ring's radial moment (E|X| sqrt(2 pi) w for X ~ N(f0, w^2)).
double bandpass_moment(double f0, double w) {
    const double e_abs = w * std::sqrt(2.0 / kPi) * std::exp(-f0 * f0 / (2 * w * w)) +
                         f0 * std::erf(f0 / (w * std::sqrt(2.0)));
    return e_abs * std::sqrt(2 * kPi) * w;
}

double power_shape(const ModelParams& p, double k) {
    double s = std::pow(1.0 + (k / p.k_low) * (k / p.k_low), -0.5 * p.slope);
    if (p.k_high > 0) s *= std::exp(-(k / p.k_high) * (k / p.k_high));
    return s;
}

/// int power_shape d^2k.
double power_norm(const ModelParams& p) {
    if (p.k_high == 0.0) return 2 * kPi * p.k_low * p.k_low / (p.slope - 2.0);
    // k = k_low e^u, d^2k = 2 pi k^2 du, from 1e-6 k_low (the rest is < 1e-12 k_low^2) to
    // 8 k_high (exp(-64) beyond).
    const double u0 = std::log(1e-6), u1 = std::log(8.0 * p.k_high / p.k_low);
    if (u1 <= u0) return 0.0;
    return 2 * kPi *
           detail::integrate(
               [&](double u) {
                   const double k = p.k_low * std::exp(u);
                   return power_shape(p, k) * k * k;
               },
               u0, u1, 400);
}

// ---------------------------------------------------------------------------------------------
// CSV tables

struct Table {
    std::vector<double> k, s;
    double operator()(double q) const {
        if (q <= k.front()) return s.front();
        if (q > k.back()) return 0.0;
        // At the last row upper_bound finds the end: there is no segment after it to interpolate.
        if (q == k.back()) return s.back();
        const size_t i = std::upper_bound(k.begin(), k.end(), q) - k.begin() - 1;
        const double t = (q - k[i]) / (k[i + 1] - k[i]);
        return s[i] + t * (s[i + 1] - s[i]);
    }
};

bool parse_number(std::string_view field, double& out) {
    size_t a = 0, b = field.size();
    while (a < b && std::isspace(static_cast<unsigned char>(field[a]))) ++a;
    while (b > a && std::isspace(static_cast<unsigned char>(field[b - 1]))) --b;
    if (a == b) return false;
    const std::string s(field.substr(a, b - a));
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return end == s.c_str() + s.size();
}

// ---------------------------------------------------------------------------------------------
// Radial (isotropic) design

/// Checks S(k) on a fine grid of [0, K]: finite, not negative beyond noise, not all zero.
void check_radial_spectrum(const Spectrum& sp, double K) {
    const int nc = 4096;
    std::vector<SpectrumSample> check(nc + 1);
    double smax = 0.0;
    for (int i = 0; i <= nc; ++i) {
        const double k = K * i / nc;
        const double s = sp.density(k, 0.0);
        require_finite_sample(sp.name, k, s);
        check[i] = {k, 0.0, s};
        smax = std::max(smax, s);
    }
    if (!(smax > 0.0))
        throw ValueError(sp.name + ": S(k) <= 0 everywhere on [0, " + num(K) +
                         "]: nothing to design");
    refuse_negative(check, smax, true, 0.0, sp.name + " is negative", false);
}

/// The amplitude A = sqrt(S) T at Gauss–Legendre nodes on [0, kp] and [kp, K] (T has a kink at
/// kp), as the weights of the Hankel transform h(r) = sum_j wa_j J0(2 pi k_j r).
struct RadialAmplitude {
    Nodes n;
    std::vector<double> wa;  // 2 pi w_j k_j sqrt(S_j) T_j
    double energy = 0.0;     // 2 pi sum w_j k_j S_j T_j^2 = int A^2 d^2k
};

/// The panel count resolves J0(2 pi k r) up to r_hi (2 panels = 32 nodes per period 1/r_hi)
/// and features of S down to K/256.
RadialAmplitude radial_amplitude(const Radial& rad, const Spectrum& sp, double K, double kp,
                                 double r_hi) {
    RadialAmplitude a;
    const int panels = std::max(256, 32 + static_cast<int>(std::ceil(2.0 * K * r_hi)));
    const int pass = std::max(1, static_cast<int>(std::lround(panels * kp / K)));
    if (kp > 0) a.n.add(0.0, kp, pass);
    if (K > kp) a.n.add(kp, K, std::max(16, panels - pass));
    for (size_t j = 0; j < a.n.x.size(); ++j) {
        const double k = a.n.x[j];
        const double amp = std::sqrt(std::max(sp.density(k, 0.0), 0.0)) * rolloff(k, K, kp);
        a.wa.push_back(rad.shell(a.n.w[j], k) * amp);
        a.energy += rad.shell(a.n.w[j], k) * amp * amp;
    }
    return a;
}

/// h(r) = int A(k) J0(2 pi k r) 2 pi k dk (the 2-D inverse Fourier transform of a radial A; in
/// 3-D int A(k) sinc(2 pi k r) 4 pi k^2 dk).
double radial_h(const Radial& rad, const RadialAmplitude& a, double r) {
    double s = 0.0;
    for (size_t j = 0; j < a.wa.size(); ++j)
        s += a.wa[j] * rad.basis(2 * kPi * a.n.x[j] * r);
    return s;
}

/// The radius for `o.energy` of the kernel energy: the energy radius R_f where
/// 2 pi int_0^R_f h^2 r dr reaches `energy` of the total (Parseval: int h^2 = int A^2 d^2k).
/// 16-point Gauss–Legendre panels of width 1/K (two periods of h^2, whose band reaches 2K);
/// not the trapezoid rule, whose Euler–Maclaurin end correction dr^2/12 * 2 pi h(0)^2 at
/// r = 0 is ~1 % for peaked kernels (markov). Within the panel that crosses the target, R_f is
/// interpolated linearly; a window's taper starts at R_f.
double radial_energy_radius(const Radial& rad, const Spectrum& sp, const DesignOptions& o,
                            double K, double kp, double total) {
    const bool tapered = o.window != DesignWindow::None;
    const double limit = tapered ? kTaperStart * o.max_radius : o.max_radius;
    const double pw = 1.0 / K, target = o.energy * total;
    double cum = 0.0, r = 0.0, rf = -1.0;
    while (rf < 0.0) {
        const double chunk_end = r + 64.0 * pw;
        const RadialAmplitude a = radial_amplitude(rad, sp, K, kp, chunk_end);
        for (; r < chunk_end - 0.5 * pw; r += pw) {
            Nodes pn;
            pn.add(r, r + pw, 1);
            double add = 0.0;
            for (size_t j = 0; j < pn.x.size(); ++j) {
                const double h = radial_h(rad, a, pn.x[j]);
                add += rad.shell(pn.w[j], pn.x[j]) * h * h;
            }
            if (cum + add >= target) {
                rf = r + pw * (target - cum) / add;
                break;
            }
            cum += add;
            if (r + pw > limit) {
                throw ValueError(sp.name + ": keeping " + num(100 * o.energy) +
                                 " % of the kernel energy needs a radius beyond " +
                                 num(tapered ? limit / kTaperStart : limit) +
                                 " units (max_radius = " + num(o.max_radius) + "; " +
                                 num(100 * cum / total) +
                                 " % kept there): lower energy, give a radius, or raise "
                                 "max_radius");
            }
        }
    }
    return std::max(tapered ? rf / kTaperStart : rf, 1.0 / K);
}

/// The windowed profile h(r) at n samples on [0, R], zero at R.
std::shared_ptr<SampledKernel> radial_profile(const Radial& rad, const RadialAmplitude& a,
                                              const DesignOptions& o, double R, int n) {
    const bool tapered = o.window != DesignWindow::None;
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = true;
    sk->n = n;
    sk->values.resize(n);
    const double taper_start = tapered ? kTaperStart * R : R;
    for (int i = 0; i < n; ++i) {
        const double r = R * i / (n - 1);
        sk->values[i] = radial_h(rad, a, r) * window_weight(o.window, r, R, taper_start);
    }
    sk->values[n - 1] = 0.0;  // the profile is zero from R on
    return sk;
}

/// |H|^2 of the final profile (as Kernel evaluates it) against S on [0, K]: the relative
/// spectrum error, the achieved |H|^2 and the worst ratio error in the pass band; the energy
/// kept of the amplitude's `amplitude_energy` and the effective area (int h^2)^2 / int h^4.
void report_radial_spectrum(DesignReport& rep, const Radial& rad, const Kernel& kern,
                            const Spectrum& sp, const DesignOptions& o, double amplitude_energy,
                            double kp, double R, int n) {
    const double K = o.nyquist;
    Nodes rn;
    rn.add(0.0, R, std::max({64, (n - 1) / 2, 32 + static_cast<int>(std::ceil(2.0 * K * R))}));
    std::vector<double> hr(rn.x.size());
    double i2 = 0.0, i4 = 0.0;  // int h^2, int h^4 over space (3-D)
    for (size_t j = 0; j < rn.x.size(); ++j) {
        const double e = kern.envelope(rn.x[j] * rn.x[j] / (R * R));
        hr[j] = rad.shell(rn.w[j], rn.x[j]) * e;
        i2 += hr[j] * e;
        i4 += hr[j] * e * e * e;
    }
    if (o.dims == 2) {  // the kernel's own integrals, as before 3-D designs existed
        i2 = kern.integral_sq();
        i4 = kern.integral_4();
    }
    rep.energy_fraction = i2 / amplitude_energy;
    rep.effective_area = i2 * i2 / i4;
    const int M = 256;
    double num2 = 0.0, den2 = 0.0, pmax = 0.0;
    std::vector<double> hk2(M + 1), sm(M + 1);
    for (int m = 0; m <= M; ++m) {
        const double k = K * m / M;
        double H = 0.0;
        for (size_t j = 0; j < rn.x.size(); ++j)
            H += hr[j] * rad.basis(2 * kPi * k * rn.x[j]);
        hk2[m] = H * H;
        sm[m] = std::max(sp.density(k, 0.0), 0.0);
        pmax = std::max(pmax, sm[m]);
        const double wt = (m == 0 || m == M ? 0.5 : 1.0) * (o.dims == 2 ? k : k * k);
        num2 += wt * (hk2[m] - sm[m]) * (hk2[m] - sm[m]);
        den2 += wt * sm[m] * sm[m];
    }
    rep.spectrum_error = den2 > 0 ? std::sqrt(num2 / den2) : 0.0;
    rep.achieved = hk2;
    for (int m = 0; m <= M; ++m)
        if (K * m / M <= kp && sm[m] >= 0.01 * pmax)
            rep.passband_error = std::max(rep.passband_error, std::abs(hk2[m] / sm[m] - 1.0));
}

/// The largest error, relative to max |h|, of what the renderer evaluates: the Chebyshev
/// polynomial, or the q-table (linear in q, so coarse in r near the centre: the first entry
/// spans r < R / 64).
double radial_render_error(const SampledKernel& sk, const Kernel& kern, double R) {
    double hmax = 0.0, err = 0.0;
    for (double v : sk.values) hmax = std::max(hmax, std::abs(v));
    const auto& table = kern.envelope_table();
    for (int i = 0; i < 20000; ++i) {
        const double r = R * i / 20000.0, q = (r / R) * (r / R);
        double fast;
        if (!table.empty()) {
            const double x = q * (table.size() - 1);
            const size_t t = std::min(static_cast<size_t>(x), table.size() - 2);
            fast = table[t] + (x - t) * (table[t + 1] - table[t]);
        } else {
            fast = kern.polynomial().evaluate(static_cast<float>(q));
        }
        err = std::max(err, std::abs(fast - kern.envelope(q)));
    }
    return hmax > 0 ? err / hmax : 0.0;
}

DesignedKernel design_radial(const Spectrum& sp, const DesignOptions& o) {
    const double K = o.nyquist, kp = (1.0 - o.rolloff) * K;
    const Radial rad{o.dims};
    check_radial_spectrum(sp, K);
    const double total = radial_amplitude(rad, sp, K, kp, 0.0).energy;
    const double R = o.radius == 0.0 ? radial_energy_radius(rad, sp, o, K, kp, total) : o.radius;

    // Samples for the Catmull–Rom profile: 16 per shortest period 1/K (interpolation error
    // < 0.1 % at K), at most 4097.
    const int n = std::clamp(static_cast<int>(std::ceil(16.0 * K * R)) + 1, 64, 4097);
    const RadialAmplitude a = radial_amplitude(rad, sp, K, kp, R);
    const auto sk = radial_profile(rad, a, o, R, n);
    DesignedKernel out;
    out.params.type = KernelType::Sampled;
    out.params.radius = R;
    out.params.sampled = sk;
    const Kernel kern(out.params);

    DesignReport& rep = out.report;
    rep.radius = R;
    rep.samples = n;
    rep.passband = kp;
    report_radial_spectrum(rep, rad, kern, sp, o, a.energy, kp, R, n);
    rep.render_error = radial_render_error(*sk, kern, R);
    return out;
}

// ---------------------------------------------------------------------------------------------
// Grid (angle-dependent) design

/// The smallest even 2^a 3^b 5^c >= max(n, 16): a fast FFT size.
int fft_size(int n) {
    for (int m = std::max(n, 16);; ++m) {
        if (m % 2) continue;
        int x = m;
        for (int f : {2, 3, 5})
            while (x % f == 0) x /= f;
        if (x == 1) return m;
    }
}

/// Fills `inv`'s half-plane spectrum with the amplitude sqrt(S) T / (sinc^2 sinc^2) on an
/// N x N grid of spacing d (the sinc^2 of the bilinear interpolant compensated) and returns
/// the symmetrised target S there. With `check`, first refuses a non-finite, negative or zero S.
std::vector<double> grid_amplitude(const Spectrum& sp, double K, double kp, int N, double d,
                                   bool check, numeric::RealFft2d& inv) {
    const double dk = 1.0 / (N * d);
    const int hw = N / 2 + 1;
    std::vector<double> target(size_t(N) * hw, 0.0);  // symmetrised S on the half grid
    std::vector<SpectrumSample> samples;
    double smax = 0.0;
    for (int j = 0; j < N; ++j) {
        const int sj = j < N / 2 ? j : j - N;
        for (int i = 0; i < hw; ++i) {
            const int si = i == N / 2 ? -i : i;  // the Nyquist column is its own mirror
            const double kx = si * dk, ky = sj * dk, k = std::hypot(kx, ky);
            if (k >= K) continue;
            const double th = std::atan2(ky, kx);
            const double s1 = sp.density(k, th), s2 = sp.density(k, th + (th > 0 ? -kPi : kPi));
            require_finite_sample(sp.name, k, s1);
            require_finite_sample(sp.name, k, s2);
            if (check) samples.push_back({k, th, std::min(s1, s2)});
            // A real field has S(k) = S(-k): use the symmetric part (Lewis 1987: the
            // spectrum of a real noise is symmetric).
            const double s = 0.5 * (s1 + s2);
            smax = std::max(smax, std::max(s1, s2));
            target[size_t(j) * hw + i] = std::max(s, 0.0);
            const double comp = std::pow(sinc(kx * d) * sinc(ky * d), 2);
            inv.spectrum()[size_t(j) * hw + i] =
                std::sqrt(std::max(s, 0.0)) * rolloff(k, K, kp) / comp;
        }
    }
    if (check) {
        if (!(smax > 0.0))
            throw ValueError(sp.name + ": S <= 0 everywhere on |k| < " + num(K) +
                             ": nothing to design");
        refuse_negative(samples, smax, false, 0.125 * K, sp.name + " is negative", true);
    }
    return target;
}

/// h at signed sample indices (x, y) of the periodic N x N grid.
double periodic_at(const std::vector<double>& h, int N, int x, int y) {
    return h[size_t((y + N) % N) * N + size_t((x + N) % N)];
}

/// The energy of h in rings of width d/2 about the centre, and in all.
struct RingEnergy {
    std::vector<double> ring;
    double total = 0.0;
};

RingEnergy ring_energy(const std::vector<double>& h, int N) {
    RingEnergy e;
    const int rings = N;  // radius up to N d / sqrt(2) < N * d/2 * 2
    e.ring.assign(rings + 1, 0.0);
    for (int y = -N / 2; y < N / 2; ++y)
        for (int x = -N / 2; x < N / 2; ++x) {
            const double v = periodic_at(h, N, x, y);
            const int b = std::min(rings, static_cast<int>(2.0 * std::hypot(x, y)));
            e.ring[b] += v * v;
            e.total += v * v;
        }
    return e;
}

/// The radius holding `o.energy` of the total (interpolated within its ring); a window's
/// taper starts there. Refuses one beyond max_radius.
double grid_energy_radius(const Spectrum& sp, const DesignOptions& o, const RingEnergy& e,
                          double d) {
    const bool tapered = o.window != DesignWindow::None;
    double cum = 0.0, rf = 0.0;
    for (size_t b = 0; b < e.ring.size(); ++b) {
        if (cum + e.ring[b] >= o.energy * e.total) {
            rf = 0.5 * d * (int(b) + (o.energy * e.total - cum) / e.ring[b]);
            break;
        }
        cum += e.ring[b];
    }
    const double R = std::max(tapered ? rf / kTaperStart : rf, 2.0 * d);
    if (R > o.max_radius)
        throw ValueError(sp.name + ": keeping " + num(100 * o.energy) +
                         " % of the kernel energy needs a radius of " + num(R) +
                         " units (max_radius = " + num(o.max_radius) +
                         "): lower energy, give a radius, or raise max_radius");
    return R;
}

/// h cropped to R (rounded up to whole samples) and windowed, also written into `fwd`'s real
/// grid for the report; the report's radius, samples and energy fraction filled.
DesignedKernel crop_grid_kernel(const std::vector<double>& h, int N, double d, double R,
                                const DesignOptions& o, double total, numeric::RealFft2d& fwd) {
    const bool tapered = o.window != DesignWindow::None;
    const int m = static_cast<int>(std::ceil(R / d - 1e-9));
    R = m * d;
    const int n = 2 * m + 1;
    const double taper_start = tapered ? kTaperStart * R : R;
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = false;
    sk->n = n;
    sk->values.assign(size_t(n) * n, 0.0);
    double kept = 0.0;
    for (int y = -m; y <= m; ++y)
        for (int x = -m; x <= m; ++x) {
            const double v = periodic_at(h, N, x, y) *
                             window_weight(o.window, std::hypot(x, y) * d, R, taper_start);
            sk->values[size_t(y + m) * n + size_t(x + m)] = v;
            fwd.real()[size_t((y + N) % N) * N + size_t((x + N) % N)] = v;
            kept += v * v;
        }
    DesignedKernel out;
    out.params.type = KernelType::Sampled;
    out.params.radius = R;
    out.params.sampled = sk;
    out.report.radius = R;
    out.report.samples = n;
    out.report.grid = true;
    out.report.energy_fraction = kept / total;
    return out;
}

/// |H(k)|^2 of the bilinear interpolant, (d^2 sinc^2(kx d) sinc^2(ky d) |DFT|)^2 (exact at the
/// grid frequencies), against the target: the spectrum error and the pass-band error. Both
/// halves of the plane count (weights 2 except columns 0 and N/2). `fwd` holds the kernel.
void report_grid_spectrum(DesignReport& rep, numeric::RealFft2d& fwd,
                          const std::vector<double>& target, int N, double d, double K, double kp) {
    const double dk = 1.0 / (N * d);
    const int hw = N / 2 + 1;
    fwd.forward();
    double num2 = 0.0, den2 = 0.0, pmax = 0.0;
    for (double t : target) pmax = std::max(pmax, t);
    for (int j = 0; j < N; ++j) {
        const int sj = j < N / 2 ? j : j - N;
        for (int i = 0; i < hw; ++i) {
            const double kx = i * dk, ky = sj * dk, k = std::hypot(kx, ky);
            if (k >= K) continue;
            const double f = d * d * std::pow(sinc(kx * d) * sinc(ky * d), 2);
            const double H2 = f * f * std::norm(fwd.spectrum()[size_t(j) * hw + i]);
            const double s = target[size_t(j) * hw + i];
            const double wt = (i == 0 || i == N / 2) ? 1.0 : 2.0;
            num2 += wt * (H2 - s) * (H2 - s);
            den2 += wt * s * s;
            if (k <= kp && s >= 0.01 * pmax)
                rep.passband_error = std::max(rep.passband_error, std::abs(H2 / s - 1.0));
        }
    }
    rep.spectrum_error = den2 > 0 ? std::sqrt(num2 / den2) : 0.0;
}

/// Refuses (BudgetError) an N x N design grid beyond `max_bytes` (0: no bound), before any of it
/// is allocated: a narrow lobe needs a long kernel and so a large grid (up to 2048^2, ~190 MiB).
void require_design_budget(const Spectrum& sp, int N, double max_bytes) {
    if (max_bytes <= 0.0 || grid_design_bytes(N) <= max_bytes) return;
    constexpr double kMiB = 1024.0 * 1024.0;
    throw BudgetError(sp.name + ": the design needs a " + std::to_string(N) + "^2 grid (" +
                      num(std::ceil(grid_design_bytes(N) / kMiB)) +
                      " MiB), over the budget of " + num(max_bytes / kMiB) + " MiB");
}

DesignedKernel design_grid(const Spectrum& sp, const DesignOptions& o) {
    const double K = o.nyquist, kp = (1.0 - o.rolloff) * K;
    // Grid spacing 1/(4K): the samples carry frequencies up to 2K, twice the designed band, so
    // the bilinear interpolant's images (at multiples of 4K) sit far from the band.
    const double d = 0.25 / K;
    // The FFT domain must hold the kernel plus its tail: side >= 4 R (the periodic copies of
    // the tail stay beyond 2 R). Start at 256 samples (or from the given radius), double as
    // needed, at most 2048.
    const int kMaxN = 2048;
    int N = std::max(
        256, o.radius > 0 ? fft_size(static_cast<int>(std::ceil(4.0 * o.radius / d))) : 256);
    if (N > kMaxN)
        throw ValueError(sp.name + ": radius = " + num(o.radius) + " needs a " + std::to_string(N) +
                         "^2 FFT for an angle-dependent spectrum (at most " +
                         std::to_string(kMaxN) + "^2 at nyquist = " + num(K) + ")");
    bool checked = false;
    for (;;) {
        require_design_budget(sp, N, o.max_bytes);
        const double dk = 1.0 / (N * d);
        numeric::RealFft2d inv(N, N, numeric::FftPlans::Inverse);
        const std::vector<double> target = grid_amplitude(sp, K, kp, N, d, !checked, inv);
        checked = true;
        inv.inverse();
        // h(x) = sum_k A(k) e^{2 pi i k.x} dk^2; index (i, j) <-> x = (si d, sj d).
        const double* raw = inv.real();
        std::vector<double> h(size_t(N) * N);
        for (size_t t = 0; t < h.size(); ++t) h[t] = raw[t] * dk * dk;
        const RingEnergy e = ring_energy(h, N);
        double R = o.radius;
        if (R == 0.0) {
            R = grid_energy_radius(sp, o, e, d);
            if (4.0 * R > N * d) {
                if (2 * N > kMaxN)
                    throw ValueError(sp.name + ": the kernel needs a radius of " + num(R) +
                                     " units, beyond the largest FFT for an angle-dependent "
                                     "spectrum (" +
                                     num(kMaxN * d / 4) + " units at nyquist = " + num(K) +
                                     "): lower energy or give a radius");
                N = fft_size(2 * N);
                continue;
            }
        }
        numeric::RealFft2d fwd(N, N, numeric::FftPlans::Forward);  // the final kernel's transform, for the report
        DesignedKernel out = crop_grid_kernel(h, N, d, R, o, e.total, fwd);
        DesignReport& rep = out.report;
        rep.passband = kp;
        {
            const Kernel kern(out.params);
            rep.effective_area = kern.integral_sq() * kern.integral_sq() / kern.integral_4();
        }
        report_grid_spectrum(rep, fwd, target, N, d, K, kp);
        return out;
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Models

std::optional<SpectralModel> spectral_model_from_string(std::string_view name) {
    if (name == "exponential") return SpectralModel::Markov;
    for (size_t i = 0; i < kSpectralModelNames.size(); ++i)
        if (kSpectralModelNames[i] == name) return static_cast<SpectralModel>(i);
    return std::nullopt;
}

bool defined_by_autocorrelation(SpectralModel m) {
    return m == SpectralModel::Markov || m == SpectralModel::Gaussian ||
           m == SpectralModel::Markaussian || m == SpectralModel::Matern ||
           m == SpectralModel::OscillatoryMarkov || m == SpectralModel::OscillatoryGaussian;
}

void validate(const ModelParams& p) {
    require(p.variance > 0, "variance", p.variance, "a variance > 0");
    switch (p.model) {
        case SpectralModel::Markov:
        case SpectralModel::Gaussian:
            require(p.length > 0, "length", p.length, "a length > 0");
            break;
        case SpectralModel::Markaussian:
            require(p.length > 0, "length", p.length, "a length > 0");
            require(p.exponent > 0 && p.exponent <= 2, "exponent", p.exponent,
                    "an exponent in (0, 2] (exp(-r^a) is a valid 2-D autocorrelation only there)");
            break;
        case SpectralModel::Matern:
            require(p.length > 0, "length", p.length, "a length > 0");
            require(p.nu > 0 && p.nu <= 50, "nu", p.nu, "a smoothness nu in (0, 50]");
            break;
        case SpectralModel::OscillatoryMarkov:
        case SpectralModel::OscillatoryGaussian:
            require(p.length > 0, "length", p.length, "a length > 0");
            require(p.omega >= 0 && std::isfinite(p.omega), "omega", p.omega,
                    "a finite angular frequency >= 0 (radians per unit)");
            break;
        case SpectralModel::Lorentzian:
            require(p.k0 > 0, "k0", p.k0, "a corner frequency > 0 (cycles per unit)");
            break;
        case SpectralModel::Bandpass:
            require(p.f0 >= 0, "f0", p.f0, "a centre frequency >= 0 (cycles per unit)");
            require(p.width > 0, "width", p.width, "a ring width > 0 (cycles per unit)");
            break;
        case SpectralModel::Power:
            require(p.slope > 0, "slope", p.slope, "a slope > 0 (S ~ k^-slope)");
            require(p.k_low > 0, "k_low", p.k_low, "a low cut-off > 0 (cycles per unit)");
            require(p.k_high >= 0, "k_high", p.k_high, "a high cut-off >= 0 (0: none)");
            if (p.k_high == 0 && p.slope <= 2)
                throw ValueError(
                    "slope = " + num(p.slope) +
                    ": expected > 2 without k_high (the variance int S d^2k diverges); "
                    "or set k_high > 0");
            break;
    }
}

namespace {

/// The 3-D spectra of the models defined by an autocorrelation (int S d^3k = R(0)).
Spectrum model_spectrum_3d(const ModelParams& p, double k_max) {
    const double v = p.variance, l = p.length;
    Spectrum s;
    s.name = std::string(kSpectralModelNames[static_cast<int>(p.model)]);
    switch (p.model) {
        case SpectralModel::Markov:  // the 3-D transform of e^{-r/l}
            s.density = [v, l](double k, double) {
                const double u = 1 + std::pow(2 * kPi * l * k, 2);
                return v * 8 * kPi * l * l * l / (u * u);
            };
            break;
        case SpectralModel::Gaussian:  // of e^{-r^2/l^2}
            s.density = [v, l](double k, double) {
                return v * std::pow(kPi, 1.5) * l * l * l * std::exp(-std::pow(kPi * l * k, 2));
            };
            break;
        case SpectralModel::Matern: {
            // Rasmussen & Williams 2006 eq. 4.15 in D dimensions: (4 pi / a)^(D/2)
            // Gamma(nu + D/2) / Gamma(nu) (1 + 4 pi^2 k^2 / a)^-(nu + D/2), a = 2 nu / l^2.
            const double a = 2 * p.nu / (l * l), nu = p.nu;
            const double c = v * std::pow(4 * kPi / a, 1.5) * std::tgamma(nu + 1.5) / std::tgamma(nu);
            s.density = [a, c, nu](double k, double) {
                return c * std::pow(1 + 4 * kPi * kPi * k * k / a, -(nu + 1.5));
            };
            break;
        }
        case SpectralModel::Markaussian:
        case SpectralModel::OscillatoryMarkov:
        case SpectralModel::OscillatoryGaussian:
            s.density = spectrum_of_autocorrelation(model_autocorrelation(p), k_max, 3).density;
            break;
        default:
            throw ValueError("model = \"" + s.name +
                             "\": its spectrum is defined in 2-D; for a 3-D kernel give an "
                             "expression or a table of the 3-D spectrum S(k), or a model defined by "
                             "its autocorrelation (markov, gaussian, markaussian, matern, "
                             "oscillatory_markov, oscillatory_gaussian)");
    }
    return s;
}

}  // namespace

Spectrum model_spectrum(const ModelParams& params, double k_max, int dims) {
    validate(params);
    if (dims != 2 && dims != 3)
        throw ValueError("dims = " + std::to_string(dims) + ": expected 2 or 3");
    if (dims == 3) return model_spectrum_3d(params, k_max);
    const ModelParams p = params;
    const double v = p.variance;
    Spectrum s;
    s.name = std::string(kSpectralModelNames[static_cast<int>(p.model)]);
    switch (p.model) {
        case SpectralModel::Markov:
            s.density = [p, v](double k, double) { return v * markov_s(k, p.length); };
            break;
        case SpectralModel::Gaussian:
            s.density = [p, v](double k, double) {
                return v * kPi * p.length * p.length * std::exp(-std::pow(kPi * p.length * k, 2));
            };
            break;
        case SpectralModel::Markaussian:
        case SpectralModel::OscillatoryMarkov:
        case SpectralModel::OscillatoryGaussian: {
            // Numerical Hankel transform; it refuses an oscillation too fast for the envelope
            // (the 2-D isotropic function then has a negative spectrum, Lewis 1987 §6.2).
            Spectrum t = spectrum_of_autocorrelation(model_autocorrelation(p), k_max);
            s.density = t.density;
            break;
        }
        case SpectralModel::Matern: {
            // Rasmussen & Williams 2006 eq. 4.15 in 2-D: S = (4 pi nu / a) (1 + 4 pi^2 k^2 /
            // a)^-(nu+1), a = 2 nu / l^2 (nu = 1/2 is markov).
            const double a = 2 * p.nu / (p.length * p.length);
            s.density = [p, v, a](double k, double) {
                return v * 4 * kPi * p.nu / a *
                       std::pow(1 + 4 * kPi * kPi * k * k / a, -(p.nu + 1));
            };
            break;
        }
        case SpectralModel::Lorentzian:
            // The 2-D transform pair of markov: k0 = 1 / (2 pi l).
            s.density = [p, v](double k, double) {
                return v / (2 * kPi * p.k0 * p.k0) * std::pow(1 + (k / p.k0) * (k / p.k0), -1.5);
            };
            break;
        case SpectralModel::Bandpass: {
            const double c = v / (2 * kPi * bandpass_moment(p.f0, p.width));
            s.density = [p, c](double k, double) {
                const double w2 = 2 * p.width * p.width;
                return c * (std::exp(-(k - p.f0) * (k - p.f0) / w2) +
                            std::exp(-(k + p.f0) * (k + p.f0) / w2));
            };
            break;
        }
        case SpectralModel::Power: {
            const double c = v / power_norm(p);
            s.density = [p, c](double k, double) { return c * power_shape(p, k); };
            break;
        }
    }
    return s;
}

Autocorrelation model_autocorrelation(const ModelParams& params) {
    validate(params);
    const ModelParams p = params;
    const double v = p.variance;
    Autocorrelation a;
    a.name = std::string(kSpectralModelNames[static_cast<int>(p.model)]);
    switch (p.model) {
        case SpectralModel::Markov:
            a.function = [p, v](double r) { return v * std::exp(-r / p.length); };
            break;
        case SpectralModel::Gaussian:
            a.function = [p, v](double r) {
                return v * std::exp(-(r / p.length) * (r / p.length));
            };
            break;
        case SpectralModel::Markaussian:
            a.function = [p, v](double r) {
                return v * std::exp(-std::pow(r / p.length, p.exponent));
            };
            break;
        case SpectralModel::OscillatoryMarkov:  // Lewis 1987 Table 1, Fig. 2
            a.function = [p, v](double r) {
                return v * std::exp(-std::abs(r) / p.length) * std::cos(p.omega * r);
            };
            break;
        case SpectralModel::OscillatoryGaussian:  // Lewis 1986 Fig. 1
            a.function = [p, v](double r) {
                return v * std::cos(p.omega * r) * std::exp(-(r / p.length) * (r / p.length));
            };
            break;
        case SpectralModel::Matern: {
            const double c = std::pow(2.0, 1.0 - p.nu) / std::tgamma(p.nu);
            a.function = [p, v, c](double r) {
                const double x = std::sqrt(2 * p.nu) * r / p.length;
                if (x < 1e-10) return v;
                if (x > 700) return 0.0;
                return v * c * std::pow(x, p.nu) * std::cyl_bessel_k(p.nu, x);
            };
            break;
        }
        default:
            throw ValueError("model = \"" + a.name +
                             "\": defined by its spectrum, not an autocorrelation: expected one of "
                             "markov, gaussian, markaussian, matern, oscillatory_markov, "
                             "oscillatory_gaussian (or use a spectrum kernel)");
    }
    return a;
}

Spectrum expression_spectrum(std::string_view text) {
    auto e = std::make_shared<const Expression>(text, std::vector<std::string>{"k", "theta"});
    Spectrum s;
    s.isotropic = !e->uses("theta");
    s.name = "expression \"" + std::string(text) + "\"";
    s.density = [e](double k, double theta) {
        const double v[2] = {k, theta};
        return e->evaluate(v);
    };
    return s;
}

Autocorrelation expression_autocorrelation(std::string_view text) {
    auto e = std::make_shared<const Expression>(text, std::vector<std::string>{"r"});
    Autocorrelation a;
    a.name = "expression \"" + std::string(text) + "\"";
    a.function = [e](double r) {
        const double v[1] = {r};
        return e->evaluate(v);
    };
    return a;
}

namespace {

/// Rows "x,y" of a two-column CSV table (the grammar of table_spectrum_text), x >= 0 strictly
/// increasing; `cx`, `cy` name the columns in messages and `x_what` says what x is.
Table parse_table(std::string_view text, const std::string& name, const std::string& cx,
                  const std::string& cy, const std::string& x_what) {
    Table t;
    std::istringstream in{std::string(text)};
    std::string line;
    int line_no = 0;
    bool first = true;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const size_t b = line.find_first_not_of(" \t");
        if (b == std::string::npos || line[b] == '#') continue;
        auto fail = [&](const std::string& what) {
            throw ValueError(name + ":" + std::to_string(line_no) + ": " + what);
        };
        std::vector<std::string> fields;
        std::stringstream ls(line);
        for (std::string f; std::getline(ls, f, ',');) fields.push_back(f);
        if (!line.empty() && line.back() == ',') fields.push_back("");
        double k = 0, s = 0;
        const bool ok_k = fields.size() >= 1 && parse_number(fields[0], k);
        const bool ok_s = fields.size() >= 2 && parse_number(fields[1], s);
        if (first && !ok_k) {  // a header line
            first = false;
            continue;
        }
        first = false;
        if (fields.size() > 2)
            fail("expected two columns " + cx + "," + cy + ", found " +
                 std::to_string(fields.size()));
        if (!ok_k) fail(cx + ": expected a number, found \"" + fields[0] + "\"");
        if (fields.size() < 2 || fields[1].find_first_not_of(" \t") == std::string::npos)
            fail("missing value: expected " + cx + "," + cy);
        if (!ok_s) fail(cy + ": expected a number, found \"" + fields[1] + "\"");
        if (!std::isfinite(k) || k < 0)
            fail(cx + " = " + num(k) + ": expected a finite " + x_what + " >= 0");
        if (!std::isfinite(s)) fail(cy + " = " + num(s) + ": expected a finite number");
        if (!t.k.empty() && !(k > t.k.back()))
            fail(cx + " = " + num(k) + " after " + num(t.k.back()) + ": " + cx +
                 " must be strictly increasing");
        t.k.push_back(k);
        t.s.push_back(s);
    }
    if (t.k.size() < 2)
        throw ValueError(name + ": expected at least two rows " + cx + "," + cy + ", found " +
                         std::to_string(t.k.size()));
    return t;
}

std::string read_text_file(const std::string& path, const std::string& what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": cannot open " + what + ": " + std::strerror(errno));
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

Spectrum table_spectrum_text(std::string_view text, const std::string& name) {
    Spectrum sp;
    sp.name = name;
    sp.density = [t = parse_table(text, name, "k", "S", "frequency")](double k, double) {
        return t(k);
    };
    return sp;
}

Autocorrelation table_autocorrelation_text(std::string_view text, const std::string& name) {
    Autocorrelation a;
    a.name = name;
    a.function = [t = parse_table(text, name, "r", "R", "lag")](double r) {
        return t(std::abs(r));
    };
    return a;
}

Autocorrelation table_autocorrelation(const std::string& path) {
    return table_autocorrelation_text(read_text_file(path, "autocorrelation table"), path);
}

Spectrum table_spectrum(const std::string& path) {
    return table_spectrum_text(read_text_file(path, "spectrum table"), path);
}

Spectrum spectrum_of_autocorrelation(const Autocorrelation& acf, double k_max, int dims) {
    require(k_max > 0, "nyquist", k_max, "a frequency > 0 (cycles per unit)");
    if (dims != 2 && dims != 3)
        throw ValueError("dims = " + std::to_string(dims) + ": expected 2 or 3");
    const Radial rad{dims};
    const double r0 = acf.function(0.0);
    if (!(r0 > 0) || !std::isfinite(r0))
        throw ValueError(acf.name + ": R(0) = " + num(r0) + ": expected a finite variance > 0");
    // Support: scan at 1/(16 k_max) for the last r with |R| >= kAcfTail R(0).
    const double dr = 1.0 / (16.0 * k_max);
    double last = 0.0, lowest = r0, lowest_r = 0.0;
    for (double r = dr; r <= kAcfMaxRadius; r += dr) {
        const double v = acf.function(r);
        if (!std::isfinite(v))
            throw ValueError(acf.name + ": R(" + num(r) + ") = " + num(v) +
                             ": expected a finite number");
        if (std::abs(v) > r0 * (1 + 1e-9))
            throw ValueError("autocorrelation " + acf.name + " is not non-negative definite: |R(" +
                             num(r) + ")| = " + num(std::abs(v)) + " > R(0) = " + num(r0));
        if (std::abs(v) >= kAcfTail * r0) last = r;
        if (v < lowest) lowest = v, lowest_r = r;
    }
    if (last > kAcfMaxRadius - 1.0)
        throw ValueError(acf.name + ": R(" + num(kAcfMaxRadius) +
                         ") = " + num(acf.function(kAcfMaxRadius)) +
                         ": expected it to decay below " + num(kAcfTail) + " R(0) within " +
                         num(kAcfMaxRadius) + " units (a shorter correlation length)");
    const double rs = last + dr;
    // Hankel transform by Gauss–Legendre in r: 2 panels per period 1/k_max of J0 at the top
    // frequency; S tabulated at dk <= 1/(8 rs) (S is the transform of a function supported on
    // [0, rs], so it varies on scales ~1/rs) and at least 4096 intervals.
    Nodes rn;
    rn.add(0.0, rs, std::max(64, 32 + static_cast<int>(std::ceil(2.0 * k_max * rs))));
    std::vector<double> wr(rn.x.size());
    for (size_t j = 0; j < rn.x.size(); ++j)
        wr[j] = rad.shell(rn.w[j], rn.x[j]) * acf.function(rn.x[j]);
    const int nk = std::max(4096, static_cast<int>(std::ceil(8.0 * rs * k_max)));
    auto table = std::make_shared<std::vector<double>>(nk + 1);
    std::vector<SpectrumSample> samples(nk + 1);
    double smax = 0.0;
    for (int i = 0; i <= nk; ++i) {
        const double k = k_max * i / nk;
        double s = 0.0;
        for (size_t j = 0; j < wr.size(); ++j)
            s += wr[j] * rad.basis(2 * kPi * k * rn.x[j]);
        (*table)[i] = s;
        samples[i] = {k, 0.0, s};
        smax = std::max(smax, s);
    }
    std::string what = "autocorrelation " + acf.name + " is not non-negative definite";
    if (dims == 3)  // the minimum of sin x / x: Yaglom 1987, the 3-D isotropic bound
        what += " in 3-D (an isotropic 3-D correlation may dip to about -0.218 R(0), the "
                "minimum of sin x / x, not below; this one reaches " + num(lowest / r0) +
                " R(0) at r = " + num(lowest_r) + ")";
    refuse_negative(samples, smax, true, 0.0, what, false);
    for (double& s : *table) s = std::max(s, 0.0);
    Spectrum out;
    out.name = "spectrum of autocorrelation " + acf.name;
    out.density = [table, k_max, nk](double k, double) {
        if (k < 0 || k > k_max) return 0.0;
        // Catmull–Rom on the table, clamped at 0 (a cubic can undershoot near zeros of S).
        const double x = k / k_max * nk;
        const int i = std::min(static_cast<int>(x), nk - 1);
        const double t = x - i;
        auto v = [&](int j) { return (*table)[std::clamp(j, 0, nk)]; };
        const double p0 = i == 0 ? v(1) : v(i - 1), p1 = v(i), p2 = v(i + 1), p3 = v(i + 2);
        const double s =
            p1 +
            0.5 * t *
                (p2 - p0 + t * (2 * p0 - 5 * p1 + 4 * p2 - p3 + t * (3 * (p1 - p2) + p3 - p0)));
        return std::max(s, 0.0);
    };
    return out;
}

Autocorrelation autocorrelation_of_spectrum(const Spectrum& spectrum, double k_max) {
    require(k_max > 0, "nyquist", k_max, "a frequency > 0 (cycles per unit)");
    if (!spectrum.isotropic)
        throw ValueError(spectrum.name +
                         ": an anisotropic spectrum has no radial autocorrelation (make the "
                         "autocorrelation anisotropic instead)");
    const auto S = spectrum.density;
    auto integrate = [S, k_max](double r) {
        Nodes n;
        n.add(0.0, k_max, std::max(64, 32 + static_cast<int>(std::ceil(2.0 * k_max * r))));
        double sum = 0.0;
        for (size_t j = 0; j < n.x.size(); ++j)
            sum += 2 * kPi * n.w[j] * n.x[j] * S(n.x[j], 0.0) * detail::bessel_j0(2 * kPi * n.x[j] * r);
        return sum;
    };
    const double r0 = integrate(0.0);
    if (!(r0 > 0) || !std::isfinite(r0))
        throw ValueError(spectrum.name + ": R(0) = " + num(r0) +
                         ": expected a finite variance > 0 (energy below k_max = " + num(k_max) + ")");
    struct Memo {
        std::mutex lock;
        std::map<double, double> values;
    };
    auto memo = std::make_shared<Memo>();
    memo->values[0.0] = r0;
    Autocorrelation a;
    a.name = spectrum.name + " (band-limited to " + num(k_max) + ")";
    a.function = [memo, integrate](double r) {
        r = std::abs(r);
        if (r > kAcfMaxRadius) return 0.0;  // past the design's reach (see the header)
        {
            const std::lock_guard<std::mutex> g(memo->lock);
            if (auto it = memo->values.find(r); it != memo->values.end()) return it->second;
        }
        const double v = integrate(r);
        const std::lock_guard<std::mutex> g(memo->lock);
        memo->values.emplace(r, v);
        return v;
    };
    return a;
}

// ---------------------------------------------------------------------------------------------
// Design

void validate(const DesignOptions& o) {
    require(o.nyquist > 0, "nyquist", o.nyquist,
            "a frequency > 0 (cycles per unit; 0.5 = pixel Nyquist at zoom 1)");
    require(o.rolloff >= 0 && o.rolloff <= 0.9, "rolloff", o.rolloff, "a fraction in [0, 0.9]");
    require(o.energy > 0 && o.energy < 1, "energy", o.energy, "a fraction in (0, 1), e.g. 0.99");
    require(o.radius >= 0, "radius", o.radius, "a radius > 0 (texture units)");
    require(o.max_radius > 0, "max_radius", o.max_radius, "a radius > 0");
    require(o.max_bytes >= 0, "max_bytes", o.max_bytes, "a size >= 0 (0: no bound)");
    if (o.dims != 2 && o.dims != 3)
        throw ValueError("dims = " + std::to_string(o.dims) + ": expected 2 or 3");
    if (o.radius > o.max_radius)
        throw ValueError("radius = " + num(o.radius) +
                         ": expected <= max_radius = " + num(o.max_radius));
}

double grid_design_bytes(int N) { return 47.0 * double(N) * double(N); }

DesignedKernel kernel_from_spectrum(const Spectrum& spectrum, const DesignOptions& options) {
    validate(options);
    if (!spectrum.density) throw ValueError("spectrum " + spectrum.name + ": no density function");
    if (options.dims == 3 && !spectrum.isotropic)
        throw ValueError(spectrum.name + ": a 3-D kernel is designed from an isotropic spectrum "
                                         "S(k) only (no theta; solid noise takes anisotropy as a metric)");
    return spectrum.isotropic ? design_radial(spectrum, options) : design_grid(spectrum, options);
}

DesignedKernel kernel_from_autocorrelation(const Autocorrelation& acf,
                                           const DesignOptions& options) {
    validate(options);
    return kernel_from_spectrum(spectrum_of_autocorrelation(acf, options.nyquist, options.dims),
                                options);
}

}  // namespace impulse::kernels
