// ResamplingSource: audio converted with exact sample accounting, other frames passed through.

#include "dreamsense/sources/resampling_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace dreamsense::sources {
namespace {

// 2 s of 2-channel 48 kHz audio in 40 ms chunks, and a skeleton frame every 100 ms.
class FakeSource : public Source {
 public:
  explicit FakeSource(int rate = 48000, Duration gap_at = Duration::from_seconds(100))
      : rate_(rate), gap_at_(gap_at) {}
  Result<FramePtr> next() override {
    const Timestamp t_audio =
        Timestamp::from_ns(0) + Duration::from_ms(40) * audio_k_ +
        (Duration::from_ms(40) * audio_k_ >= gap_at_ ? Duration::from_ms(500) : Duration());
    const Timestamp t_skel = Timestamp::from_ns(0) + Duration::from_ms(100) * skel_k_;
    if (audio_k_ >= 50 && skel_k_ >= 20) return make_error(ErrorCode::kEndOfStream, "fake: end");
    if (skel_k_ < 20 && (audio_k_ >= 50 || t_skel < t_audio))
      return make_frame("skeleton", t_skel, static_cast<uint64_t>(skel_k_++), Skeleton{});
    AudioChunk c;
    c.sample_rate = rate_;
    c.channels = 2;
    const int n = rate_ / 25;
    for (int i = 0; i < n; ++i) {
      const double t = static_cast<double>(audio_k_ * n + i) / rate_;
      c.samples.push_back(static_cast<float>(0.5 * std::sin(2 * std::numbers::pi * 1000 * t)));
      c.samples.push_back(0.f);
    }
    return make_frame("mic", t_audio, static_cast<uint64_t>(audio_k_++), std::move(c));
  }
  SourceInfo info() const override {
    SourceInfo i;
    SensorDescription a;
    a.id = "mic";
    a.kind = SensorKind::kAudio;
    a.sample_rate = rate_;
    a.channels = 2;
    a.rate_hz = 25;
    SensorDescription s;
    s.id = "skeleton";
    s.kind = SensorKind::kSkeleton;
    s.rate_hz = 10;
    i.sensors = {a, s};
    return i;
  }

 private:
  int rate_;
  Duration gap_at_;
  int64_t audio_k_ = 0, skel_k_ = 0;
};

TEST(ResamplingSource, ConvertsAudioExactlyAndPassesOtherFrames) {
  auto src = ResamplingSource::wrap(std::make_unique<FakeSource>(), {});
  ASSERT_TRUE(src) << src.error().message;
  EXPECT_EQ((*src)->info().find("mic")->sample_rate, 16000);
  EXPECT_EQ((*src)->info().find("skeleton")->kind, SensorKind::kSkeleton);
  int64_t frames = 0, skeletons = 0;
  uint64_t expect_seq = 0;
  Timestamp expect_stamp = Timestamp::from_ns(0);
  while (true) {
    auto f = (*src)->next();
    if (!f) {
      ASSERT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
    if ((*f)->sensor == "skeleton") {
      ++skeletons;
      continue;
    }
    const AudioChunk* a = (*f)->as<AudioChunk>();
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->sample_rate, 16000);
    EXPECT_EQ(a->channels, 2);
    EXPECT_EQ((*f)->sequence, expect_seq++);
    EXPECT_EQ((*f)->stamp, expect_stamp) << "continuous stamps";
    frames += a->frames();
    expect_stamp = Timestamp::from_ns(0) + Duration::from_ns(frames * 1'000'000'000LL / 16000);
  }
  EXPECT_EQ(frames, 2 * 16000) << "exact length after the end-of-stream flush";
  EXPECT_EQ(skeletons, 20);
}

TEST(ResamplingSource, GapInTheInputIsAGapInTheOutput) {
  auto src =
      ResamplingSource::wrap(std::make_unique<FakeSource>(44100, Duration::from_seconds(1.0)), {});
  ASSERT_TRUE(src);
  std::vector<std::pair<Timestamp, int64_t>> chunks;
  while (auto f = (*src)->next())
    if ((*f)->sensor == "mic") chunks.emplace_back((*f)->stamp, (*f)->as<AudioChunk>()->frames());
  ASSERT_FALSE(chunks.empty());
  int64_t before = 0;
  size_t i = 0;
  for (; i < chunks.size() && chunks[i].first < Timestamp::from_seconds(1.2); ++i)
    before += chunks[i].second;
  EXPECT_EQ(before, 16000) << "the first second, flushed at the gap";
  ASSERT_LT(i, chunks.size());
  EXPECT_EQ(chunks[i].first, Timestamp::from_seconds(1.5)) << "resumes at the input's stamp";
}

TEST(ResamplingSource, RejectsUnknownStreams) {
  ResamplingSourceOptions o;
  o.streams = {"skeleton"};
  auto src = ResamplingSource::wrap(std::make_unique<FakeSource>(), o);
  ASSERT_FALSE(src);
  EXPECT_NE(src.error().message.find("skeleton"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::sources
