// SPDX-License-Identifier: Apache-2.0
// Kernels from an exemplar image: Lewis 1986 §3 "the (windowed) noise sample h ... playing the
// role of a filter kernel", whose spectrum resembles the prototype's "if it is large enough to
// include any low-frequency components characteristic of the prototype and if it is windowed to
// reduce the effects of discontinuities at the sample boundary".

#include <algorithm>
#include <cmath>
#include <numbers>
#include <memory>
#include <sstream>
#include <utility>

#include "numeric/fft.h"
#include "kernels/kernels.h"
#include "numeric/errors.h"

namespace impulse::kernels {
namespace {

constexpr double kPi = std::numbers::pi;

double sinc(double x) { return x == 0.0 ? 1.0 : std::sin(kPi * x) / (kPi * x); }

}  // namespace

std::vector<float> luminance(const float* pixels, int width, int height, int channels) {
    if (width <= 0 || height <= 0 || channels <= 0)
        throw ValueError("luminance: image is " + std::to_string(width) + "x" +
                         std::to_string(height) + " with " + std::to_string(channels) +
                         " channels: expected a non-empty image");
    const size_t n = size_t(width) * height;
    std::vector<float> y(n);
    for (size_t i = 0; i < n; ++i) {
        const float* p = pixels + i * channels;
        y[i] = channels >= 3 ? 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2] : p[0];  // Rec. 709
    }
    return y;
}

namespace {

void check_options(int width, int height, const ExemplarOptions& o) {
    if (width < 8 || height < 8)
        throw ValueError("exemplar is " + std::to_string(width) + "x" + std::to_string(height) +
                         ": expected at least 8x8 pixels");
    if (!(o.radius >= 0) || !std::isfinite(o.radius))
        throw ValueError("radius = " + std::to_string(o.radius) +
                         ": expected a radius >= 0 (0: largest)");
    if (!(o.density > 0) || !std::isfinite(o.density))
        throw ValueError("density = " + std::to_string(o.density) + ": expected a density > 0");
    if (!(o.amplitude_second_moment > 0) || !std::isfinite(o.amplitude_second_moment))
        throw ValueError("E[a^2] = " + std::to_string(o.amplitude_second_moment) +
                         ": expected > 0");
}

/// Whole-image mean and variance: the variance is what the synthesis reproduces.
std::pair<double, double> image_moments(const float* pixels, int width, int height) {
    const size_t npx = size_t(width) * height;
    double mean = 0.0;
    for (size_t i = 0; i < npx; ++i) {
        if (!std::isfinite(pixels[i]))
            throw ValueError("exemplar pixel (" + std::to_string(i % width) + ", " +
                             std::to_string(i / width) + ") is not a finite number");
        mean += pixels[i];
    }
    mean /= double(npx);
    double var = 0.0;
    for (size_t i = 0; i < npx; ++i) var += (pixels[i] - mean) * (pixels[i] - mean);
    var /= double(npx);
    if (!(var > 0.0)) throw ValueError("exemplar is constant: it has no spectrum to resynthesise");
    return {mean, var};
}

/// Half-size m of the centred crop of P = 2m + 1 pixels (centre pixel m <-> kernel origin).
int crop_half_size(int width, int height, double radius) {
    const int fit = (std::min(width, height) - 1) / 2;
    int m = fit;
    if (radius > 0) {
        m = static_cast<int>(std::ceil(radius - 1e-9));
        if (m > fit) {
            std::ostringstream s;
            s << "exemplar is " << width << "x" << height << ": a kernel of radius " << radius
              << " needs a centred crop of " << 2 * m + 1 << "x" << 2 * m + 1
              << " pixels: expected radius <= " << fit;
            throw ValueError(s.str());
        }
    }
    if (m < 2)
        throw ValueError("radius = " + std::to_string(radius) + ": expected a radius >= 2 pixels");
    return m;
}

/// The radial design window at r = distance / m (zero from r = 1 on).
double window_at(DesignWindow window, double r) {
    if (r >= 1.0) return 0.0;
    switch (window) {
        case DesignWindow::None:
            return 1.0;
        case DesignWindow::Hann:
            return 0.5 + 0.5 * std::cos(kPi * r);
        case DesignWindow::Gaussian:
            return std::exp(-4.5 * r * r);  // sigma = R/3
    }
    return 0.0;
}

/// The mean-removed, windowed centred crop of P x P pixels, transformed (fwd holds its DFT).
void transform_crop(const float* pixels, int width, int height, int m, DesignWindow window,
                    numeric::RealFft2d& fwd) {
    const int P = 2 * m + 1;
    const int x0 = (width - P) / 2, y0 = (height - P) / 2;
    double crop_mean = 0.0;
    for (int y = 0; y < P; ++y)
        for (int x = 0; x < P; ++x) crop_mean += pixels[size_t(y0 + y) * width + (x0 + x)];
    crop_mean /= double(P) * P;
    for (int y = 0; y < P; ++y)
        for (int x = 0; x < P; ++x) {
            const double w = window_at(window, std::hypot(x - m, y - m) / m);
            fwd.real()[size_t(y) * P + x] =
                w * (pixels[size_t(y0 + y) * width + (x0 + x)] - crop_mean);
        }
    fwd.forward();
}

/// Resample at half-pixel spacing by zero-padding the spectrum to 2P x 2P (band-limited
/// interpolation: P is odd, so there is no Nyquist bin to split), dividing by the bilinear
/// interpolant's transform sinc^2(kx/2) sinc^2(ky/2): the renderer's bilinear lookup of the
/// half-pixel grid then has |H|^2 = |DFT of the sample|^2 for |k| < 1/2 cycle per pixel, and
/// its images sit at |k| >= 3/2, where sinc^2 has fallen below 0.05. Half-pixel index I <-> x =
/// I/2 pixels in the crop; the kernel sample I (0 .. 4m) sits at x = I/2 - m from the centre,
/// i.e. at crop coordinate I/2: the same index. 1/P^2 undoes the unnormalised forward + inverse
/// pair.
std::shared_ptr<SampledKernel> half_pixel_kernel(numeric::RealFft2d& fwd, int m) {
    const int P = 2 * m + 1, Q = 2 * P, hp = P / 2 + 1, hq = Q / 2 + 1;
    numeric::RealFft2d inv(Q, Q, numeric::FftPlans::Inverse);
    for (int j = 0; j < P; ++j) {
        const int sj = j <= m ? j : j - P;  // signed frequency index, |sj| <= m
        for (int i = 0; i < hp; ++i) {
            const double kx = double(i) / P, ky = double(sj) / P;
            const double comp = std::pow(sinc(0.5 * kx) * sinc(0.5 * ky), 2);
            inv.spectrum()[size_t((sj + Q) % Q) * hq + i] =
                fwd.spectrum()[size_t(j) * hp + i] / comp;
        }
    }
    inv.inverse();
    const int n = 4 * m + 1;
    auto sk = std::make_shared<SampledKernel>();
    sk->radial = false;
    sk->n = n;
    sk->values.assign(size_t(n) * n, 0.0);
    const double inv_p2 = 1.0 / (double(P) * P);
    for (int J = 0; J < n; ++J)
        for (int I = 0; I < n; ++I) {
            const double r = std::hypot(0.5 * I - m, 0.5 * J - m);
            if (r < m) sk->values[size_t(J) * n + I] = inv.real()[size_t(J) * Q + I] * inv_p2;
        }
    return sk;
}

}  // namespace

ExemplarKernel kernel_from_exemplar(const float* pixels, int width, int height,
                                    const ExemplarOptions& o) {
    check_options(width, height, o);
    const auto [mean, var] = image_moments(pixels, width, height);
    const int m = crop_half_size(width, height, o.radius);
    const int P = 2 * m + 1;
    numeric::RealFft2d fwd(P, P, numeric::FftPlans::Forward);
    transform_crop(pixels, width, height, m, o.window, fwd);
    auto sk = half_pixel_kernel(fwd, m);

    // Normalise: lambda E[a^2] int h^2 = variance, lambda = density / (pi R^2) (Campbell). The
    // aspect squeeze changes lambda and int h^2 by inverse factors, so this holds for any aspect.
    KernelParams params;
    params.type = KernelType::Sampled;
    params.radius = m;
    params.sampled = sk;
    const double i2 = Kernel(params).integral_sq();
    if (!(i2 > 0.0))
        throw ValueError("exemplar: the windowed sample has no energy (a constant crop)");
    const double lambda = o.density / (kPi * double(m) * m);
    const double scale = std::sqrt(var / (lambda * o.amplitude_second_moment * i2));
    for (double& v : sk->values) v *= scale;

    ExemplarKernel out;
    out.params = params;
    out.report.radius = m;
    out.report.crop = P;
    out.report.mean = mean;
    out.report.variance = var;
    out.report.scale = scale;
    return out;
}

}  // namespace impulse::kernels
