#pragma once
// The one FFT wrapper of the tree: real FFTs with FFTW (double precision).
//
// Plans come from a process-wide cache, one pair (r2c, c2r) per size, made the first time a size
// is asked for and reused by every RealFft of that size (never destroyed). Planning is the only
// part of FFTW that is not thread-safe: the cache makes it under one mutex, and the planner is
// switched to its thread-safe mode (fftw_make_planner_thread_safe) before the first plan, so
// other FFTW users in the process do not race with us either. Execution on the new-array
// interface is thread-safe, so RealFft objects on different threads never share state except the
// read-only plans.
//
// Buffers passed to forward()/inverse() must be aligned as fftw_malloc aligns them
// (AlignedReal / AlignedComplex, or the object's own real()/spectrum()).

#include <complex>
#include <cstddef>
#include <memory>

namespace dreamsense::audio {

namespace detail {
struct FftwFree {
  void operator()(void* p) const;
};
struct FftPlans;
}  // namespace detail

// fftw_malloc-aligned buffers (uninitialised).
using AlignedReal = std::unique_ptr<double[], detail::FftwFree>;
using AlignedComplex = std::unique_ptr<std::complex<double>[], detail::FftwFree>;
AlignedReal aligned_real(size_t n);
AlignedComplex aligned_complex(size_t n);

class RealFft {
 public:
  // n > 0 real samples, n / 2 + 1 complex bins.
  explicit RealFft(int n);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  int size() const { return n_; }
  int bins() const { return n_ / 2 + 1; }
  // The object's own buffers: size() reals and bins() complex values.
  double* real() { return real_.get(); }
  std::complex<double>* spectrum() { return spectrum_.get(); }

  // real() -> spectrum() (unnormalised).
  void forward();
  // spectrum() -> real(), scaled by n (FFTW convention); the spectrum is destroyed.
  void inverse();
  // The same transforms on other aligned buffers of this size (`in` of inverse() is destroyed).
  void forward(double* in, std::complex<double>* out) const;
  void inverse(std::complex<double>* in, double* out) const;

 private:
  int n_;
  const detail::FftPlans* plans_;
  AlignedReal real_;
  AlignedComplex spectrum_;
};

}  // namespace dreamsense::audio
