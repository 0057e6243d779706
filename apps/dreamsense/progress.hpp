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

}  // namespace dreamsense::app
