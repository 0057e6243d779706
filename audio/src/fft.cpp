#include "dreamsense/audio/fft.hpp"

#include "dreamsense/core/status.hpp"

#include <fftw3.h>

#include <algorithm>
#include <map>
#include <mutex>

namespace dreamsense::audio {
namespace detail {

void FftwFree::operator()(void* p) const { fftw_free(p); }

struct FftPlans {
  fftw_plan forward = nullptr, inverse = nullptr;
};

namespace {

// Plans of every size used so far. Made under the mutex with the planner in thread-safe mode;
// kept for the life of the process (plans are small, sizes few), so no plan is ever destroyed
// while another thread executes it.
const FftPlans& plans_for(int n) {
  static std::once_flag thread_safe_once;
  std::call_once(thread_safe_once, [] { fftw_make_planner_thread_safe(); });
  static std::mutex mutex;
  static std::map<int, FftPlans> cache;
  std::lock_guard lock(mutex);
  auto it = cache.find(n);
  if (it != cache.end()) return it->second;
  // Out-of-place plans on aligned scratch buffers: valid for any other aligned buffers of the
  // same size with fftw_execute_dft_r2c / _c2r.
  AlignedReal real = aligned_real(static_cast<size_t>(n));
  AlignedComplex spec = aligned_complex(static_cast<size_t>(n / 2 + 1));
  auto* s = reinterpret_cast<fftw_complex*>(spec.get());
  FftPlans p;
  p.forward = fftw_plan_dft_r2c_1d(n, real.get(), s, FFTW_ESTIMATE);
  p.inverse = fftw_plan_dft_c2r_1d(n, s, real.get(), FFTW_ESTIMATE);
  DS_CHECK(p.forward != nullptr && p.inverse != nullptr);
  return cache.emplace(n, p).first->second;
}

}  // namespace
}  // namespace detail

AlignedReal aligned_real(size_t n) { return AlignedReal(fftw_alloc_real(std::max<size_t>(n, 1))); }
AlignedComplex aligned_complex(size_t n) {
  return AlignedComplex(
      reinterpret_cast<std::complex<double>*>(fftw_alloc_complex(std::max<size_t>(n, 1))));
}

RealFft::RealFft(int n)
    : n_(n),
      plans_(&detail::plans_for(n)),
      real_(aligned_real(static_cast<size_t>(n))),
      spectrum_(aligned_complex(static_cast<size_t>(n / 2 + 1))) {}
RealFft::~RealFft() = default;

void RealFft::forward() { forward(real_.get(), spectrum_.get()); }
void RealFft::inverse() { inverse(spectrum_.get(), real_.get()); }

void RealFft::forward(double* in, std::complex<double>* out) const {
  fftw_execute_dft_r2c(plans_->forward, in, reinterpret_cast<fftw_complex*>(out));
}
void RealFft::inverse(std::complex<double>* in, double* out) const {
  fftw_execute_dft_c2r(plans_->inverse, reinterpret_cast<fftw_complex*>(in), out);
}

}  // namespace dreamsense::audio
