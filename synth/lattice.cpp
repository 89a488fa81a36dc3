// SPDX-License-Identifier: Apache-2.0
// Lattice solid noises: hashed value noise, Perlin gradient noise and Wiener-interpolated
// lattice noise (Lewis 1989 §2.2, §2.3, §3; synth/lattice.h).

#include "synth/lattice.h"

#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "numeric/errors.h"
#include "numeric/rng.h"
#include "synth/detail/cells.h"

namespace impulse::synth {
namespace {

constexpr uint32_t kLatticeStream = 0x4C415454u;  // "LATT": tables of value and perlin
constexpr uint32_t kWienerStream = 0x5749454Eu;   // "WIEN": the white lattice of wiener
constexpr int kPrime = 4093;                      // Fig. 1's prime table length
constexpr int kTableIntervals = 8192;

/// Hermite cubic 3t^2 - 2t^3 (L89 §2.3, [10]: "a cosine-like function").
inline double hermite(double t) { return t * t * (3.0 - 2.0 * t); }

void require_positive(const char* key, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) {
        std::ostringstream s;
        s << key << " = " << v << ": expected a finite number > 0";
        throw ValueError(s.str());
    }
}

}  // namespace

LatticeMethod parse_lattice_method(const std::string& name) {
    if (name == "value") return LatticeMethod::Value;
    if (name == "perlin") return LatticeMethod::Perlin;
    if (name == "wiener") return LatticeMethod::Wiener;
    throw ValueError("method \"" + name + "\": expected one of value, perlin, wiener");
}

WienerCovariance wiener_covariance(const std::string& name, double l) {
    require_positive("length", l);
    if (name == "gaussian") return {[l](double r) { return std::exp(-r * r / (l * l)); }, name};
    if (name == "markov") return {[l](double r) { return std::exp(-r / l); }, name};
    if (name == "spherical")
        return {[l](double r) {
                    const double x = r / l;
                    return x < 1.0 ? 1.0 - 1.5 * x + 0.5 * x * x * x : 0.0;
                },
                name};
    if (name == "cosine") {
        // 3-D autocorrelation of the cosine bump of radius l/2 (support l), by its spectrum:
        // C(r) = (2 / r) int S(k) sin(2 pi k r) k dk, S = |H|^2, normalised to C(0) = 1.
        kernels::KernelParams kp;
        kp.radius = 0.5 * l;
        const SolidKernel h(kp);
        const int n = 2048;
        const double kmax = 24.0 / l, dk = kmax / n;
        std::vector<double> S(n);
        for (int i = 0; i < n; ++i) S[i] = h.radial_power_spectrum((i + 0.5) * dk);
        auto C = [S, dk](double r) {
            double s = 0.0;
            for (size_t i = 0; i < S.size(); ++i) {
                const double k = (i + 0.5) * dk, x = 2.0 * M_PI * k * r;
                s += S[i] * k * k * (x == 0.0 ? 1.0 : std::sin(x) / x);
            }
            return 4.0 * M_PI * s * dk;
        };
        const double c0 = C(0.0);
        return {[C, c0, l](double r) { return r >= l ? 0.0 : C(r) / c0; }, name};
    }
    throw ValueError("covariance \"" + name + "\": expected one of gaussian, markov, spherical, cosine");
}

LatticeNoise::LatticeNoise(const LatticeParams& p) : m_params(p) {
    require_positive("spacing", p.spacing);
    const numeric::CounterRng rng(p.seed, kLatticeStream);
    // Fig. 1: permuted indirection tables and a prime-length table of uniform values.
    for (int a = 0; a < 3; ++a) {
        std::array<int, 256> perm;
        std::iota(perm.begin(), perm.end(), 0);
        for (int i = 255; i > 0; --i) {  // Fisher–Yates, draw i of table a
            const int j = static_cast<int>(rng.uniforms(a, i, 0, 0)[0] * (i + 1) - 1e-12);
            std::swap(perm[i], perm[std::clamp(j, 0, i)]);
        }
        for (int i = 0; i < 256; ++i) m_index[a][i] = static_cast<uint8_t>(perm[i]);
    }
    m_values.resize(kPrime);
    for (int i = 0; i < kPrime; ++i) m_values[i] = static_cast<float>(2.0 * rng.uniforms(3, i, 0, 0)[0] - 1.0);
    m_gradients.resize(256);
    for (int i = 0; i < 256; ++i) {  // uniform on the sphere
        const auto r = rng.uniforms(4, i, 0, 0);
        const double z = 2.0 * r[0] - 1.0, phi = 2.0 * M_PI * r[1], s = std::sqrt(1.0 - z * z);
        m_gradients[i] = {float(s * std::cos(phi)), float(s * std::sin(phi)), float(z)};
    }
    if (p.method != LatticeMethod::Wiener) return;
    setup_wiener();
}

}  // namespace impulse::synth

namespace impulse::synth {

void LatticeNoise::setup_wiener() {
    const LatticeParams& p = m_params;
    if (!p.covariance.function) throw ValueError("wiener: a covariance is required");
    if (p.neighbourhood < 2 || p.neighbourhood > 4)
        throw ValueError("neighbourhood = " + std::to_string(p.neighbourhood) + ": expected 2, 3 or 4");
    if (!(p.tolerance >= 0.0 && p.tolerance < 1.0))
        throw ValueError("tolerance = " + std::to_string(p.tolerance) + ": expected in [0, 1)");
    const int n = p.neighbourhood, lo = -(n - 1) / 2;
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) m_offsets.push_back({lo + i, lo + j, lo + k});
    const double c0 = p.covariance.function(0.0);
    if (!(c0 > 0.0) || !std::isfinite(c0))
        throw ValueError("covariance " + p.covariance.name + ": C(0) must be > 0");
    // L89 §3.3: the lattice values are uncorrelated, so C centred on a lattice point must vanish
    // at every other lattice point the interpolation uses; otherwise the realized covariance is
    // not the specified one.
    double worst = 0.0;
    std::array<int, 3> at{};
    for (int dz = 0; dz < n; ++dz)
        for (int dy = 0; dy < n; ++dy)
            for (int dx = 0; dx < n; ++dx) {
                if (dx + dy + dz == 0) continue;
                const double c = std::abs(p.covariance.function(std::sqrt(double(dx * dx + dy * dy + dz * dz))));
                if (c > worst) worst = c, at = {dx, dy, dz};
            }
    if (worst > p.tolerance * c0) {
        std::ostringstream s;
        s << "covariance " << p.covariance.name << ": C(" << at[0] << ", " << at[1] << ", " << at[2]
          << ") = " << worst / c0 << " C(0), expected |C| <= " << p.tolerance
          << " C(0) at every nonzero lattice offset: the lattice values are uncorrelated, so the "
             "lattice cannot realize this covariance (Lewis 1989 §3.3); shorten its length";
        throw ValueError(s.str());
    }
    // The Gram matrix of the neighbourhood (eq. 5) and its inverse (eq. 6: eta^T C^-1 is one
    // vector per cell).
    const int m = static_cast<int>(m_offsets.size());
    Eigen::MatrixXd C(m, m);
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b) {
            double q = 0.0;
            for (int d = 0; d < 3; ++d) q += double(m_offsets[a][d] - m_offsets[b][d]) * (m_offsets[a][d] - m_offsets[b][d]);
            C(a, b) = p.covariance.function(std::sqrt(q));
        }
    const Eigen::MatrixXd inv = C.ldlt().solve(Eigen::MatrixXd::Identity(m, m));
    m_inverse.assign(inv.data(), inv.data() + size_t(m) * m);  // symmetric: layout irrelevant
    // C tabulated in q = r^2 over the farthest a point of the cell is from the neighbourhood.
    const double reach = std::max(-lo + 1, lo + n - 1);
    m_table_q = 3.0 * reach * reach;
    m_table.resize(kTableIntervals + 1);
    for (int i = 0; i <= kTableIntervals; ++i)
        m_table[i] = static_cast<float>(p.covariance.function(std::sqrt(m_table_q * i / kTableIntervals)));
}

double LatticeNoise::covariance_q(double q) const {
    const double x = std::min(q / m_table_q, 1.0) * kTableIntervals;
    const int i = std::min(static_cast<int>(x), kTableIntervals - 1);
    return m_table[i] + (x - i) * (m_table[i + 1] - m_table[i]);
}

double LatticeNoise::lattice_value(int64_t i, int64_t j, int64_t k) const {
    if (m_params.method == LatticeMethod::Wiener) {
        // Uniform with unit variance: sqrt(3) (2u - 1).
        static const double kS3 = std::sqrt(3.0);
        return kS3 * (2.0 * numeric::CounterRng(m_params.seed, kWienerStream).uniforms(i, j, k, 0)[0] - 1.0);
    }
    // Fig. 1: the low bits index the permuted tables, hashed into the prime-length value table.
    const int h = (m_index[0][i & 255] * 65536 + m_index[1][j & 255] * 256 + m_index[2][k & 255]) % kPrime;
    return m_values[h];
}

std::vector<double> LatticeNoise::weights(const std::array<double, 3>& u) const {
    const size_t m = m_offsets.size();
    std::vector<double> c(m), a(m, 0.0);
    for (size_t j = 0; j < m; ++j) {
        double q = 0.0;
        for (int d = 0; d < 3; ++d) q += (u[d] - m_offsets[j][d]) * (u[d] - m_offsets[j][d]);
        c[j] = m_params.covariance.function(std::sqrt(q));
    }
    for (size_t i = 0; i < m; ++i)
        for (size_t j = 0; j < m; ++j) a[i] += m_inverse[i * m + j] * c[j];
    return a;
}

double LatticeNoise::confidence(const std::array<double, 3>& u) const {
    const std::vector<double> a = weights(u);
    double ca = 0.0;
    for (size_t j = 0; j < m_offsets.size(); ++j) {
        double q = 0.0;
        for (int d = 0; d < 3; ++d) q += (u[d] - m_offsets[j][d]) * (u[d] - m_offsets[j][d]);
        ca += a[j] * m_params.covariance.function(std::sqrt(q));
    }
    return m_params.covariance.function(0.0) - ca;  // eq. 3 at the optimum: C(0) - c^T C^-1 c
}

float LatticeNoise::value_noise(double x, double y, double z) const {
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int64_t i = int64_t(fx), j = int64_t(fy), k = int64_t(fz);
    const double sx = hermite(x - fx), sy = hermite(y - fy), sz = hermite(z - fz);
    double acc = 0.0;
    for (int c = 0; c < 8; ++c) {
        const int a = c & 1, b = (c >> 1) & 1, d = c >> 2;
        acc += (a ? sx : 1 - sx) * (b ? sy : 1 - sy) * (d ? sz : 1 - sz) * lattice_value(i + a, j + b, k + d);
    }
    return static_cast<float>(acc);
}

float LatticeNoise::perlin_noise(double x, double y, double z) const {
    const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
    const int64_t i = int64_t(fx), j = int64_t(fy), k = int64_t(fz);
    const double tx = x - fx, ty = y - fy, tz = z - fz;
    const double sx = hermite(tx), sy = hermite(ty), sz = hermite(tz);
    const auto& P = m_index[0];
    double acc = 0.0;
    for (int c = 0; c < 8; ++c) {
        const int a = c & 1, b = (c >> 1) & 1, d = c >> 2;
        // Perlin's hash: P[P[P[i] + j] + k] (8-bit wrap: period 256 cells).
        const int h = P[(P[(P[(i + a) & 255] + ((j + b) & 255)) & 255] + ((k + d) & 255)) & 255];
        const auto& g = m_gradients[h];
        const double dot = g[0] * (tx - a) + g[1] * (ty - b) + g[2] * (tz - d);
        acc += (a ? sx : 1 - sx) * (b ? sy : 1 - sy) * (d ? sz : 1 - sz) * dot;
    }
    return static_cast<float>(acc);
}

void LatticeNoise::evaluate(const std::vector<SolidPoint>& points, std::vector<float>& values) const {
    values.assign(points.size(), 0.0f);
    const double s = 1.0 / m_params.spacing;
    if (m_params.method != LatticeMethod::Wiener) {
        const bool perlin = m_params.method == LatticeMethod::Perlin;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const auto& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const SolidPoint& q = points[i];
                values[i] = perlin ? perlin_noise(q.x * s, q.y * s, q.z * s)
                                   : value_noise(q.x * s, q.y * s, q.z * s);
            }
        });
        return;
    }
    // Wiener (eq. 6): per cell the vector w = C^-1 eta once, then <w, c(x)> per point.
    const auto b = detail::group_by_cell<3>(points.size(), [&](size_t i, double* o) {
        o[0] = points[i].x * s, o[1] = points[i].y * s, o[2] = points[i].z * s;
    });
    const size_t m = m_offsets.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, b.cells.size(), 1), [&](const auto& r) {
        std::vector<double> eta(m), w(m);
        for (size_t g = r.begin(); g != r.end(); ++g) {
            const auto& c = b.cells[g];
            for (size_t j = 0; j < m; ++j)
                eta[j] = lattice_value(c[0] + m_offsets[j][0], c[1] + m_offsets[j][1], c[2] + m_offsets[j][2]);
            for (size_t i = 0; i < m; ++i) {
                double acc = 0.0;
                for (size_t j = 0; j < m; ++j) acc += m_inverse[i * m + j] * eta[j];
                w[i] = acc;
            }
            for (size_t t = b.start[g]; t < b.start[g + 1]; ++t) {
                double acc = 0.0;
                for (size_t j = 0; j < m; ++j) {
                    double q = 0.0;
                    for (int d = 0; d < 3; ++d) {
                        const double dd = double(b.local[d][t]) - m_offsets[j][d];
                        q += dd * dd;
                    }
                    acc += w[j] * covariance_q(q);
                }
                values[b.index[t]] = static_cast<float>(acc);
            }
        }
    });
}

float LatticeNoise::evaluate(const SolidPoint& p) const {
    std::vector<float> v;
    evaluate(std::vector<SolidPoint>{p}, v);
    return v[0];
}

std::vector<float> LatticeNoise::grid(int width, int height, int depth, const SolidPoint& origin,
                                      double spacing) const {
    if (width <= 0 || height <= 0 || depth <= 0)
        throw ValueError("grid size " + std::to_string(width) + "x" + std::to_string(height) + "x" +
                         std::to_string(depth) + ": expected positive sizes");
    const size_t plane = size_t(width) * height;
    std::vector<float> out(plane * depth), vals;
    std::vector<SolidPoint> pts(plane);
    for (int k = 0; k < depth; ++k) {
        for (int j = 0; j < height; ++j)
            for (int i = 0; i < width; ++i)
                pts[size_t(j) * width + i] = {origin.x + i * spacing, origin.y + j * spacing,
                                              origin.z + k * spacing, origin.t};
        evaluate(pts, vals);
        std::copy(vals.begin(), vals.end(), out.begin() + ptrdiff_t(plane) * k);
    }
    return out;
}

double LatticeNoise::mean_variance() const {
    // Midpoint quadrature over the cell of the pointwise variance.
    const int n = 24;
    double sum = 0.0;
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::array<double, 3> u = {(i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n};
                if (m_params.method == LatticeMethod::Wiener) {
                    for (double a : weights(u)) sum += a * a;  // white unit-variance lattice
                    continue;
                }
                const double s[3] = {hermite(u[0]), hermite(u[1]), hermite(u[2])};
                for (int c = 0; c < 8; ++c) {
                    double w = 1.0, d2 = 0.0;
                    for (int d = 0; d < 3; ++d) {
                        const int bit = (c >> d) & 1;
                        w *= bit ? s[d] : 1.0 - s[d];
                        d2 += (u[d] - bit) * (u[d] - bit);
                    }
                    // value: E[v^2] = 1/3 (uniform in [-1, 1]); perlin: E[(g.d)^2] = |d|^2 / 3
                    // for unit gradients uniform on the sphere.
                    sum += w * w * (m_params.method == LatticeMethod::Value ? 1.0 / 3.0 : d2 / 3.0);
                }
            }
    return sum / (n * n * n);
}

}  // namespace impulse::synth
