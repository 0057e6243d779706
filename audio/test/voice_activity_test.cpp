// Voice activity (the energy gate): a tone burst in noise is found where it is; stationary noise
// gives nothing; a long steady utterance stays whole.

#include "dreamsense/audio/voice_activity.hpp"

#include "dreamsense/audio/energy_gate.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace dreamsense::audio {
namespace {

std::vector<float> noise(int64_t n, double rms, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.f, static_cast<float>(rms));
  std::vector<float> x(static_cast<size_t>(n));
  for (auto& v : x) v = d(rng);
  return x;
}

// Pink-ish noise (first-order low-pass of white noise + white): the demo's kind of noise.
std::vector<float> coloured_noise(int64_t n, double rms, uint32_t seed) {
  auto w = noise(n, 1.0, seed);
  std::vector<float> x(w.size());
  double lp = 0, s2 = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    lp = 0.97 * lp + 0.03 * w[i];
    x[i] = static_cast<float>(4 * lp + 0.2 * w[i]);
    s2 += x[i] * x[i];
  }
  const double g = rms / std::sqrt(s2 / static_cast<double>(x.size()));
  for (auto& v : x) v = static_cast<float>(v * g);
  return x;
}

std::vector<VoiceActivityFrame> run(const std::vector<float>& x, VoiceActivityOptions o = {}) {
  auto vad = VoiceActivityDetector::create(o);
  EXPECT_TRUE(vad);
  std::vector<VoiceActivityFrame> frames;
  for (size_t i = 0; i < x.size(); i += 640)  // 40 ms chunks, not a multiple of the frame
    (*vad)->push(std::span<const float>(x).subspan(i, std::min<size_t>(640, x.size() - i)), frames);
  return frames;
}

TEST(VoiceActivity, FindsToneBurstInNoise) {
  const int rate = 16000;
  auto x = noise(rate * 6, 0.01, 1);
  // 1 kHz tone from 2.0 s to 3.0 s, 20 dB above the noise (the gate's floor may rise 3 dB during
  // the burst).
  const double amp = 0.01 * 10.0 * std::sqrt(2.0);
  for (int64_t i = 2 * rate; i < 3 * rate; ++i)
    x[static_cast<size_t>(i)] +=
        static_cast<float>(amp * std::sin(2 * std::numbers::pi * 1000.0 * i / rate));
  const auto frames = run(x);
  ASSERT_EQ(frames.size(), static_cast<size_t>(6 * rate / 320));
  int inside = 0, inside_speech = 0, outside_speech = 0;
  for (const auto& f : frames) {
    const double t = static_cast<double>(f.first_sample) / rate;
    if (t >= 2.02 && t < 2.98) {
      ++inside;
      inside_speech += f.speech;
      EXPECT_GT(f.probability, 0.5f);
    } else if (t < 1.98 || t >= 3.02) {
      outside_speech += f.speech;
    }
  }
  EXPECT_EQ(inside_speech, inside) << "every frame of the burst";
  EXPECT_LE(outside_speech, 2) << "at most a stray frame of noise";
}

TEST(VoiceActivity, StationaryNoiseIsNotSpeech) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    for (bool coloured : {false, true}) {
      const auto x =
          coloured ? coloured_noise(16000 * 20, 0.05, seed) : noise(16000 * 20, 0.05, seed);
      const auto frames = run(x);
      int speech = 0;
      for (const auto& f : frames) speech += f.speech;
      EXPECT_LE(speech, 2) << "seed " << seed << (coloured ? " coloured" : " white") << ": "
                           << speech << " of " << frames.size() << " frames";
    }
  }
}

TEST(VoiceActivity, DigitalSilenceAndLevelSteps) {
  // Digital silence stays finite and is not speech.
  const auto silent = run(std::vector<float>(16000 * 2, 0.f));
  for (const auto& f : silent) {
    EXPECT_TRUE(std::isfinite(f.snr_db));
    EXPECT_FALSE(f.speech);
  }
  // Noise 6 dB louder than before is under the 10 dB threshold at once, and the floor rises to
  // it within 2 s (3 dB/s): no speech.
  auto x = noise(16000 * 4, 0.01, 6);
  const auto loud = noise(16000 * 6, 0.02, 7);
  x.insert(x.end(), loud.begin(), loud.end());
  int speech = 0;
  for (const auto& f : run(x)) speech += f.speech;
  EXPECT_LE(speech, 2);
  // Known limit of the gate: after a noise step larger than the threshold the noise counts as
  // speech until the floor has risen to it (20 dB: about 3.3 s beyond the threshold).
  auto y = noise(16000 * 4, 0.001, 8);
  const auto step = noise(16000 * 8, 0.01, 9);
  y.insert(y.end(), step.begin(), step.end());
  int early = 0, late = 0;
  for (const auto& f : run(y)) {
    if (f.first_sample >= 16000 * 4 && f.first_sample < 16000 * 6) early += f.speech;
    if (f.first_sample > 16000 * 9) late += f.speech;
  }
  EXPECT_GT(early, 80) << "the first 2 s after the step";
  EXPECT_EQ(late, 0) << "the floor caught up after 20 dB / 3 dB/s";
}

TEST(VoiceActivity, OptionsAreChecked) {
  VoiceActivityOptions o;
  o.sample_rate = 100;
  o.frame_s = 1;
  auto v = VoiceActivityDetector::create(o);
  ASSERT_FALSE(v);
  EXPECT_NE(v.error().message.find("sample_rate"), std::string::npos);
  EXPECT_NE(v.error().message.find("frame_s"), std::string::npos);
}

// A reader who talks for 5 s without a pause (a steady tone here, 30 dB over the noise): the
// floor rises at most 3 dB/s, so the whole stretch stays speech.
TEST(VoiceActivity, KeepsALongUtteranceWhole) {
  const int rate = 16000;
  auto x = noise(rate * 8, 0.001, 4);
  const double amp = 0.001 * std::pow(10.0, 30.0 / 20) * std::sqrt(2.0);
  for (int64_t i = 2 * rate; i < 7 * rate; ++i)
    x[static_cast<size_t>(i)] +=
        static_cast<float>(amp * std::sin(2 * std::numbers::pi * 500.0 * i / rate));
  int speech = 0, outside = 0, inside = 0;
  const auto g = run(x);
  for (const auto& f : g) {
    const double t = static_cast<double>(f.first_sample) / rate;
    if (t >= 2.02 && t < 6.98) {
      ++inside;
      speech += f.speech;
    } else if (t < 1.98 || t >= 7.5) {
      outside += f.speech;
    }
  }
  EXPECT_EQ(speech, inside);
  EXPECT_EQ(outside, 0);
  // Near the end the floor has risen by at most 3 dB/s x 5 s = 15 dB over the noise.
  EXPECT_GT(g[static_cast<size_t>(6.9 * rate / 320)].snr_db, 30.0 - 15.0 - 0.5);
}

TEST(EnergyGate, FloorFollowsDropsRisesSlowlyAndHangoverAndMinLevelApply) {
  EnergyGateOptions o;
  o.threshold_db = 6;
  o.floor_rise_db_per_s = 1;
  o.min_level_dbfs = -70;
  o.hangover_frames = 2;
  ASSERT_TRUE(o.check());
  EnergyGate g(o, 0.5);              // the floor may rise 0.5 dB per frame
  EXPECT_FALSE(g.push(-60).speech);  // first frame: the floor
  EXPECT_TRUE(g.push(-50).speech);   // 10 dB over -60
  EXPECT_TRUE(g.push(-50).speech);   // floor -59.5
  EXPECT_TRUE(g.push(-60).speech);   // hangover 1
  EXPECT_TRUE(g.push(-60).speech);   // hangover 2
  EXPECT_FALSE(g.push(-60).speech);
  EXPECT_FALSE(g.push(-90).speech);  // drop: the floor follows at once
  EXPECT_FALSE(g.push(-80).speech);  // 10 dB over the floor but below min_level_dbfs
  const auto d = g.push(-40);
  EXPECT_TRUE(d.speech);
  EXPECT_NEAR(d.margin_db, -40 - (-89.5 + 6), 1e-9);  // floor -90, then +0.5 dB at -80
  g.reset();
  EXPECT_FALSE(g.push(-40).speech);  // forgotten: -40 is the new floor
  o.threshold_db = -1;
  EXPECT_FALSE(o.check());
}

}  // namespace
}  // namespace dreamsense::audio
