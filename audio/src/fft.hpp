#pragma once
// Internal: a real FFT of one size with FFTW (double), its buffers and plans. FFTW's planner is
// not thread-safe, so plan creation and destruction take one process-wide lock.

#include <fftw3.h>

#include <complex>
#include <mutex>

namespace dreamsense::audio::detail {

inline std::mutex& fftw_planner_mutex() {
  static std::mutex m;
  return m;
}

class RealFft {
 public:
  explicit RealFft(int n) : n_(n) {
    real_ = fftw_alloc_real(static_cast<size_t>(n));
    spec_ = fftw_alloc_complex(static_cast<size_t>(n / 2 + 1));
    std::lock_guard lock(fftw_planner_mutex());
    forward_ = fftw_plan_dft_r2c_1d(n, real_, spec_, FFTW_ESTIMATE);
    inverse_ = fftw_plan_dft_c2r_1d(n, spec_, real_, FFTW_ESTIMATE);
  }
  ~RealFft() {
    {
      std::lock_guard lock(fftw_planner_mutex());
      fftw_destroy_plan(forward_);
      fftw_destroy_plan(inverse_);
    }
    fftw_free(real_);
    fftw_free(spec_);
  }
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  int size() const { return n_; }
  int bins() const { return n_ / 2 + 1; }
  double* real() { return real_; }
  std::complex<double>* spectrum() { return reinterpret_cast<std::complex<double>*>(spec_); }
  // real() -> spectrum() (unnormalised).
  void forward() { fftw_execute(forward_); }
  // spectrum() -> real(), scaled by n (FFTW convention); the spectrum is destroyed.
  void inverse() { fftw_execute(inverse_); }
  // Same plans on other (fftw_malloc-aligned) buffers of the same size.
  void forward(double* in, std::complex<double>* out) {
    fftw_execute_dft_r2c(forward_, in, reinterpret_cast<fftw_complex*>(out));
  }
  void inverse(std::complex<double>* in, double* out) {
    fftw_execute_dft_c2r(inverse_, reinterpret_cast<fftw_complex*>(in), out);
  }

 private:
  int n_;
  double* real_ = nullptr;
  fftw_complex* spec_ = nullptr;
  fftw_plan forward_ = nullptr, inverse_ = nullptr;
};

}  // namespace dreamsense::audio::detail
