#include "dreamsense/core/timestamp.hpp"

#include <fmt/format.h>

namespace dreamsense {

std::string Timestamp::to_string() const {
  if (*this == unset()) return "unset";
  if (*this == pre_stream()) return "pre_stream";
  if (*this == post_stream()) return "post_stream";
  const int64_t whole = ns_ / 1000000000LL;
  int64_t frac = ns_ % 1000000000LL;
  const bool negative = ns_ < 0;
  if (frac < 0) frac = -frac;
  return fmt::format("{}{}.{:09d}s", negative && whole == 0 ? "-" : "", whole, frac);
}

}  // namespace dreamsense
