// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one FFT wrapper of impulse: real 2-D transforms on FFTW (double), the DCT-I and 1-D
// inverse of the spectral synthesizers (double), and a float n x n inverse for fields too large
// for doubles. FFTW_ESTIMATE plans made and destroyed under one process-wide planner lock,
// buffers from fftw_alloc_* so every call gets the same alignment and hence the same plan and
// the same bits.

#include <complex>
#include <mutex>
#include <vector>

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

/// The forward transform of an nz x ny x nx real array (x fastest) to its nz x ny x (nx/2 + 1)
/// half spectrum, unnormalised, e^{-2 pi i k.x / n}; zero-filled buffers. Throws impulse::Error
/// when FFTW cannot allocate or plan.
class RealForwardFft3d {
public:
    RealForwardFft3d(int nz, int ny, int nx);
    ~RealForwardFft3d();
    RealForwardFft3d(const RealForwardFft3d&) = delete;
    RealForwardFft3d& operator=(const RealForwardFft3d&) = delete;

    int half_x() const { return m_nx / 2 + 1; }
    double* real() { return m_real; }
    const std::complex<double>* spectrum() const { return m_spectrum; }
    void forward();

private:
    void release();

    int m_nx;
    double* m_real = nullptr;
    std::complex<double>* m_spectrum = nullptr;
    void* m_plan = nullptr;
};

/// FFTW threads of the threaded transforms below (dct1, InverseFft2dFloat): a constant, not the
/// machine's core count, so the plan (FFTW_ESTIMATE) and hence the bits are the same on every
/// machine and under any --threads. Set and reset under the planner lock, so every other plan
/// stays serial.
inline constexpr int kFftThreads = 4;

/// In place: the DCT-I (FFTW_REDFT00) along each axis of a rank-1 or rank-2 row-major array of
/// sizes dims[0] (x dims[1]): Y_k = X_0 + (-1)^k X_{h-1} + 2 sum_{j=1}^{h-2} X_j cos(pi j k/(h-1))
/// per axis, the DFT of the even extension of period 2 (h - 1). kFftThreads threads. Throws
/// impulse::Error when FFTW cannot plan.
void dct1(double* data, int rank, const int* dims);

/// x(m) = sum_{k=0}^{n-1} X(k) e^{+2 pi i k m / n}, m in [0, n), of a Hermitian X given by its
/// half X(0..n/2) (n/2 + 1 values; unnormalised c2r). Serial. Throws impulse::Error when FFTW
/// cannot plan.
std::vector<double> inverse_real_1d(const std::complex<double>* half, int n);

/// An n x n real float field and its half spectrum in one buffer (FFTW's in-place c2r layout:
/// rows k_y in [0, n) of n/2 + 1 complex values k_x in [0, n/2]; after `inverse`, real rows of
/// stride 2 (n/2 + 1) floats). The buffer is not initialised. Threaded (kFftThreads). Throws
/// impulse::Error when FFTW cannot allocate or plan.
class InverseFft2dFloat {
public:
    /// `rows`: how many rows m_y in [0, rows) `inverse` must produce (clamped to [1, n]; the
    /// others are left undefined): the transform along x is skipped for them.
    InverseFft2dFloat(int n, int rows);
    ~InverseFft2dFloat();
    InverseFft2dFloat(const InverseFft2dFloat&) = delete;
    InverseFft2dFloat& operator=(const InverseFft2dFloat&) = delete;

    int n() const { return m_n; }
    int half() const { return m_n / 2 + 1; }
    std::complex<float>* spectrum() { return m_spec; }
    const std::complex<float>* spectrum() const { return m_spec; }
    float* real() { return reinterpret_cast<float*>(m_spec); }
    const float* real() const { return reinterpret_cast<const float*>(m_spec); }
    /// Bytes of the buffer for side n.
    static double bytes(int n) { return 8.0 * n * (n / 2 + 1); }
    /// In place: X -> x(m) = sum_k X(k) e^{+2 pi i k.m / n} (unnormalised) for m_y < rows:
    /// complex transforms along y for every k_x, then c2r along x row by row.
    void inverse();

private:
    void release();

    int m_n;
    std::complex<float>* m_spec = nullptr;
    void* m_plan_y = nullptr;  ///< n/2 + 1 complex columns of length n, in place
    void* m_plan_x = nullptr;  ///< `rows` c2r rows of length n, in place
};

}  // namespace impulse::numeric
