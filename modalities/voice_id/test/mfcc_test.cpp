// MFCC front end: shapes, the spectral peak of a tone, silence dropping, normalisation, errors.

#include "dreamsense/voice_id/mfcc.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace dreamsense::voice_id {
namespace {

std::vector<float> tone(double hz, double seconds, int rate, double amp = 0.5) {
  std::vector<float> x(static_cast<size_t>(seconds * rate));
  for (size_t i = 0; i < x.size(); ++i)
    x[i] = static_cast<float>(amp * std::sin(2 * CV_PI * hz * static_cast<double>(i) / rate));
  return x;
}

TEST(Mfcc, MelScaleRoundTrips) {
  EXPECT_NEAR(hz_to_mel(1000), 1000, 1.0);  // the mel scale's anchor
  for (double hz : {0.0, 100.0, 1234.5, 3800.0}) EXPECT_NEAR(mel_to_hz(hz_to_mel(hz)), hz, 1e-6);
}

TEST(Mfcc, ToneGivesExpectedShapeAndPeaksInTheFilterAtItsFrequency) {
  MfccOptions o;
  const int rate = 16000;
  const auto x = tone(1000, 1.0, rate);
  auto mel = log_mel_spectrum(x, rate, o);
  ASSERT_TRUE(mel) << mel.error().message;
  // 25 ms frames every 10 ms: 1 + (16000 - 400) / 160 frames.
  EXPECT_EQ(mel->rows, 1 + (16000 - 400) / 160);
  EXPECT_EQ(mel->cols, o.filters);
  // The filter whose centre is nearest 1 kHz holds the peak in every frame.
  const double lo = hz_to_mel(o.low_hz), hi = hz_to_mel(o.high_hz);
  int expected = 0;
  double best = 1e9;
  for (int f = 0; f < o.filters; ++f) {
    const double centre = mel_to_hz(lo + (hi - lo) * (f + 1) / (o.filters + 1));
    if (std::abs(centre - 1000) < best) best = std::abs(centre - 1000), expected = f;
  }
  for (int t = 0; t < mel->rows; ++t) {
    cv::Point peak;
    cv::minMaxLoc(mel->row(t), nullptr, nullptr, nullptr, &peak);
    ASSERT_EQ(peak.x, expected) << "frame " << t;
  }
  auto c = static_cepstra(x, rate, o);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->rows, mel->rows);
  EXPECT_EQ(c->cols, o.cepstra);
  // Column 0 is the log frame energy: a steady tone has the same energy in every frame.
  EXPECT_NEAR(c->at<double>(10, 0), c->at<double>(50, 0), 1e-3);
  // The same tone at 8 kHz (FSDD's rate) peaks in the same filter: the bank is in Hz.
  auto mel8 = log_mel_spectrum(tone(1000, 1.0, 8000), 8000, o);
  ASSERT_TRUE(mel8);
  cv::Point peak8;
  cv::minMaxLoc(mel8->row(20), nullptr, nullptr, nullptr, &peak8);
  EXPECT_EQ(peak8.x, expected);
}

TEST(Mfcc, FeaturesHaveDeltasDropSilenceAndAreMeanNormalised) {
  MfccOptions o;
  const int rate = 16000;
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 1e-4f);
  std::vector<float> x(static_cast<size_t>(1.5 * rate));
  for (auto& v : x) v = noise(rng);
  // 0.5 s of a chirp-like vowel in the middle of 1.5 s of faint noise.
  for (size_t i = 0; i < static_cast<size_t>(0.5 * rate); ++i) {
    const double t = static_cast<double>(i) / rate;
    x[static_cast<size_t>(0.5 * rate) + i] += static_cast<float>(
        0.3 * std::sin(2 * CV_PI * (300 + 400 * t) * t) + 0.2 * std::sin(2 * CV_PI * 1700 * t));
  }
  auto f = compute_mfcc(x, rate, o);
  ASSERT_TRUE(f) << f.error().message;
  // 12 cepstra + 13 deltas + 13 delta-deltas (the static log energy is left out by default).
  EXPECT_EQ(f->frames.cols, 38);
  EXPECT_EQ(o.dimension(), 38);
  o.static_energy = true;
  EXPECT_EQ(o.dimension(), 39);
  EXPECT_EQ(f->frames_total, 1 + (24000 - 400) / 160);
  // About 50 voiced frames kept (+- the frames straddling the edges), the silence dropped.
  EXPECT_GE(f->frames_kept(), 45);
  EXPECT_LE(f->frames_kept(), 56);
  for (int j = 0; j < f->frames.cols; ++j)
    EXPECT_NEAR(cv::mean(f->frames.col(j))[0], 0.0, 1e-9) << "column " << j;
}

TEST(Mfcc, SilenceAndShortInputGiveNoFrames) {
  MfccOptions o;
  std::vector<float> zeros(16000, 0.f);
  auto f = compute_mfcc(zeros, 16000, o);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->frames_kept(), 0);
  EXPECT_EQ(f->frames.cols, 38);
  std::vector<float> tiny(100, 0.1f);
  auto g = compute_mfcc(tiny, 16000, o);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->frames_total, 0);
}

TEST(Mfcc, RejectsARateBelowTheBandAndBadOptions) {
  MfccOptions o;
  auto f = compute_mfcc(tone(500, 0.5, 6000), 6000, o);
  ASSERT_FALSE(f);
  EXPECT_EQ(f.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(f.error().message.find("6000 Hz"), std::string::npos);
  o.cepstra = 40;  // more than filters
  o.hop_s = 0;
  auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("cepstra"), std::string::npos);
  EXPECT_NE(s.error().message.find("hop_s"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::voice_id
