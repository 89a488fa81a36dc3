// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one FFT wrapper of impulse: real 2-D transforms on FFTW (double), FFTW_ESTIMATE plans
// made and destroyed under one process-wide planner lock, buffers from fftw_alloc_* so every
// call gets the same alignment and hence the same plan and the same bits.

#include <complex>
#include <mutex>

namespace impulse::numeric {

/// The mutex every FFTW planner call (plan creation and destruction) must hold: fftw_plan_*
/// and fftw_destroy_plan share the planner's global state whatever the flags; fftw_execute is
/// thread-safe. Code that calls FFTW's planner itself must take this lock too.
std::mutex& fftw_planner_mutex();

/// The smallest n >= x whose only prime factors are 2, 3, 5 and 7: a size FFTW transforms fast
/// (for zero-padded linear correlations).
int fast_fft_size(int x);

/// Which transforms a RealFft2d plans.
enum class FftPlans { Forward, Inverse, Both };

/// A rows x cols real array and its rows x (cols/2 + 1) half spectrum, row-major (rows = y),
/// zero-filled, with the plans asked for: forward (real -> spectrum, unnormalised,
/// F(k) = sum f(x) e^{-2 pi i k.x / n}) and inverse (spectrum -> real, unnormalised,
/// e^{+2 pi i ...}; a forward + inverse pair multiplies by rows * cols; it destroys the
/// spectrum buffer, as every FFTW c2r transform does). Throws impulse::Error when FFTW cannot
/// allocate or plan.
class RealFft2d {
public:
    RealFft2d(int rows, int cols, FftPlans plans);
    ~RealFft2d();
    RealFft2d(const RealFft2d&) = delete;
    RealFft2d& operator=(const RealFft2d&) = delete;

    int rows() const { return m_rows; }
    int cols() const { return m_cols; }
    int half_cols() const { return m_cols / 2 + 1; }
    double* real() { return m_real; }
    std::complex<double>* spectrum() { return m_spectrum; }
    void forward();
    void inverse();

private:
    void release();

    int m_rows, m_cols;
    double* m_real = nullptr;
    std::complex<double>* m_spectrum = nullptr;
    void* m_forward = nullptr;
    void* m_inverse = nullptr;
};

}  // namespace impulse::numeric
