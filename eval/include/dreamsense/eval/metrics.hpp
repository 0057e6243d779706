#pragma once
// Small statistics used by every evaluation.

#include <optional>
#include <vector>

namespace dreamsense::eval {

// Linear-interpolated percentile (p in [0, 100]); nullopt for an empty sample.
std::optional<double> percentile(std::vector<double> values, double p);
inline std::optional<double> median(std::vector<double> values) {
  return percentile(std::move(values), 50);
}

struct BinaryCounts {
  int tp = 0, fp = 0, tn = 0, fn = 0;
  void add(bool truth, bool predicted);
  std::optional<double> precision() const;
  std::optional<double> recall() const;
  std::optional<double> f1() const;
  std::optional<double> false_positive_rate() const;
};

}  // namespace dreamsense::eval
