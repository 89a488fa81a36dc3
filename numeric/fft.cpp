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

RealFft2d::RealFft2d(int rows, int cols, FftPlans plans) : m_rows(rows), m_cols(cols) {
    const std::string size = std::to_string(rows) + "x" + std::to_string(cols);
    const size_t nr = size_t(rows) * cols, nc = size_t(rows) * (cols / 2 + 1);
    m_real = fftw_alloc_real(nr);
    fftw_complex* spec = fftw_alloc_complex(nc);
    // fftw_complex is double[2], layout-compatible with std::complex<double> (FFTW manual §4.1.1).
    m_spectrum = reinterpret_cast<std::complex<double>*>(spec);
    if (m_real == nullptr || spec == nullptr) {
        release();
        throw Error("fftw: cannot allocate " + size + " transform buffers");
    }
    std::fill(m_real, m_real + nr, 0.0);
    std::fill(m_spectrum, m_spectrum + nc, std::complex<double>(0.0, 0.0));
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

void RealFft2d::forward() { fftw_execute(static_cast<fftw_plan>(m_forward)); }
void RealFft2d::inverse() { fftw_execute(static_cast<fftw_plan>(m_inverse)); }

}  // namespace impulse::numeric
