// Small numeric helpers shared by the demo generator's sources (private to the sim library).
#pragma once

#include <opencv2/core.hpp>

#include <random>

namespace dreamsense::sim::detail {

// Uniform in [lo, hi) from the top 53 bits of the generator (the same numbers on every platform,
// unlike std::uniform_real_distribution).
inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
}

inline cv::Vec3d normalized(const cv::Vec3d& v) {
  const double n = cv::norm(v);
  return n > 1e-12 ? v / n : cv::Vec3d(0, 0, 0);
}

}  // namespace dreamsense::sim::detail
