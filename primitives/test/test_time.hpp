// Shared by the primitives tests: a stamp from milliseconds.
#pragma once

#include "dreamsense/core/timestamp.hpp"

#include <cstdint>

namespace dreamsense::primitives::test {

inline Timestamp ms(int64_t v) { return Timestamp::from_ns(v * 1'000'000); }

}  // namespace dreamsense::primitives::test
