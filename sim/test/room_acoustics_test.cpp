#include "dreamsense/sim/room_acoustics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dreamsense::sim {
namespace {

// Index of the strongest tap, refined by a parabola through its neighbours.
double peak_position(const std::vector<double>& h) {
  size_t k = 0;
  for (size_t i = 1; i < h.size(); ++i)
    if (std::abs(h[i]) > std::abs(h[k])) k = i;
  if (k == 0 || k + 1 >= h.size()) return static_cast<double>(k);
  const double a = h[k - 1], b = h[k], c = h[k + 1];
  const double den = a - 2 * b + c;
  return static_cast<double>(k) + (std::abs(den) > 1e-12 ? 0.5 * (a - c) / den : 0.0);
}

TEST(RoomAcoustics, DirectPathDelayDifferenceMatchesGeometricTdoa) {
  RoomOptions room;
  room.rt60_s = 0.3;
  AcousticPlacement pl;
  pl.source_m = {3.6, 1.7, 2.9};
  const cv::Vec3d centre(2.5, 2.0, 1.5);
  for (double x : {0.113, -0.036, -0.076, -0.113}) pl.mics_m.push_back(centre + cv::Vec3d(x, 0, 0));
  auto rirs = room_impulse_responses(room, pl);
  ASSERT_TRUE(rirs) << rirs.error().to_string();
  ASSERT_EQ(rirs->size(), 4u);
  const double fs = room.sample_rate_hz, c = room.speed_of_sound_m_s;
  for (size_t i = 0; i < 4; ++i) {
    const double expected = cv::norm(pl.source_m - pl.mics_m[i]) / c * fs;
    EXPECT_NEAR(peak_position((*rirs)[i]), expected, 1.0) << "mic " << i;
    for (size_t j = i + 1; j < 4; ++j) {
      const double tdoa =
          (cv::norm(pl.source_m - pl.mics_m[i]) - cv::norm(pl.source_m - pl.mics_m[j])) / c * fs;
      EXPECT_NEAR(peak_position((*rirs)[i]) - peak_position((*rirs)[j]), tdoa, 1.0)
          << "mics " << i << "," << j;
    }
  }
}

TEST(RoomAcoustics, AnechoicGainIsOneOverDistance) {
  RoomOptions room;
  room.rt60_s = 0;
  AcousticPlacement pl{{1.0, 2.0, 1.5}, {{3.0, 2.0, 1.5}}};
  auto rirs = room_impulse_responses(room, pl);
  ASSERT_TRUE(rirs);
  double sum = 0;
  for (double v : rirs->front()) sum += v;  // windowed sinc sums to ~1
  EXPECT_NEAR(sum, 0.5, 0.01);
}

class Rt60Test : public ::testing::TestWithParam<double> {};

TEST_P(Rt60Test, SchroederEstimateWithin25Percent) {
  RoomOptions room;
  room.rt60_s = GetParam();
  AcousticPlacement pl{{1.3, 1.1, 1.2}, {{3.4, 2.6, 1.7}}};
  auto rirs = room_impulse_responses(room, pl);
  ASSERT_TRUE(rirs) << rirs.error().to_string();
  const auto t20 = schroeder_rt60(rirs->front(), room.sample_rate_hz, -5, -25);
  ASSERT_TRUE(t20.has_value());
  EXPECT_NEAR(*t20, room.rt60_s, 0.25 * room.rt60_s) << "T20 = " << *t20;
  const auto t30 = schroeder_rt60(rirs->front(), room.sample_rate_hz, -5, -35);
  ASSERT_TRUE(t30.has_value());
  EXPECT_NEAR(*t30, room.rt60_s, 0.25 * room.rt60_s) << "T30 = " << *t30;
}

TEST(RoomAcoustics, PlainSabineCoefficientDecaysSlowerInAShoebox) {
  // Documents why match_rt60 exists: uniform Sabine walls give a longer T30 in 5x4x3 m.
  RoomOptions room;
  room.rt60_s = 0.6;
  room.match_rt60 = false;
  auto rirs = room_impulse_responses(room, {{1.3, 1.1, 1.2}, {{3.4, 2.6, 1.7}}});
  ASSERT_TRUE(rirs);
  const auto t30 = schroeder_rt60(rirs->front(), room.sample_rate_hz, -5, -35);
  ASSERT_TRUE(t30.has_value());
  EXPECT_GT(*t30, 1.1 * room.rt60_s);
  room.match_rt60 = true;
  EXPECT_LT(matched_reflection_coefficient(room),
            sabine_reflection_coefficient(room.size_m, room.rt60_s));
}

INSTANTIATE_TEST_SUITE_P(RoomAcoustics, Rt60Test, ::testing::Values(0.3, 0.6));

TEST(RoomAcoustics, FftConvolutionMatchesDirectForm) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> a(1000), b(300);
  for (double& v : a) v = u(rng);
  for (double& v : b) v = u(rng);
  const auto fast = fft_convolve(a, b);
  ASSERT_EQ(fast.size(), a.size() + b.size() - 1);
  for (size_t n = 0; n < fast.size(); n += 37) {
    double ref = 0;
    for (size_t i = 0; i < a.size(); ++i)
      if (n >= i && n - i < b.size()) ref += a[i] * b[n - i];
    EXPECT_NEAR(fast[n], ref, 1e-9);
  }
}

class NoiseTest : public ::testing::TestWithParam<NoiseColor> {};

TEST_P(NoiseTest, MeasuredSnrWithinHalfDecibel) {
  Channels clean(4, std::vector<double>(32000));
  for (size_t c = 0; c < clean.size(); ++c)
    for (size_t i = 0; i < clean[c].size(); ++i)
      clean[c][i] = 0.3 * std::sin(2 * CV_PI * 440.0 * static_cast<double>(i) / 16000 +
                                   static_cast<double>(c));
  for (double snr : {0.0, 10.0, 20.0, 30.0}) {
    Channels noisy = clean;
    add_noise(noisy, snr, GetParam(), 42);
    Channels noise = noisy;
    for (size_t c = 0; c < noise.size(); ++c)
      for (size_t i = 0; i < noise[c].size(); ++i) noise[c][i] -= clean[c][i];
    const double measured = 10 * std::log10(mean_power(clean) / mean_power(noise));
    EXPECT_NEAR(measured, snr, 0.5);
  }
  // Seeded: same seed, same noise.
  EXPECT_EQ(make_noise(2, 100, GetParam(), 9), make_noise(2, 100, GetParam(), 9));
  EXPECT_NE(make_noise(2, 100, GetParam(), 9), make_noise(2, 100, GetParam(), 10));
}

INSTANTIATE_TEST_SUITE_P(RoomAcoustics, NoiseTest,
                         ::testing::Values(NoiseColor::kWhite, NoiseColor::kPink));

TEST(RoomAcoustics, PinkNoiseHasMoreLowFrequencyPower) {
  const auto n = make_noise(1, 1 << 15, NoiseColor::kPink, 5);
  // First difference (a high-pass) removes much more power from pink than from white noise.
  double diff = 0;
  for (size_t i = 1; i < n[0].size(); ++i) diff += std::pow(n[0][i] - n[0][i - 1], 2);
  diff /= static_cast<double>(n[0].size() - 1);
  EXPECT_LT(diff, 0.5);  // white noise would give ~2
}

TEST(RoomAcoustics, RejectsBadInput) {
  RoomOptions room;
  EXPECT_TRUE(room.check());
  room.size_m = {5, 0, 3};
  EXPECT_FALSE(room.check());
  room = RoomOptions{};
  room.rt60_s = 0.05;  // shorter than Sabine allows with alpha <= 1
  EXPECT_FALSE(room.check());
  room = RoomOptions{};
  EXPECT_FALSE(room_impulse_responses(room, {{6, 1, 1}, {{1, 1, 1}}}));
  EXPECT_FALSE(room_impulse_responses(room, {{1, 1, 1}, {}}));
}

// Five 3 s utterances at five places mixed into 20 s of 4-channel audio with pink noise, as
// the demo does: every sample finite and each utterance heard. (Its speed is a benchmark:
// BM_RoomSimulationOfAThreeSecondUtterance in sound_direction_bench, not a timed test, which
// failed under ASan on a loaded machine.)
TEST(RoomAcoustics, TwentySecondsOfFourChannelsMix) {
  RoomOptions room;
  room.rt60_s = 0.4;
  const cv::Vec3d centre(2.5, 2.05, 1.5);
  std::vector<cv::Vec3d> mics;
  for (double x : {0.113, -0.036, -0.076, -0.113}) mics.push_back(centre + cv::Vec3d(x, 0, 0));
  Channels mix(4, std::vector<double>(20 * 16000, 0.0));
  const auto clip = make_noise(1, 3 * 16000, NoiseColor::kWhite, 1)[0];  // a 3 s "utterance"
  for (int u = 0; u < 5; ++u) {
    auto wet = simulate(clip, room, {{1.0 + 0.5 * u, 1.8, 2.8}, mics});
    ASSERT_TRUE(wet);
    for (size_t c = 0; c < 4; ++c)
      for (size_t i = 0; i < (*wet)[c].size() && u * 64000 + i < mix[c].size(); ++i)
        mix[c][u * 64000 + i] += (*wet)[c][i];
  }
  const Channels dry = mix;
  add_noise(mix, 20, NoiseColor::kPink, 7);
  for (const auto& channel : mix)
    for (double v : channel) ASSERT_TRUE(std::isfinite(v));
  // Each utterance's first second carries energy well above the 20 dB-down noise.
  for (int u = 0; u < 5; ++u) {
    double speech = 0, total = 0;
    for (size_t i = 0; i < 16000; ++i) {
      const size_t k = static_cast<size_t>(u) * 64000 + 4000 + i;
      speech += dry[0][k] * dry[0][k];
      total += mix[0][k] * mix[0][k];
    }
    EXPECT_GT(speech, 0.5 * total) << "utterance " << u;
  }
}

}  // namespace
}  // namespace dreamsense::sim
