#include "progress.hpp"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace dreamsense::app {

ProgressBar::ProgressBar(std::string label, bool quiet)
    : label_(std::move(label)),
      enabled_(!quiet && ::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction) {
  if (!enabled_) return;
  const int permille = static_cast<int>(std::clamp(fraction, 0.0, 1.0) * 1000);
  if (permille == last_permille_) return;
  last_permille_ = permille;
  constexpr int kWidth = 30;
  const int filled = permille * kWidth / 1000;
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r%-10s [%.*s%*s] %5.1f%%  %5.1fs", label_.c_str(), filled,
               "##############################", kWidth - filled, "", permille / 10.0, elapsed);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!enabled_ || last_permille_ < 0) return;
  std::fprintf(stderr, "\n");
  last_permille_ = -1;
  enabled_ = false;
}

}  // namespace dreamsense::app
