#include "dreamsense/audio/audio_file.hpp"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace dreamsense::audio {
namespace {
namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path d =
      fs::temp_directory_path() /
      ("ds_audio_file_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::create_directories(d);
  return d;
}

void write_wav(const fs::path& p, const std::vector<int16_t>& interleaved, int channels, int rate) {
  SF_INFO info{};
  info.samplerate = rate;
  info.channels = channels;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* f = sf_open(p.string().c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr);
  sf_write_short(f, interleaved.data(), static_cast<sf_count_t>(interleaved.size()));
  sf_close(f);
}

TEST(ReadAudio, Pcm16WavIsExactAndChannelsCanBePicked) {
  const fs::path p = temp_dir() / "stereo.wav";
  const std::vector<int16_t> s = {100, -200, 32767, -32768, 0, 5};  // 3 frames, 2 channels
  write_wav(p, s, 2, 8000);
  auto all = read_audio(p);
  ASSERT_TRUE(all) << all.error().message;
  EXPECT_EQ(all->sample_rate, 8000);
  EXPECT_EQ(all->channels, 2);
  EXPECT_EQ(all->frames(), 3);
  EXPECT_EQ(to_pcm16(all->samples), s);
  ReadAudioOptions right;
  right.channel = 1;
  auto r = read_audio(p, right);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->channels, 1);
  EXPECT_EQ(to_pcm16(r->samples), (std::vector<int16_t>{-200, -32768, 5}));
  ReadAudioOptions mono;
  mono.require_mono = true;
  auto bad = read_audio(p, mono);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("stereo.wav: expected mono"), std::string::npos)
      << bad.error().message;
  auto info = audio_file_info(p);
  ASSERT_TRUE(info);
  EXPECT_EQ(info->frames, 3);
  fs::remove(p);
}

TEST(ReadAudio, HeaderlessRawIsLittleEndianPcm16) {
  const fs::path p = temp_dir() / "clip.raw";
  {
    std::ofstream out(p, std::ios::binary);
    const unsigned char bytes[] = {0x01, 0x00, 0xff, 0xff, 0x00, 0x80, 0x7f};  // odd byte dropped
    out.write(reinterpret_cast<const char*>(bytes), sizeof bytes);
  }
  auto a = read_audio(p);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->sample_rate, 16000);
  EXPECT_EQ(to_pcm16(a->samples), (std::vector<int16_t>{1, -1, -32768}));
  ReadAudioOptions at8k;
  at8k.expected_sample_rate = 8000;
  EXPECT_FALSE(read_audio(p, at8k));
  fs::remove(p);
}

TEST(ReadAudio, ResamplesOnRequest) {
  const fs::path p = temp_dir() / "tone.wav";
  std::vector<int16_t> s(8000);
  for (size_t i = 0; i < s.size(); ++i)
    s[i] = static_cast<int16_t>(10000 * std::sin(2 * std::numbers::pi * 440 * i / 8000.0));
  write_wav(p, s, 1, 8000);
  ReadAudioOptions up;
  up.resample_to_hz = 16000;
  auto a = read_audio(p, up);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->sample_rate, 16000);
  EXPECT_NEAR(static_cast<double>(a->frames()), 16000.0, 2.0);
  // The tone keeps its amplitude (within the filter's pass band).
  float peak = 0;
  for (size_t i = 2000; i < 14000; ++i) peak = std::max(peak, std::abs(a->samples[i]));
  EXPECT_NEAR(peak, 10000 / 32768.0, 0.01);
  fs::remove(p);
}

TEST(ReadAudio, MissingAndBrokenFilesNameTheFile) {
  auto missing = read_audio("/nonexistent/x.wav");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message, "/nonexistent/x.wav: audio file missing");
  const fs::path p = temp_dir() / "broken.wav";
  std::ofstream(p) << "not audio";
  auto broken = read_audio(p);
  ASSERT_FALSE(broken);
  EXPECT_EQ(broken.error().message.rfind(p.string() + ": cannot read audio", 0), 0u)
      << broken.error().message;
  fs::remove(p);
}

TEST(ResamplePcm16, SameRateCopiesAndBothMethodsKeepLength) {
  const std::vector<int16_t> s(800, 1000);
  EXPECT_EQ(resample_pcm16(s, 8000, 8000), s);
  EXPECT_EQ(resample_pcm16(s, 8000, 16000, Pcm16Resampler::kSoxr).size(), 1600u);
  const auto sinc = resample_pcm16(s, 8000, 16000, Pcm16Resampler::kSinc);
  ASSERT_EQ(sinc.size(), 1600u);
  EXPECT_NEAR(sinc[800], 1000, 5);  // DC passes
}

TEST(AudioFiles, ListsAudioByExtensionSorted) {
  const fs::path d = temp_dir() / "list";
  fs::create_directories(d);
  for (const char* n : {"b.WAV", "a.raw", "c.txt", "d.flac"}) std::ofstream(d / n) << "x";
  const auto files = audio_files_in(d);
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].filename(), "a.raw");
  EXPECT_EQ(files[1].filename(), "b.WAV");
  EXPECT_EQ(files[2].filename(), "d.flac");
  fs::remove_all(d);
}

}  // namespace
}  // namespace dreamsense::audio
