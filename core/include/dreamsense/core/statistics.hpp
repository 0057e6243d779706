#pragma once
// Small order statistics shared by the libraries.

#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace dreamsense {

// The upper median (the middle element; of an even count the larger of the two middle ones),
// NaN for no values. By value: nth_element reorders the copy.
inline double upper_median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

}  // namespace dreamsense
