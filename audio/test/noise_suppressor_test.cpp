#include "dreamsense/audio/noise_suppressor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace dreamsense::audio {
namespace {

double band_power(const std::vector<float>& x, size_t a, size_t b) {
  double p = 0;
  for (size_t i = a; i < b; ++i) p += static_cast<double>(x[i]) * x[i];
  return p / static_cast<double>(b - a);
}

// 1 s of noise, then a 2 s "vowel" (harmonics of 200 Hz) in the same noise, 10 dB SNR.
struct Scene {
  std::vector<float> clean, noisy;
};
Scene scene(int rate, double noise_rms, uint64_t seed) {
  Scene s;
  const size_t n = static_cast<size_t>(3 * rate);
  s.clean.assign(n, 0.0f);
  for (size_t i = static_cast<size_t>(rate); i < n; ++i)
    for (int h = 1; h <= 10; ++h)
      s.clean[i] += static_cast<float>(
          0.03 / h * std::sin(2 * M_PI * 200 * h * static_cast<double>(i) / rate));
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, noise_rms);
  s.noisy = s.clean;
  for (auto& v : s.noisy) v += static_cast<float>(g(rng));
  return s;
}

TEST(NoiseSuppressor, RaisesTheSnrOfAVoiceInWhiteNoise) {
  const int rate = 16000;
  const Scene s = scene(rate, 0.012, 3);
  auto y = suppress_noise(s.noisy, rate);
  ASSERT_TRUE(y);
  ASSERT_EQ(y->size(), s.noisy.size());
  // SNR = clean power / error power over the voice part (after 0.3 s of it).
  auto snr = [&](const std::vector<float>& x) {
    double e = 0, c = 0;
    for (size_t i = static_cast<size_t>(1.3 * rate); i < x.size(); ++i) {
      e += (x[i] - s.clean[i]) * (x[i] - s.clean[i]);
      c += s.clean[i] * s.clean[i];
    }
    return 10 * std::log10(c / e);
  };
  const double before = snr(s.noisy), after = snr(*y);
  EXPECT_GT(after, before + 5) << before << " -> " << after;
  // The noise alone is attenuated by about the gain floor (15 dB), at least 10 dB.
  const double att =
      10 * std::log10(band_power(s.noisy, 4000, 15000) / band_power(*y, 4000, 15000));
  EXPECT_GT(att, 10);
  EXPECT_LT(att, 17);
}

TEST(NoiseSuppressor, PassesCleanSpeechAndKeepsChannelsInPhase) {
  const int rate = 16000;
  Scene s = scene(rate, 1e-5, 5);
  // Two channels: the second is the first delayed by 3 samples.
  std::vector<float> st(2 * s.noisy.size());
  for (size_t i = 0; i < s.noisy.size(); ++i) {
    st[2 * i] = s.noisy[i];
    st[2 * i + 1] = i >= 3 ? s.noisy[i - 3] : 0.0f;
  }
  NoiseSuppressorOptions o;
  o.channels = 2;
  auto ns = NoiseSuppressor::create(o);
  ASSERT_TRUE(ns);
  std::vector<float> out;
  for (size_t i = 0; i < st.size(); i += 2 * 333)  // odd chunk sizes
    (*ns)->process(std::span<const float>(st).subspan(i, std::min<size_t>(2 * 333, st.size() - i)),
                   out);
  (*ns)->flush(out);
  ASSERT_EQ(out.size(), st.size() + 2 * static_cast<size_t>((*ns)->latency()));
  const size_t lat = static_cast<size_t>((*ns)->latency());
  double e = 0, c = 0, d = 0;
  for (size_t i = static_cast<size_t>(1.5 * rate); i < s.noisy.size(); ++i) {
    const float y0 = out[2 * (i + lat)], y1 = out[2 * (i + lat + 3) + 1];
    e += (y0 - s.clean[i]) * (y0 - s.clean[i]);
    d += (y1 - y0) * (y1 - y0);
    c += s.clean[i] * s.clean[i];
  }
  EXPECT_LT(10 * std::log10(e / c), -20);  // the voice passes (clean input)
  EXPECT_LT(10 * std::log10(d / c), -30);  // channel 1 = channel 0 delayed, as in the input
}

TEST(NoiseSuppressor, BadOptions) {
  NoiseSuppressorOptions o;
  o.channels = 0;
  o.gain_floor_db = 5;
  EXPECT_FALSE(NoiseSuppressor::create(o));
}

}  // namespace
}  // namespace dreamsense::audio
