#pragma once
// A progress bar on stderr, only when stderr is a terminal and --quiet is not given.

#include <chrono>
#include <string>

namespace dreamsense::app {

class ProgressBar {
 public:
  ProgressBar(std::string label, bool quiet);
  ~ProgressBar();
  void update(double fraction);
  void finish();

 private:
  std::string label_;
  bool enabled_;
  int last_permille_ = -1;
  std::chrono::steady_clock::time_point start_;
};

// Runs `work(progress)` with a bar labelled `label`; progress takes fractions in [0, 1].
template <typename Work>
auto with_progress(const std::string& label, bool quiet, Work&& work) {
  ProgressBar bar(label, quiet);
  auto result = work([&bar](double fraction) { bar.update(fraction); });
  bar.finish();
  return result;
}

}  // namespace dreamsense::app
