// SPDX-License-Identifier: Apache-2.0
#include "numeric/fft.h"

#include <fftw3.h>

#include <algorithm>
#include <string>

#include "numeric/errors.h"

namespace impulse::numeric {

std::mutex& fftw_planner_mutex() {
    static std::mutex m;
    return m;
}

int fast_fft_size(int x) {
    for (int n = std::max(x, 1);; ++n) {
        int m = n;
        for (int p : {2, 3, 5, 7})
            while (m % p == 0) m /= p;
        if (m == 1) return n;
    }
}

namespace {

// Zero-filled FFTW buffers of nr reals and nc complex values (fftw_alloc_*: the same alignment
// every call, hence the same plan and bits); false when either allocation failed.
bool allocate_zeroed(size_t nr, size_t nc, double*& real, std::complex<double>*& spectrum) {
    real = fftw_alloc_real(nr);
    // fftw_complex is double[2], layout-compatible with std::complex<double> (FFTW manual §4.1.1).
    spectrum = reinterpret_cast<std::complex<double>*>(fftw_alloc_complex(nc));
    if (real == nullptr || spectrum == nullptr) return false;
    std::fill(real, real + nr, 0.0);
    std::fill(spectrum, spectrum + nc, std::complex<double>(0.0, 0.0));
    return true;
}

}  // namespace

RealFft2d::RealFft2d(int rows, int cols, FftPlans plans) : m_rows(rows), m_cols(cols) {
    const std::string size = std::to_string(rows) + "x" + std::to_string(cols);
    const size_t nr = size_t(rows) * cols, nc = size_t(rows) * (cols / 2 + 1);
    if (!allocate_zeroed(nr, nc, m_real, m_spectrum)) {
        release();
        throw Error("fftw: cannot allocate " + size + " transform buffers");
    }
    auto* spec = reinterpret_cast<fftw_complex*>(m_spectrum);
    {
        // Plans are made before the input is written: safe whatever the planner does to arrays.
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        if (plans != FftPlans::Inverse)
            m_forward = fftw_plan_dft_r2c_2d(rows, cols, m_real, spec, FFTW_ESTIMATE);
        if (plans != FftPlans::Forward)
            m_inverse = fftw_plan_dft_c2r_2d(rows, cols, spec, m_real, FFTW_ESTIMATE);
    }
    if ((plans != FftPlans::Inverse && m_forward == nullptr) ||
        (plans != FftPlans::Forward && m_inverse == nullptr)) {
        release();
        throw Error("fftw: cannot plan a " + size + " transform");
    }
}

RealFft2d::~RealFft2d() { release(); }

void RealFft2d::release() {
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        if (m_forward != nullptr) fftw_destroy_plan(static_cast<fftw_plan>(m_forward));
        if (m_inverse != nullptr) fftw_destroy_plan(static_cast<fftw_plan>(m_inverse));
    }
    m_forward = m_inverse = nullptr;
    fftw_free(m_real);
    fftw_free(reinterpret_cast<fftw_complex*>(m_spectrum));
    m_real = nullptr;
    m_spectrum = nullptr;
}

RealForwardFft3d::RealForwardFft3d(int nz, int ny, int nx) : m_nx(nx) {
    const std::string size = std::to_string(nz) + "x" + std::to_string(ny) + "x" + std::to_string(nx);
    const size_t nr = size_t(nz) * ny * nx, nc = size_t(nz) * ny * half_x();
    if (!allocate_zeroed(nr, nc, m_real, m_spectrum)) {
        release();
        throw Error("fftw: cannot allocate " + size + " transform buffers");
    }
    auto* spec = reinterpret_cast<fftw_complex*>(m_spectrum);
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        m_plan = fftw_plan_dft_r2c_3d(nz, ny, nx, m_real, spec, FFTW_ESTIMATE);
    }
    if (m_plan == nullptr) {
        release();
        throw Error("fftw: cannot plan a " + size + " transform");
    }
}

RealForwardFft3d::~RealForwardFft3d() { release(); }

void RealForwardFft3d::release() {
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        if (m_plan != nullptr) fftw_destroy_plan(static_cast<fftw_plan>(m_plan));
    }
    m_plan = nullptr;
    fftw_free(m_real);
    fftw_free(reinterpret_cast<fftw_complex*>(m_spectrum));
    m_real = nullptr;
    m_spectrum = nullptr;
}

void RealForwardFft3d::forward() { fftw_execute(static_cast<fftw_plan>(m_plan)); }

namespace {

// Runs `plan` with the planner lock held and FFTW threads set to kFftThreads (float and double
// planners alike), then back to 1.
template <class Plan>
auto with_threads(Plan plan) {
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    static const bool threads = fftwf_init_threads() != 0 && fftw_init_threads() != 0;
    if (threads) fftwf_plan_with_nthreads(kFftThreads), fftw_plan_with_nthreads(kFftThreads);
    auto p = plan();
    if (threads) fftwf_plan_with_nthreads(1), fftw_plan_with_nthreads(1);
    return p;
}

}  // namespace

void dct1(double* data, int rank, const int* dims) {
    const fftw_r2r_kind kinds[2] = {FFTW_REDFT00, FFTW_REDFT00};
    const fftw_plan plan =
        with_threads([&] { return fftw_plan_r2r(rank, dims, data, data, kinds, FFTW_ESTIMATE); });
    if (plan == nullptr) throw Error("fftw: cannot plan a DCT-I of " + std::to_string(dims[0]));
    fftw_execute(plan);
    std::lock_guard<std::mutex> lock(fftw_planner_mutex());
    fftw_destroy_plan(plan);
}

std::vector<double> inverse_real_1d(const std::complex<double>* half, int n) {
    const size_t h = size_t(n) / 2 + 1;
    fftw_complex* in = fftw_alloc_complex(h);
    double* out = fftw_alloc_real(size_t(n));
    if (in == nullptr || out == nullptr) {
        fftw_free(in);
        fftw_free(out);
        throw Error("fftw: cannot allocate a 1-D transform of " + std::to_string(n));
    }
    std::copy(half, half + h, reinterpret_cast<std::complex<double>*>(in));
    fftw_plan plan;
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        plan = fftw_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE);
    }
    if (plan != nullptr) fftw_execute(plan);
    std::vector<double> x(out, out + n);
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        if (plan != nullptr) fftw_destroy_plan(plan);
    }
    fftw_free(in);
    fftw_free(out);
    if (plan == nullptr) throw Error("fftw: cannot plan a 1-D transform of " + std::to_string(n));
    return x;
}

InverseFft2dFloat::InverseFft2dFloat(int n, int rows) : m_n(n) {
    const std::string size = std::to_string(n) + "x" + std::to_string(n);
    auto* spec = fftwf_alloc_complex(size_t(n) * half());
    if (spec == nullptr)
        throw Error("fftw: cannot allocate a " + size + " float field (" +
                    std::to_string(bytes(n) / double(1 << 30)) + " GiB)");
    // fftwf_complex is float[2], layout-compatible with std::complex<float> (FFTW manual §4.1.1).
    m_spec = reinterpret_cast<std::complex<float>*>(spec);
    rows = std::clamp(rows, 1, n);
    const int h = half();
    with_threads([&] {
        m_plan_y = fftwf_plan_many_dft(1, &n, h, spec, nullptr, h, 1, spec, nullptr, h, 1,
                                       FFTW_BACKWARD, FFTW_ESTIMATE);
        m_plan_x = fftwf_plan_many_dft_c2r(1, &n, rows, spec, nullptr, 1, h, real(), nullptr, 1,
                                           2 * h, FFTW_ESTIMATE);
        return 0;
    });
    if (m_plan_y == nullptr || m_plan_x == nullptr) {
        release();
        throw Error("fftw: cannot plan a " + size + " inverse transform");
    }
}

InverseFft2dFloat::~InverseFft2dFloat() { release(); }

void InverseFft2dFloat::release() {
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        if (m_plan_y) fftwf_destroy_plan(static_cast<fftwf_plan>(m_plan_y));
        if (m_plan_x) fftwf_destroy_plan(static_cast<fftwf_plan>(m_plan_x));
    }
    m_plan_y = m_plan_x = nullptr;
    fftwf_free(reinterpret_cast<fftwf_complex*>(m_spec));
    m_spec = nullptr;
}

void InverseFft2dFloat::inverse() {
    fftwf_execute(static_cast<fftwf_plan>(m_plan_y));
    fftwf_execute(static_cast<fftwf_plan>(m_plan_x));
}

void RealFft2d::forward() { fftw_execute(static_cast<fftw_plan>(m_forward)); }
void RealFft2d::inverse() { fftw_execute(static_cast<fftw_plan>(m_inverse)); }

}  // namespace impulse::numeric
