// SPDX-License-Identifier: Apache-2.0
#pragma once
// Real 2-D FFTs for kernel design (internal to impulse::kernels). FFTW (double), FFTW_ESTIMATE
// plans created and destroyed under impulse::fftw_planner_mutex() (util/fftw_lock.h), buffers
// from fftw_alloc_* so every call gets the same alignment and hence the same plan and bits.

#include <complex>
#include <memory>

namespace impulse::kernels::detail {

/// A rows x cols real array and its rows x (cols/2 + 1) half spectrum, with one plan: forward
/// (real -> spectrum, F(k) = sum f(x) e^{-2 pi i k.x / n}) or inverse (spectrum -> real,
/// unnormalised, e^{+2 pi i ...}; destroys the spectrum buffer). Row-major, rows = y.
class RealFft2d {
public:
    RealFft2d(int rows, int cols, bool forward);
    ~RealFft2d();
    RealFft2d(const RealFft2d&) = delete;
    RealFft2d& operator=(const RealFft2d&) = delete;

    int rows() const { return m_rows; }
    int cols() const { return m_cols; }
    int half_cols() const { return m_cols / 2 + 1; }
    double* real() { return m_real; }
    std::complex<double>* spectrum() { return m_spectrum; }
    void execute();

private:
    int m_rows, m_cols;
    double* m_real = nullptr;
    std::complex<double>* m_spectrum = nullptr;
    void* m_plan = nullptr;
};

}  // namespace impulse::kernels::detail
