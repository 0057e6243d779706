// The speech analyser through a MultiFrame harness: audio chunks in, recognised utterances out.

#include "dreamsense/speech/speech_analyzer.hpp"

#include "dreamsense/core/perception.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;
const fs::path kTestData = "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata

std::vector<float> read_raw_float(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<float> out;
  int16_t v;
  while (in.read(reinterpret_cast<char*>(&v), 2)) out.push_back(v / 32768.f);
  return out;
}

// Feeds `mono` (16 kHz) as 2-channel 40 ms chunks, one per 25 Hz tick, with low noise; returns
// every recognised utterance written to the blackboard.
std::vector<RecognizedSpeech> run(Analyzer& a, const std::vector<float>& mono) {
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.f, 3e-4f);
  Blackboard bb;
  std::vector<RecognizedSpeech> heard;
  const int64_t chunk = 640;
  for (int64_t k = 0; k * chunk < static_cast<int64_t>(mono.size()); ++k) {
    AudioChunk c;
    c.sample_rate = 16000;
    c.channels = 2;
    for (int64_t i = k * chunk; i < std::min<int64_t>((k + 1) * chunk, mono.size()); ++i) {
      c.samples.push_back(mono[static_cast<size_t>(i)] + noise(rng));
      c.samples.push_back(mono[static_cast<size_t>(i)] + noise(rng));
    }
    MultiFrame mf;
    mf.stamp = Timestamp::from_ns(k * 40'000'000LL);
    mf.chunks["mic"].push_back(make_frame("mic", mf.stamp, static_cast<uint64_t>(k), c));
    BlackboardWriter w("speech");
    EXPECT_TRUE(a.process(mf, bb.snapshot(), w));
    bb.commit(w, mf.stamp);
    auto e = bb.snapshot().get(keys::kRecognizedSpeech);
    if (e && e->present() && e->stamp == mf.stamp) heard.push_back(*e->value);
  }
  return heard;
}

TEST(SpeechAnalyzer, CutsTheUtteranceOutOfTheStreamAndRecognisesIt) {
  if (!fs::exists(RecognizerOptions{}.model_dir / "mdef") ||
      !fs::exists(kTestData / "goforward.raw"))
    GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.grammar = kTestData / "goforward.gram";
  auto a = make_speech_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  std::vector<float> stream(16000, 0.f);  // 1 s of quiet, the utterance, 2 s of quiet
  const auto speech = read_raw_float(kTestData / "goforward.raw");
  stream.insert(stream.end(), speech.begin(), speech.end());
  stream.insert(stream.end(), 32000, 0.f);
  const auto heard = run(**a, stream);
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0].text, "go forward ten meters");
  EXPECT_EQ(heard[0].sensor, "mic");
  EXPECT_GE(heard[0].start.seconds(), 0.5) << "stamps are on the stream's clock";
}

TEST(SpeechAnalyzer, QuietStreamWritesNothing) {
  if (!fs::exists(RecognizerOptions{}.model_dir / "mdef") ||
      !fs::exists(kTestData / "goforward.gram"))
    GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.grammar = kTestData / "goforward.gram";
  auto a = make_speech_analyzer(o);
  ASSERT_TRUE(a);
  EXPECT_TRUE(run(**a, std::vector<float>(48000, 0.f)).empty());
}

TEST(SpeechAnalyzer, OptionsAreChecked) {
  SpeechAnalyzerOptions o;
  EXPECT_FALSE(make_speech_analyzer(o)) << "no grammar";
  o.grammar = "/nonexistent.gram";
  auto a = make_speech_analyzer(o);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("/nonexistent.gram"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::speech
