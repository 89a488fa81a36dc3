// SPDX-License-Identifier: Apache-2.0
#include "kernels/fft.h"

#include <fftw3.h>

#include <mutex>
#include <string>

#include "util/errors.h"
#include "util/fftw_lock.h"

namespace impulse::kernels::detail {

RealFft2d::RealFft2d(int rows, int cols, bool forward) : m_rows(rows), m_cols(cols) {
    const size_t nr = size_t(rows) * cols, nc = size_t(rows) * (cols / 2 + 1);
    m_real = fftw_alloc_real(nr);
    fftw_complex* spec = fftw_alloc_complex(nc);
    // fftw_complex is double[2], layout-compatible with std::complex<double> (FFTW manual §4.1.1).
    m_spectrum = reinterpret_cast<std::complex<double>*>(spec);
    if (m_real == nullptr || spec == nullptr) {
        fftw_free(m_real);
        fftw_free(spec);
        throw Error("fftw: cannot allocate " + std::to_string(rows) + "x" + std::to_string(cols) +
                    " transform buffers");
    }
    std::fill(m_real, m_real + nr, 0.0);
    std::fill(m_spectrum, m_spectrum + nc, std::complex<double>(0.0, 0.0));
    fftw_plan plan;
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        plan = forward ? fftw_plan_dft_r2c_2d(rows, cols, m_real, spec, FFTW_ESTIMATE)
                       : fftw_plan_dft_c2r_2d(rows, cols, spec, m_real, FFTW_ESTIMATE);
    }
    if (plan == nullptr) {
        fftw_free(m_real);
        fftw_free(spec);
        throw Error("fftw: cannot plan a " + std::to_string(rows) + "x" + std::to_string(cols) +
                    " transform");
    }
    m_plan = plan;
}

RealFft2d::~RealFft2d() {
    {
        std::lock_guard<std::mutex> lock(fftw_planner_mutex());
        fftw_destroy_plan(static_cast<fftw_plan>(m_plan));
    }
    fftw_free(m_real);
    fftw_free(reinterpret_cast<fftw_complex*>(m_spectrum));
}

void RealFft2d::execute() { fftw_execute(static_cast<fftw_plan>(m_plan)); }

}  // namespace impulse::kernels::detail
