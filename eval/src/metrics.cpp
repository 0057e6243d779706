#include "dreamsense/eval/metrics.hpp"

#include <algorithm>
#include <cmath>

namespace dreamsense::eval {

std::optional<double> percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::nullopt;
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return v[lo] * (1 - frac) + v[hi] * frac;
}

void BinaryCounts::add(bool truth, bool predicted) {
  if (truth && predicted)
    tp++;
  else if (!truth && predicted)
    fp++;
  else if (truth)
    fn++;
  else
    tn++;
}
std::optional<double> BinaryCounts::precision() const {
  if (tp + fp == 0) return std::nullopt;
  return static_cast<double>(tp) / (tp + fp);
}
std::optional<double> BinaryCounts::recall() const {
  if (tp + fn == 0) return std::nullopt;
  return static_cast<double>(tp) / (tp + fn);
}
std::optional<double> BinaryCounts::f1() const {
  auto p = precision(), r = recall();
  if (!p || !r || *p + *r == 0) return std::nullopt;
  return 2 * *p * *r / (*p + *r);
}
std::optional<double> BinaryCounts::false_positive_rate() const {
  if (fp + tn == 0) return std::nullopt;
  return static_cast<double>(fp) / (fp + tn);
}

}  // namespace dreamsense::eval
