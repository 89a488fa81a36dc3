// SPDX-License-Identifier: Apache-2.0
// impulse_bench_shaping: what the default shaping F_x (the shot-noise law, kernels/shot_noise.h)
// costs when a shaped layer is loaded, per kernel type and amplitude law: the kernel's value law
// (512^2 evaluations of h), the lattice law (jump spreading and two FFTs of 2^15) and the
// transfer table (4096 quantiles), each in thread CPU milliseconds, median [min-max] of the
// timed runs after one untimed warm-up. A layer with a fixed kernel pays all three once at load;
// a keyframed density or target pays the last two per frame whose moments change; a keyframed
// kernel all three. See bench/README.md.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "bench/common.h"
#include "kernels/kernels.h"

namespace {

using namespace impulse;
using namespace impulse::bench;
namespace K = impulse::kernels;

struct Case {
    const char* name;
    K::KernelParams kernel;
    K::AmplitudeLaw law;
    int ages;  ///< weight nodes: 1 for a still layer, 256 for an animated one (hann envelope)
};

std::vector<Case> cases() {
    K::KernelParams cosine;
    cosine.radius = 4.0;
    K::KernelParams gauss;
    gauss.type = K::KernelType::Gaussian;
    K::KernelParams gabor;
    gabor.type = K::KernelType::Gabor;
    gabor.radius = 8.0;
    gabor.frequency = 0.15;
    auto radial = std::make_shared<K::SampledKernel>();
    radial->n = 65;
    for (int i = 0; i < radial->n; ++i) {
        const double r = double(i) / (radial->n - 1);
        radial->values.push_back((1.0 - 3.0 * r * r) * (1.0 - r * r) * (1.0 - r * r));
    }
    K::KernelParams sampled;
    sampled.type = K::KernelType::Sampled;
    sampled.sampled = radial;
    return {{"cosine normal still", cosine, K::AmplitudeLaw::Normal, 1},
            {"cosine uniform still", cosine, K::AmplitudeLaw::Uniform, 1},
            {"cosine sign still", cosine, K::AmplitudeLaw::Sign, 1},
            {"cosine normal hann", cosine, K::AmplitudeLaw::Normal, 256},
            {"gaussian sign hann", gauss, K::AmplitudeLaw::Sign, 256},
            {"gabor normal still", gabor, K::AmplitudeLaw::Normal, 1},
            {"sampled radial normal", sampled, K::AmplitudeLaw::Normal, 1}};
}

}  // namespace

int main(int argc, char** argv) {
    const int reps = argc > 2 && std::string(argv[1]) == "--reps" ? std::atoi(argv[2]) : 7;
    std::printf(
        "impulse_bench_shaping: thread CPU ms, median [min-max] of %d runs; density 16; "
        "load %s\n\n",
        reps, loadavg().c_str());
    std::printf("| case | value law | lattice law | table | total |\n|---|---|---|---|---|\n");
    K::MarginalParams target;
    target.type = K::MarginalType::Lognormal;
    for (const Case& c : cases()) {
        const K::Kernel k(c.kernel);
        const double lambda = 16.0 / k.support_area();
        std::vector<K::WeightNode> nodes;
        for (int i = 0; i < c.ages; ++i) {
            const double s = std::sin(3.141592653589793 * (i + 0.5) / c.ages);
            nodes.push_back({c.ages == 1 ? 1.0 : s * s, 1.0 / c.ages});
        }
        std::vector<double> tv, tl, tt;
        for (int r = 0; r <= reps; ++r) {
            double t0 = thread_cpu_ms();
            const K::KernelValueLaw values = K::kernel_value_law(k);
            double t1 = thread_cpu_ms();
            auto cdf = std::make_shared<const K::ShotNoiseCdf>(lambda, values, c.law, nodes);
            double t2 = thread_cpu_ms();
            const K::MarginalTransform g(target, 0.0, cdf);
            double t3 = thread_cpu_ms();
            if (r == 0) continue;
            tv.push_back(t1 - t0), tl.push_back(t2 - t1), tt.push_back(t3 - t2);
        }
        std::vector<double> total;
        for (size_t i = 0; i < tv.size(); ++i) total.push_back(tv[i] + tl[i] + tt[i]);
        std::printf("| %s | %s | %s | %s | %s |\n", c.name, cell(summarise(tv)).c_str(),
                    cell(summarise(tl)).c_str(), cell(summarise(tt)).c_str(),
                    cell(summarise(total)).c_str());
    }
    return 0;
}
