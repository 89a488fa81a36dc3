// SPDX-License-Identifier: Apache-2.0
#pragma once
// Lattice solid noises (Lewis 1989 §2–3; docs/solid.md), the baselines of sparse convolution:
//   value   hashed lattice white noise (§2.2, Fig. 1) interpolated with the Hermite cubic
//           3t^2 - 2t^3, separably in x, y, z;
//   perlin  gradient noise (§2.3, [10]): hashed unit gradients at the eight lattice corners,
//           Hermite-interpolated; zero at every lattice point, directional artifacts;
//   wiener  Wiener interpolation of a white lattice (§3, eq. 2–6): weights a = C^-1 c(x) solved
//           from a chosen covariance C over an n^3 neighbourhood, with the expected squared error
//           (the confidence measure, eq. 3) and the lattice-compatibility condition (§3.3).
// Lengths: the lattice spacing is `spacing` texture units. Deterministic: a pure function of
// (params, point); the tables and lattice values come from the counter RNG keyed by the seed.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "synth/solid.h"

namespace impulse::synth {

enum class LatticeMethod { Value, Perlin, Wiener };
/// "value", "perlin", "wiener"; anything else throws ValueError listing them.
LatticeMethod parse_lattice_method(const std::string& name);

/// The covariance a Wiener-interpolated lattice noise is built for: C(r), r in lattice units.
struct WienerCovariance {
    std::function<double(double r)> function;
    std::string name;  ///< for messages
};

/// Named covariances for Wiener interpolation: "gaussian" exp(-r^2 / l^2), "markov"
/// exp(-r / l), "spherical" 1 - 3/2 (r/l) + 1/2 (r/l)^3 for r < l (valid in 3-D), "cosine" the
/// cosine kernel's 3-D autocorrelation normalised to C(0) = 1 over radius l; l in lattice units.
/// ValueError for an unknown name or l <= 0.
WienerCovariance wiener_covariance(const std::string& name, double length);

struct LatticeParams {
    LatticeMethod method = LatticeMethod::Perlin;
    double spacing = 8.0;   ///< lattice spacing, texture units, > 0
    uint64_t seed = 0;
    /// wiener only: the covariance, the neighbourhood side n (2, 3 or 4: n^3 lattice points,
    /// L89 §3.3 "3^3 or 4^3") and the compatibility tolerance: |C(o)| <= tolerance C(0) at every
    /// nonzero lattice offset o within the neighbourhood, else ValueError saying where.
    WienerCovariance covariance;
    int neighbourhood = 4;
    double tolerance = 1e-3;
};

class LatticeNoise {
public:
    /// Validates; wiener: solves the Gram matrix and checks compatibility (ValueError).
    explicit LatticeNoise(const LatticeParams& params);
    const LatticeParams& params() const { return m_params; }

    /// values[i] = f(points[i]) (t ignored); TBB-parallel, bit-identical for any order.
    void evaluate(const std::vector<SolidPoint>& points, std::vector<float>& values) const;
    float evaluate(const SolidPoint& p) const;
    /// W x H x D grid, sample (i, j, k) at origin + (i, j, k) * spacing, x fastest.
    std::vector<float> grid(int width, int height, int depth, const SolidPoint& origin,
                            double spacing = 1.0) const;

    /// The lattice's white value at integer point (i, j, k): uniform in [-1, 1] (value, Fig. 1
    /// tables) or with unit variance (wiener, counter RNG).
    double lattice_value(int64_t i, int64_t j, int64_t k) const;

    /// wiener: the interpolation weights a(x) = C^-1 c(x) at the position u in [0, 1)^3 of a
    /// lattice cell, over the neighbourhood's points (eq. 5), in neighbourhood order.
    std::vector<double> weights(const std::array<double, 3>& u) const;
    /// wiener: the expected squared error C(0) - c^T C^-1 c at u (eq. 3, the confidence measure).
    double confidence(const std::array<double, 3>& u) const;
    /// wiener: offsets of the neighbourhood's lattice points from the cell's lower corner.
    const std::vector<std::array<int, 3>>& offsets() const { return m_offsets; }
    /// Mean over the cell of the field's variance: value (26/35)^3 / 3; wiener sum a_j^2
    /// averaged over the cell; perlin by the closed form of docs/solid.md.
    double mean_variance() const;

private:
    void setup_wiener();
    float value_noise(double x, double y, double z) const;
    float perlin_noise(double x, double y, double z) const;
    double covariance_q(double q) const;  ///< C(sqrt(q)) from the table
    template <class Eval>
    void run(const std::vector<SolidPoint>& points, std::vector<float>& values, const Eval& eval) const;

    LatticeParams m_params;
    std::array<std::array<uint8_t, 256>, 3> m_index{};  ///< Fig. 1's permuted indirection tables
    std::vector<float> m_values;                        ///< Fig. 1's prime-length value table
    std::vector<std::array<float, 3>> m_gradients;      ///< unit gradients (perlin)
    std::vector<std::array<int, 3>> m_offsets;          ///< wiener neighbourhood
    std::vector<double> m_inverse;                      ///< C^-1, row-major (wiener)
    std::vector<float> m_table;                         ///< C(sqrt(q)) for q in [0, q_max]
    double m_table_q = 0.0;
};

}  // namespace impulse::synth
