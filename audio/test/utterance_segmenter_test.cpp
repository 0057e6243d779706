// Utterance segmenter: boundaries, pre-roll, hangover, min/max length, stamps, channels, gaps.

#include "dreamsense/audio/utterance_segmenter.hpp"

#include "dreamsense/audio/stamped_audio.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace dreamsense::audio {
namespace {

constexpr int kSegmenterRate = 16000;

// `channels`-channel stream of `seconds` of low noise with tone bursts [from, to) (seconds);
// channel c carries the burst scaled by (c + 1).
std::vector<float> scene(double seconds, const std::vector<std::pair<double, double>>& bursts,
                         int channels = 1, uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> d(0.f, 0.002f);
  const int64_t n = static_cast<int64_t>(seconds * kSegmenterRate);
  std::vector<float> x(static_cast<size_t>(n * channels));
  for (int64_t i = 0; i < n; ++i) {
    double s = 0;
    const double t = static_cast<double>(i) / kSegmenterRate;
    for (auto [a, b] : bursts)
      // Syllables of 0.3 s, each at another pitch (a steady tone longer than the noise window
      // would rightly be taken for noise).
      if (t >= a && t < b) {
        const double f0 = 220.0 * (1 + 0.15 * (static_cast<int>((t - a) / 0.3) % 5));
        s += 0.1 * std::sin(2 * std::numbers::pi * 2 * f0 * t) +
             0.05 * std::sin(2 * std::numbers::pi * 6 * f0 * t);
      }
    for (int c = 0; c < channels; ++c)
      x[static_cast<size_t>(i * channels + c)] = static_cast<float>(s * (c + 1)) + d(rng);
  }
  return x;
}

std::vector<Utterance> segment(const std::vector<float>& x, UtteranceSegmenterOptions o,
                               Timestamp t0 = Timestamp::from_ns(0), bool flush = true) {
  auto seg = UtteranceSegmenter::create(o);
  EXPECT_TRUE(seg) << (seg ? "" : seg.error().message);
  std::vector<Utterance> out;
  const int64_t chunk = 640, ch = o.channels;
  const int64_t n = static_cast<int64_t>(x.size()) / ch;
  for (int64_t i = 0; i < n; i += chunk) {
    const int64_t len = std::min(chunk, n - i);
    EXPECT_TRUE((*seg)->push(std::span<const float>(x).subspan(static_cast<size_t>(i * ch),
                                                               static_cast<size_t>(len * ch)),
                             t0 + frames_to_duration(i, kSegmenterRate), out));
  }
  if (flush) (*seg)->flush(out);
  return out;
}

double s(Timestamp t) { return t.seconds(); }

TEST(UtteranceSegmenter, BoundariesPreRollAndHangover) {
  UtteranceSegmenterOptions o;
  const auto x = scene(8.0, {{1.0, 2.0}, {4.0, 5.5}});
  const auto u = segment(x, o);
  ASSERT_EQ(u.size(), 2u);
  const double frame = 0.02;
  EXPECT_NEAR(s(u[0].speech_start), 1.0, frame);
  EXPECT_NEAR(s(u[0].speech_end), 2.0, frame);
  EXPECT_NEAR(s(u[0].start), 1.0 - o.pre_roll_s, frame);
  EXPECT_NEAR(s(u[0].end), 2.0 + o.hangover_s, frame);
  EXPECT_NEAR(s(u[1].speech_start), 4.0, frame);
  EXPECT_NEAR(s(u[1].speech_end), 5.5, frame);
  for (const auto& v : u) {
    EXPECT_FALSE(v.truncated);
    EXPECT_EQ(v.frames(), duration_to_frames(v.end - v.start, kSegmenterRate))
        << "samples match stamps";
    EXPECT_GT(v.mean_probability, 0.5f);
  }
}

TEST(UtteranceSegmenter, StampsFollowTheStreamAnchor) {
  UtteranceSegmenterOptions o;
  const auto x = scene(4.0, {{1.0, 2.0}});
  const Timestamp t0 = Timestamp::from_seconds(100.0);
  const auto u = segment(x, o, t0);
  ASSERT_EQ(u.size(), 1u);
  EXPECT_NEAR(s(u[0].speech_start) - 100.0, 1.0, 0.02);
  // The first sample of the utterance is exactly the stream sample its stamp says.
  const int64_t first = duration_to_frames(u[0].start - t0, kSegmenterRate);
  EXPECT_FLOAT_EQ(u[0].samples[0], x[static_cast<size_t>(first)]);
}

TEST(UtteranceSegmenter, ShortBurstsAndMinimumLengthAreIgnored) {
  UtteranceSegmenterOptions o;
  o.min_speech_s = 0.15;
  // 60 ms click: shorter than min_speech_s.
  EXPECT_TRUE(segment(scene(4.0, {{1.0, 1.06}}), o).empty());
  // 0.4 s burst, but min_utterance_s = 0.6.
  o.min_utterance_s = 0.6;
  EXPECT_TRUE(segment(scene(4.0, {{1.0, 1.4}}), o).empty());
  o.min_utterance_s = 0.3;
  EXPECT_EQ(segment(scene(4.0, {{1.0, 1.4}}), o).size(), 1u);
}

TEST(UtteranceSegmenter, ShortPausesStayInsideOneUtterance) {
  UtteranceSegmenterOptions o;
  o.hangover_s = 0.5;
  const auto u = segment(scene(6.0, {{1.0, 1.8}, {2.1, 3.0}}), o);  // 0.3 s pause
  ASSERT_EQ(u.size(), 1u);
  EXPECT_NEAR(s(u[0].speech_end), 3.0, 0.02);
}

TEST(UtteranceSegmenter, LongSpeechIsCutAtMaxLength) {
  UtteranceSegmenterOptions o;
  o.max_utterance_s = 2.0;
  const auto u = segment(scene(8.0, {{1.0, 6.0}}), o);
  ASSERT_GE(u.size(), 3u);
  EXPECT_TRUE(u[0].truncated);
  EXPECT_NEAR((u[0].end - u[0].start).seconds(), 2.0, 0.021);
  EXPECT_EQ(u[1].start, u[0].end) << "no sample lost at the cut";
  EXPECT_FALSE(u.back().truncated);
  EXPECT_NEAR(s(u.back().speech_end), 6.0, 0.02);
}

TEST(UtteranceSegmenter, KeepsAllChannelsAndDecidesOnTheChosenOne) {
  UtteranceSegmenterOptions o;
  o.channels = 3;
  o.vad_channel = 2;
  const auto u = segment(scene(4.0, {{1.0, 2.0}}, 3), o);
  ASSERT_EQ(u.size(), 1u);
  EXPECT_EQ(u[0].channels, 3);
  const auto c0 = u[0].channel(0), c2 = u[0].channel(2);
  ASSERT_EQ(c0.size(), c2.size());
  double e0 = 0, e2 = 0;
  for (size_t i = 0; i < c0.size(); ++i) e0 += c0[i] * c0[i], e2 += c2[i] * c2[i];
  EXPECT_NEAR(e2 / e0, 9.0, 0.5) << "channel 2 carries the burst at 3x";
}

TEST(UtteranceSegmenter, OpenUtteranceIsClosedByFlushOrByAGap) {
  UtteranceSegmenterOptions o;
  const auto x = scene(3.0, {{1.0, 3.0}});  // speech until the end
  EXPECT_TRUE(segment(x, o, Timestamp::from_ns(0), /*flush=*/false).empty());
  const auto flushed = segment(x, o);
  ASSERT_EQ(flushed.size(), 1u);
  EXPECT_NEAR(s(flushed[0].end), 3.0, 1e-6);

  // A 1 s gap in the stamps closes the utterance and re-anchors the stream.
  auto seg = UtteranceSegmenter::create(o);
  ASSERT_TRUE(seg);
  std::vector<Utterance> out;
  ASSERT_TRUE((*seg)->push(x, Timestamp::from_ns(0), out));
  EXPECT_TRUE(out.empty());
  ASSERT_TRUE(
      (*seg)->push(std::span<const float>(x).subspan(0, 640), Timestamp::from_seconds(4.0), out));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(s(out[0].end), 3.0, 1e-6);
  EXPECT_EQ((*seg)->stamp_of(0), Timestamp::from_seconds(4.0));
}

TEST(UtteranceSegmenter, FadeInTouchesOnlyThePreRoll) {
  Utterance u;
  u.sample_rate = 1000;
  u.channels = 1;
  u.start = Timestamp::from_seconds(1.0);
  u.speech_start = Timestamp::from_seconds(1.05);  // 50 samples of pre-roll
  std::vector<float> mono(200, 1.0f);
  fade_in_pre_roll(mono, u, 0.1);  // 100 samples asked, the pre-roll allows 50
  EXPECT_EQ(mono[0], 0.0f);
  EXPECT_NEAR(mono[25], 0.5f, 1e-6);
  EXPECT_LT(mono[49], 1.0f);
  for (size_t i = 50; i < mono.size(); ++i) ASSERT_EQ(mono[i], 1.0f) << i;

  std::vector<float> shorter(200, 1.0f);
  fade_in_pre_roll(shorter, u, 0.02);  // 20 samples
  EXPECT_NEAR(shorter[10], 0.5f, 1e-6);
  EXPECT_EQ(shorter[20], 1.0f);

  // Speech from the first sample (a cut at the robot's voice) or 0 s: nothing changes.
  std::vector<float> untouched(200, 1.0f);
  fade_in_pre_roll(untouched, u, 0.0);
  u.speech_start = u.start;
  fade_in_pre_roll(untouched, u, 0.1);
  EXPECT_EQ(untouched, std::vector<float>(200, 1.0f));
}

TEST(UtteranceSegmenter, OptionsAreChecked) {
  UtteranceSegmenterOptions o;
  o.channels = 2;
  o.vad_channel = 5;
  o.max_utterance_s = 0.1;
  auto seg = UtteranceSegmenter::create(o);
  ASSERT_FALSE(seg);
  EXPECT_NE(seg.error().message.find("vad_channel"), std::string::npos);
  EXPECT_NE(seg.error().message.find("max_utterance_s"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::audio
