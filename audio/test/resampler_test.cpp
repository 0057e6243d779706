// Resampler: frequency and length preserved, stamps continuous across chunks, gaps re-anchor.

#include "dreamsense/audio/resampler.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace dreamsense::audio {
namespace {

std::vector<float> sine(double hz, int rate, int64_t n, int channels = 1, double amp = 0.5) {
  std::vector<float> x(static_cast<size_t>(n * channels));
  for (int64_t i = 0; i < n; ++i)
    for (int c = 0; c < channels; ++c)
      x[static_cast<size_t>(i * channels + c)] = static_cast<float>(
          amp * std::sin(2 * std::numbers::pi * hz * static_cast<double>(i) / rate + c));
  return x;
}

// Frequency of a mono signal by zero crossings (interpolated), over its middle part.
double frequency(const std::vector<float>& x, int rate, size_t stride = 1, size_t offset = 0) {
  std::vector<double> crossings;
  const size_t n = x.size() / stride;
  for (size_t i = n / 10; i + 1 < n * 9 / 10; ++i) {
    const double a = x[i * stride + offset], b = x[(i + 1) * stride + offset];
    if (a < 0 && b >= 0) crossings.push_back(static_cast<double>(i) + a / (a - b));
  }
  if (crossings.size() < 2) return 0;
  return (static_cast<double>(crossings.size()) - 1) /
         ((crossings.back() - crossings.front()) / rate);
}

struct Collected {
  std::vector<StampedAudio> blocks;
  std::vector<float> all() const {
    std::vector<float> out;
    for (const auto& b : blocks)
      out.insert(out.end(), b.audio.samples.begin(), b.audio.samples.end());
    return out;
  }
};

// Feeds `x` in chunks of `chunk` frames stamped from sample counts at `t0`.
Collected stream(Resampler& r, const std::vector<float>& x, int channels, int rate, int64_t chunk,
                 Timestamp t0) {
  Collected c;
  const int64_t n = static_cast<int64_t>(x.size()) / channels;
  for (int64_t i = 0; i < n; i += chunk) {
    const int64_t len = std::min(chunk, n - i);
    EXPECT_TRUE(r.process(std::span<const float>(x).subspan(static_cast<size_t>(i * channels),
                                                            static_cast<size_t>(len * channels)),
                          t0 + frames_to_duration(i, rate), c.blocks));
  }
  EXPECT_TRUE(r.flush(c.blocks));
  return c;
}

TEST(Resampler, PreservesSineFrequencyAndLength) {
  for (auto [from, to] : {std::pair{44100, 16000},
                          {48000, 16000},
                          {8000, 16000},
                          {22050, 16000},
                          {16000, 48000},
                          {16000, 16000}}) {
    SCOPED_TRACE(fmt::format("{} -> {}", from, to));
    const int64_t n = from * 2 + 37;  // 2 s and a bit, not a multiple of the chunk
    const auto x = sine(1000.0, from, n);
    ResamplerOptions o;
    o.input_rate = from;
    o.output_rate = to;
    auto r = Resampler::create(o);
    ASSERT_TRUE(r) << r.error().message;
    const auto y = stream(**r, x, 1, from, 441, Timestamp::from_ns(0)).all();
    const double expected_len = static_cast<double>(n) * to / from;
    EXPECT_NEAR(static_cast<double>(y.size()), expected_len, 1.0);
    EXPECT_NEAR(frequency(y, to), 1000.0, 0.5);
    // Amplitude kept (pass band): RMS of the middle part.
    double s2 = 0;
    for (size_t i = y.size() / 4; i < y.size() * 3 / 4; ++i) s2 += y[i] * y[i];
    EXPECT_NEAR(std::sqrt(s2 / static_cast<double>(y.size() / 2)), 0.5 / std::sqrt(2.0), 0.01);
  }
}

TEST(Resampler, MultichannelInt16KeepsChannelsApart) {
  const int from = 48000, to = 16000, ch = 4;
  const int64_t n = from;
  std::vector<int16_t> x(static_cast<size_t>(n * ch));
  for (int64_t i = 0; i < n; ++i)
    for (int c = 0; c < ch; ++c)
      x[static_cast<size_t>(i * ch + c)] =
          static_cast<int16_t>(12000 * std::sin(2 * std::numbers::pi * (500.0 * (c + 1)) *
                                                static_cast<double>(i) / from));
  ResamplerOptions o;
  o.input_rate = from;
  o.output_rate = to;
  o.channels = ch;
  auto r = Resampler::create(o);
  ASSERT_TRUE(r);
  std::vector<StampedAudio> out;
  for (int64_t i = 0; i < n; i += 480)
    ASSERT_TRUE(
        (*r)->process(std::span<const int16_t>(x).subspan(static_cast<size_t>(i * ch), 480 * ch),
                      Timestamp::from_ns(0) + frames_to_duration(i, from), out));
  ASSERT_TRUE((*r)->flush(out));
  std::vector<float> y;
  for (const auto& b : out) {
    EXPECT_EQ(b.audio.channels, ch);
    EXPECT_EQ(b.audio.sample_rate, to);
    y.insert(y.end(), b.audio.samples.begin(), b.audio.samples.end());
  }
  EXPECT_EQ(y.size(), static_cast<size_t>(to * ch));
  for (int c = 0; c < ch; ++c)
    EXPECT_NEAR(frequency(y, to, ch, static_cast<size_t>(c)), 500.0 * (c + 1), 1.0);
}

TEST(Resampler, StampsAreContinuousAcrossChunks) {
  const int from = 44100, to = 16000;
  const auto x = sine(440.0, from, from * 3);
  ResamplerOptions o;
  o.input_rate = from;
  o.output_rate = to;
  auto r = Resampler::create(o);
  ASSERT_TRUE(r);
  const Timestamp t0 = Timestamp::from_ns(1'234'567'891);
  const auto c = stream(**r, x, 1, from, 1000, t0);
  ASSERT_GT(c.blocks.size(), 10u);
  EXPECT_EQ(c.blocks.front().stamp, t0) << "output starts where the input starts";
  int64_t k = 0;
  for (const auto& b : c.blocks) {
    EXPECT_EQ(b.stamp, t0 + frames_to_duration(k, to)) << "block " << k;
    k += b.audio.frames();
  }
  EXPECT_EQ(k, to * 3) << "exact length after flush";
}

TEST(Resampler, GapStartsANewSegment) {
  const int from = 48000, to = 16000;
  const auto x = sine(300.0, from, 4800);
  ResamplerOptions o;
  o.input_rate = from;
  o.output_rate = to;
  auto r = Resampler::create(o);
  ASSERT_TRUE(r);
  std::vector<StampedAudio> out;
  ASSERT_TRUE((*r)->process(x, Timestamp::from_seconds(1.0), out));
  // 0.5 s later than the 0.1 s of audio implies: the first segment is flushed first.
  ASSERT_TRUE((*r)->process(x, Timestamp::from_seconds(1.6), out));
  ASSERT_TRUE((*r)->flush(out));
  int64_t first = 0;
  size_t i = 0;
  for (; i < out.size() && out[i].stamp < Timestamp::from_seconds(1.5); ++i)
    first += out[i].audio.frames();
  EXPECT_EQ(first, 1600);
  ASSERT_LT(i, out.size());
  EXPECT_EQ(out[i].stamp, Timestamp::from_seconds(1.6));
  int64_t second = 0;
  for (; i < out.size(); ++i) second += out[i].audio.frames();
  EXPECT_EQ(second, 1600);
}

TEST(Resampler, RejectsBadOptionsAndPartialFrames) {
  ResamplerOptions o;
  o.input_rate = 0;
  o.channels = 0;
  auto r = Resampler::create(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("input_rate"), std::string::npos);
  EXPECT_NE(r.error().message.find("channels"), std::string::npos);
  o.input_rate = 8000;
  o.channels = 2;
  auto ok = Resampler::create(o);
  ASSERT_TRUE(ok);
  std::vector<StampedAudio> out;
  const std::vector<float> three(3, 0.f);
  EXPECT_FALSE((*ok)->process(three, Timestamp::from_ns(0), out));
}

TEST(Resampler, ConvertWholeBuffer) {
  const auto x = sine(1000.0, 8000, 8000);
  auto y = Resampler::convert(x, 1, 8000, 16000);
  ASSERT_TRUE(y);
  EXPECT_EQ(y->size(), 16000u);
  EXPECT_NEAR(frequency(*y, 16000), 1000.0, 0.5);
}

}  // namespace
}  // namespace dreamsense::audio
