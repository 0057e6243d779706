#include "dreamsense/core/timestamp.hpp"

#include <gtest/gtest.h>

namespace dreamsense {
namespace {

TEST(Timestamp, ArithmeticIsExactInNanoseconds) {
  const Timestamp t = Timestamp::from_ns(1'000'000'007);
  EXPECT_EQ((t + Duration::from_ms(40)).ns(), 1'040'000'007);
  EXPECT_EQ((t - Timestamp::from_ns(7)).ns(), 1'000'000'000);
  EXPECT_EQ(Duration::from_seconds(0.04).ns(), 40'000'000);
  EXPECT_EQ(Duration::from_seconds(-0.5).ns(), -500'000'000);
  EXPECT_EQ(period_from_rate(30.0).ns(), 33'333'333);
  EXPECT_EQ(Duration::from_ms(100) / Duration::from_ms(40), 2);
  EXPECT_DOUBLE_EQ(Timestamp::from_seconds(2.5).seconds(), 2.5);
}

TEST(Timestamp, SpecialValuesOrderAroundRealStamps) {
  EXPECT_FALSE(Timestamp().is_set());
  EXPECT_EQ(Timestamp(), Timestamp::unset());
  EXPECT_LT(Timestamp::unset(), Timestamp::pre_stream());
  EXPECT_LT(Timestamp::pre_stream(), Timestamp::from_ns(-1'000'000'000'000));
  EXPECT_GT(Timestamp::post_stream(), Timestamp::from_ns(1'000'000'000'000'000));
  EXPECT_TRUE(Timestamp::post_stream().is_special());
  EXPECT_FALSE(Timestamp::from_ns(0).is_special());
}

TEST(Timestamp, ToStringShowsSecondsWithNanoseconds) {
  EXPECT_EQ(Timestamp::from_ns(12'345'678'901).to_string(), "12.345678901s");
  EXPECT_EQ(Timestamp::from_ns(-5).to_string(), "-0.000000005s");
  EXPECT_EQ(Timestamp::unset().to_string(), "unset");
}

TEST(Duration, AbsAndComparison) {
  EXPECT_EQ(Duration::from_ms(-3).abs(), Duration::from_ms(3));
  EXPECT_LT(Duration::from_us(999), Duration::from_ms(1));
  Duration d = Duration::from_ms(1);
  d += Duration::from_ms(2);
  EXPECT_EQ(d.ns(), 3'000'000);
}

}  // namespace
}  // namespace dreamsense
