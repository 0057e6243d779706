#include "dreamsense/eval/metrics.hpp"

#include <gtest/gtest.h>

namespace dreamsense::eval {
namespace {

TEST(Metrics, PercentileInterpolates) {
  EXPECT_FALSE(percentile({}, 50).has_value());
  EXPECT_DOUBLE_EQ(*median({3, 1, 2}), 2);
  EXPECT_DOUBLE_EQ(*median({4, 1, 2, 3}), 2.5);
  EXPECT_DOUBLE_EQ(*percentile({0, 10}, 95), 9.5);
}

TEST(Metrics, BinaryCounts) {
  BinaryCounts c;
  c.add(true, true);
  c.add(true, false);
  c.add(false, true);
  c.add(false, false);
  c.add(false, false);
  EXPECT_DOUBLE_EQ(*c.precision(), 0.5);
  EXPECT_DOUBLE_EQ(*c.recall(), 0.5);
  EXPECT_DOUBLE_EQ(*c.f1(), 0.5);
  EXPECT_DOUBLE_EQ(*c.false_positive_rate(), 1.0 / 3);
  EXPECT_FALSE(BinaryCounts{}.f1().has_value()) << "no data is not a score of zero";
}

}  // namespace
}  // namespace dreamsense::eval
