// Live ALSA capture. This machine may have no sound card: the device tests use ALSA's "null"
// PCM (silence, no hardware) and skip cleanly when even that cannot be opened; the hardware
// test runs only when ALSA lists a capture card.

#include "dreamsense/sources/alsa_audio_source.hpp"

#include <gtest/gtest.h>

namespace dreamsense::sources {
namespace {

TEST(AlsaAudioSource, MissingDeviceIsAClearErrorNotACrash) {
  AlsaAudioSourceOptions o;
  o.device = "dreamsense_no_such_device";
  auto s = AlsaAudioSource::open(o);
  ASSERT_FALSE(s);
  if (s.error().code == ErrorCode::kUnsupported) GTEST_SKIP() << s.error().message;
  EXPECT_EQ(s.error().code, ErrorCode::kNotFound) << s.error().message;
  EXPECT_NE(s.error().message.find("dreamsense_no_such_device"), std::string::npos);

  o.device = "hw:63,0";  // card 63 does not exist
  s = AlsaAudioSource::open(o);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("hw:63,0"), std::string::npos) << s.error().message;
}

TEST(AlsaAudioSource, BadOptionsAreListed) {
  AlsaAudioSourceOptions o;
  o.channels = 0;
  o.sample_rate = 5;
  o.chunk_s = 0;
  auto s = AlsaAudioSource::open(o);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  for (const char* field : {"channels", "sample_rate", "chunk_s"})
    EXPECT_NE(s.error().message.find(field), std::string::npos) << field;
}

TEST(AlsaAudioSource, NullDeviceDeliversChunksWithSampleCountStamps) {
  AlsaAudioSourceOptions o;
  o.device = "null";
  o.sensor = "mic";
  o.channels = 4;
  o.sample_rate = 16000;
  auto s = AlsaAudioSource::open(o);
  if (!s) GTEST_SKIP() << "ALSA 'null' device unavailable: " << s.error().message;
  const SourceInfo info = (*s)->info();
  ASSERT_EQ(info.sensors.size(), 1u);
  EXPECT_TRUE(info.live);
  EXPECT_EQ(info.sensors[0].channels, 4);
  EXPECT_EQ(info.sensors[0].sample_rate, 16000);
  // The null device is not paced: the capture runs ahead and drops the oldest queued chunks
  // (counted), so sequence numbers may start above 0; stamps follow them exactly.
  Timestamp first;
  uint64_t first_seq = 0;
  for (uint64_t k = 0; k < 5; ++k) {
    auto f = (*s)->next();
    ASSERT_TRUE(f) << f.error().message;
    const AudioChunk* a = (*f)->as<AudioChunk>();
    ASSERT_NE(a, nullptr);
    EXPECT_EQ((*f)->sensor, "mic");
    EXPECT_EQ(a->channels, 4);
    EXPECT_EQ(a->sample_rate, 16000);
    EXPECT_EQ(a->frames(), 640);
    if (k == 0) {
      first = (*f)->stamp;
      first_seq = (*f)->sequence;
    }
    const int64_t seq = static_cast<int64_t>((*f)->sequence - first_seq);
    if ((*s)->stats().overruns == 0) {
      EXPECT_EQ((*f)->stamp, first + Duration::from_ms(40) * seq) << "stamps from the sample count";
    }
  }
  (*s)->stop();
  // After stop: what was queued, then end of stream.
  for (int i = 0; i < 1000; ++i) {
    auto f = (*s)->next();
    if (!f) {
      EXPECT_TRUE(is_end_of_stream(f.error())) << f.error().message;
      break;
    }
  }
}

TEST(AlsaAudioSource, CapturesFromARealCardWhenThereIsOne) {
  if (!AlsaAudioSource::has_capture_card()) GTEST_SKIP() << "no ALSA capture card on this machine";
  AlsaAudioSourceOptions o;
  o.device = "default";
  o.channels = 1;
  o.sample_rate = 16000;
  auto s = AlsaAudioSource::open(o);
  if (!s) GTEST_SKIP() << "capture card present but 'default' unusable: " << s.error().message;
  auto f = (*s)->next();
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ((*f)->as<AudioChunk>()->frames(), 640);
}

}  // namespace
}  // namespace dreamsense::sources
