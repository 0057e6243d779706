#include "dreamsense/audio/reference_gate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace dreamsense::audio {
namespace {

// A 1 s, 440 Hz burst at -20 dBFS starting at `at_s` in `total_s` of digital silence.
std::vector<float> burst(int rate, double total_s, double at_s, double len_s = 1.0) {
  std::vector<float> x(static_cast<size_t>(total_s * rate), 0.0f);
  for (size_t i = static_cast<size_t>(at_s * rate);
       i < std::min(x.size(), static_cast<size_t>((at_s + len_s) * rate)); ++i)
    x[i] = static_cast<float>(0.14 * std::sin(2 * M_PI * 440 * static_cast<double>(i) / rate));
  return x;
}

TEST(ReferenceGate, MarksTheReferenceWithLeadAndTailAtAnyRate) {
  for (int rate : {16000, 22050, 48000}) {
    ReferenceGateOptions o;
    o.align = false;
    ReferenceGate g(o);
    const auto x = burst(rate, 5, 2);
    ASSERT_TRUE(g.push_reference(x, 1, rate, Timestamp::from_seconds(10)));
    ASSERT_TRUE(g.push_reference(std::vector<float>(static_cast<size_t>(rate) / 10, 0.0f), 1, rate,
                                 Timestamp::from_seconds(15)));
    EXPECT_FALSE(g.active(Timestamp::from_seconds(11.9))) << rate;
    EXPECT_TRUE(g.active(Timestamp::from_seconds(12.5))) << rate;
    EXPECT_TRUE(g.active(Timestamp::from_seconds(13.3))) << rate;  // the room's tail
    EXPECT_FALSE(g.active(Timestamp::from_seconds(13.5))) << rate;
    EXPECT_NEAR(g.active_fraction(Timestamp::from_seconds(12), Timestamp::from_seconds(13)), 1.0,
                1e-9);
    const auto [a, b] =
        g.longest_quiet_span(Timestamp::from_seconds(11), Timestamp::from_seconds(15));
    EXPECT_NEAR(a.seconds(), 13.42, 0.03) << rate;
    EXPECT_NEAR(b.seconds(), 15.0, 1e-9) << rate;
  }
}

TEST(ReferenceGate, SilenceGatesNothing) {
  ReferenceGate g;
  ASSERT_TRUE(g.push_reference(std::vector<float>(16000 * 3, 0.0f), 1, 16000, Timestamp()));
  EXPECT_EQ(g.active_fraction(Timestamp::from_seconds(0), Timestamp::from_seconds(3)), 0.0);
  // Unset bounds (found by UBSan: b - a overflowed) are nothing to measure.
  EXPECT_EQ(g.active_fraction(Timestamp(), Timestamp::from_seconds(3)), 0.0);
  EXPECT_TRUE(g.intervals().empty());
  EXPECT_FALSE(g.push_reference(std::vector<float>(10, 0.0f), 0, 16000, Timestamp()));
}

// The reference's stamps are 0.5 s late against the microphones: the offset is measured from
// the robot's speech (loud at the microphones) and the gate moves to where the robot is heard.
TEST(ReferenceGate, MeasuresAReferenceOffset) {
  const int rate = 16000;
  std::vector<float> ref = burst(rate, 8, 1, 1.2), ref2 = burst(rate, 8, 4, 1.5);
  for (size_t i = 0; i < ref.size(); ++i) ref[i] += ref2[i];
  // Microphones: the same sound 0.5 s earlier in stamp time, plus noise.
  std::mt19937 rng(1);
  std::normal_distribution<float> n(0, 0.003f);
  std::vector<float> mic(ref.size());
  for (size_t i = 0; i < mic.size(); ++i) {
    const size_t k = i + static_cast<size_t>(0.5 * rate);
    mic[i] = (k < ref.size() ? 0.5f * ref[k] : 0.0f) + n(rng);
  }
  ReferenceGate g;
  const size_t chunk = 1600;
  for (size_t i = 0; i + chunk <= ref.size(); i += chunk) {
    const Timestamp t = Timestamp::from_ns(static_cast<int64_t>(i) * 1'000'000'000LL / rate);
    ASSERT_TRUE(g.push_reference(std::span<const float>(ref).subspan(i, chunk), 1, rate, t));
    g.push_microphone(std::span<const float>(mic).subspan(i, chunk), 1, rate, t);
  }
  ASSERT_TRUE(g.measured_offset().has_value());
  EXPECT_NEAR(*g.measured_offset(), -0.5, 0.021);
  EXPECT_NEAR(g.offset_s(), -0.5, 0.021);
  EXPECT_TRUE(g.active(Timestamp::from_seconds(0.7)));   // heard 0.5 s before its stamp says
  EXPECT_FALSE(g.active(Timestamp::from_seconds(2.3)));  // where the reference stamp alone says
}

TEST(ReferenceGate, BadOptions) {
  ReferenceGateOptions o;
  o.threshold_dbfs = 3;
  o.tail_s = -1;
  EXPECT_FALSE(o.check());
  EXPECT_TRUE(ReferenceGateOptions{}.check());
}

}  // namespace
}  // namespace dreamsense::audio
