// The speech analyser through a MultiFrame harness: audio chunks in, recognised utterances out.

#include "dreamsense/speech/speech_analyzer.hpp"

#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/speech.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;
const fs::path kPocketsphinxData = "/usr/share/pocketsphinx/test/data";  // pocketsphinx-testdata

std::vector<float> read_raw_float(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<float> out;
  int16_t v;
  while (in.read(reinterpret_cast<char*>(&v), 2)) out.push_back(v / 32768.f);
  return out;
}

struct Heard {
  RecognizedSpeech speech;
  Timestamp tick;  // the tick that reported it
};

// Feeds `mono` (16 kHz) as 2-channel 40 ms chunks, one per 25 Hz tick, with low noise; returns
// every recognised utterance written to the blackboard. `paced_quiet_ticks`: then this many more
// quiet ticks, 10 ms of wall time apart (a live analysis, where a background decode finishes
// while later ticks run), stopping at the first report.
std::vector<Heard> run_ticks(Analyzer& a, std::vector<float> mono, int paced_quiet_ticks = 0) {
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.f, 3e-4f);
  Blackboard bb;
  std::vector<Heard> heard;
  const int64_t chunk = 640;
  const int64_t speech_ticks = (static_cast<int64_t>(mono.size()) + chunk - 1) / chunk;
  mono.resize(static_cast<size_t>((speech_ticks + paced_quiet_ticks) * chunk), 0.f);
  for (int64_t k = 0; k * chunk < static_cast<int64_t>(mono.size()); ++k) {
    if (k >= speech_ticks) {
      if (!heard.empty()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
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
    if (e && e->present() && e->stamp == mf.stamp) heard.push_back({*e->value, mf.stamp});
  }
  return heard;
}

std::vector<RecognizedSpeech> run(Analyzer& a, const std::vector<float>& mono) {
  std::vector<RecognizedSpeech> out;
  for (Heard& h : run_ticks(a, mono)) out.push_back(std::move(h.speech));
  return out;
}

bool has_goforward() {
  return fs::exists(RecognizerOptions{}.model_dir / "mdef") &&
         fs::exists(kPocketsphinxData / "goforward.raw");
}

// The analyser on a 2-channel stream "mic" with the test data's grammar.
SpeechAnalyzerOptions goforward_options() {
  SpeechAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.grammar = kPocketsphinxData / "goforward.gram";
  return o;
}

// 1 s of quiet, "go forward ten meters", then `quiet_after` samples of quiet.
std::vector<float> goforward_stream(size_t quiet_after) {
  std::vector<float> stream(16000, 0.f);
  const auto speech = read_raw_float(kPocketsphinxData / "goforward.raw");
  stream.insert(stream.end(), speech.begin(), speech.end());
  stream.insert(stream.end(), quiet_after, 0.f);
  return stream;
}

TEST(SpeechAnalyzer, CutsTheUtteranceOutOfTheStreamAndRecognisesIt) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  auto a = make_speech_analyzer(goforward_options());
  ASSERT_TRUE(a) << a.error().message;
  const auto heard = run(**a, goforward_stream(32000));
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0].text, "go forward ten meters");
  EXPECT_EQ(heard[0].sensor, "mic");
  EXPECT_GE(heard[0].start.seconds(), 0.5) << "stamps are on the stream's clock";
}

// A live analysis decodes on a background thread: the same utterance (words, confidence, stamps)
// is reported, at a later tick than the one that closed it, and the tick is not held up by it.
TEST(SpeechAnalyzer, BackgroundDecodingReportsTheSameUtteranceLater) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o = goforward_options();
  const std::vector<float> stream = goforward_stream(32000);
  auto tick_decoder = make_speech_analyzer(o);
  ASSERT_TRUE(tick_decoder) << tick_decoder.error().message;
  const auto at_tick = run_ticks(**tick_decoder, stream);
  ASSERT_EQ(at_tick.size(), 1u);

  o.background_decode = true;
  auto background = make_speech_analyzer(o);
  ASSERT_TRUE(background) << background.error().message;
  const auto later = run_ticks(**background, stream, 1000);
  ASSERT_EQ(later.size(), 1u) << "reported once the decode finished (10 s at most)";
  EXPECT_EQ(later[0].speech.text, at_tick[0].speech.text);
  EXPECT_EQ(later[0].speech.confidence, at_tick[0].speech.confidence);
  EXPECT_EQ(later[0].speech.start, at_tick[0].speech.start);
  EXPECT_EQ(later[0].speech.end, at_tick[0].speech.end);
  EXPECT_EQ(later[0].speech.sensor, "mic");
  EXPECT_GT(later[0].tick, at_tick[0].tick) << "the closing tick did not wait for the decode";
}

// Reset and destruction with an utterance still being decoded: nothing is reported for the old
// stream, nothing hangs.
TEST(SpeechAnalyzer, BackgroundDecodingStopsCleanly) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o = goforward_options();
  o.background_decode = true;
  const std::vector<float> stream = goforward_stream(16000);  // long enough to close it
  {
    auto a = make_speech_analyzer(o);
    ASSERT_TRUE(a);
    EXPECT_TRUE(run_ticks(**a, stream).empty()) << "the decode outlasts the unpaced ticks";
    (*a)->reset();
    EXPECT_TRUE(run_ticks(**a, std::vector<float>(16000, 0.f), 50).empty())
        << "the old stream's utterance is not reported after a reset";
    EXPECT_TRUE(run_ticks(**a, stream).empty());
  }  // destroyed while decoding
}

TEST(SpeechAnalyzer, QuietStreamWritesNothing) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  auto a = make_speech_analyzer(goforward_options());
  ASSERT_TRUE(a);
  EXPECT_TRUE(run(**a, std::vector<float>(48000, 0.f)).empty());
}

// Kinect v1 array; speech arrives as a plane wave from `azimuth_deg` (linear-interpolated
// delays), and microphone 0 is broken: it hears loud noise only. A tick of sound direction is
// written before each speech tick when `direction` is set, as the sound-direction analyser does.
std::vector<RecognizedSpeech> run_array(Analyzer& a, const std::vector<float>& mono,
                                        double azimuth_deg, bool direction, float broken_rms) {
  const std::vector<cv::Vec3d> mics = {
      {0.113, 0, 0}, {-0.036, 0, 0}, {-0.076, 0, 0}, {-0.113, 0, 0}};
  const double az = azimuth_deg * CV_PI / 180;
  const cv::Vec3d dir(std::sin(az), 0, std::cos(az));
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 3e-4f), broken(0.f, broken_rms);
  Blackboard bb;
  std::vector<RecognizedSpeech> heard;
  const int64_t chunk = 640, n = static_cast<int64_t>(mono.size());
  auto sample = [&](double t) {  // mono at fractional index t
    const int64_t i = static_cast<int64_t>(std::floor(t));
    if (i < 0 || i + 1 >= n) return 0.f;
    const float f = static_cast<float>(t - static_cast<double>(i));
    return (1 - f) * mono[static_cast<size_t>(i)] + f * mono[static_cast<size_t>(i + 1)];
  };
  for (int64_t k = 0; k * chunk < n; ++k) {
    AudioChunk c;
    c.sample_rate = 16000;
    c.channels = 4;
    for (int64_t i = k * chunk; i < std::min((k + 1) * chunk, n); ++i)
      for (size_t m = 0; m < 4; ++m) {
        const double delay = -mics[m].dot(dir) / 343.0 * 16000;  // centroid ~ 0
        c.samples.push_back(m == 0 ? broken(rng)
                                   : sample(static_cast<double>(i) - delay) + noise(rng));
      }
    MultiFrame mf;
    mf.stamp = Timestamp::from_ns(k * 40'000'000LL);
    mf.chunks["mic"].push_back(make_frame("mic", mf.stamp, static_cast<uint64_t>(k), c));
    if (direction) {
      BlackboardWriter d("sound_direction");
      SoundDirection sd;
      sd.azimuth_deg = azimuth_deg;
      sd.direction_array = dir;
      sd.sensor = "mic";
      d.set(keys::kSoundDirection, sd, mf.stamp, 0.9f);
      bb.commit(d, mf.stamp);
    }
    BlackboardWriter w("speech");
    EXPECT_TRUE(a.process(mf, bb.snapshot(), w));
    bb.commit(w, mf.stamp);
    auto e = bb.snapshot().get(keys::kRecognizedSpeech);
    if (e && e->present() && e->stamp == mf.stamp) heard.push_back(*e->value);
  }
  return heard;
}

TEST(SpeechAnalyzer, SteersTheArrayTowardTheSoundDirection) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o = goforward_options();
  o.mic_positions_m = {{0.113, 0, 0}, {-0.036, 0, 0}, {-0.076, 0, 0}, {-0.113, 0, 0}};
  auto a = make_speech_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  const auto reads = (*a)->contract().reads;
  EXPECT_NE(std::find(reads.begin(), reads.end(), keys::kSoundDirection.name), reads.end());
  const std::vector<float> stream = goforward_stream(32000);
  const auto speech = read_raw_float(kPocketsphinxData / "goforward.raw");
  double rms = 0;
  for (float v : speech) rms += v * v;
  rms = std::sqrt(rms / static_cast<double>(speech.size()));
  // Broken microphone 0: white noise 10 dB under the speech. Channel 0 alone is rejected (the
  // decoder fails from 14 dB down to 6 dB), the beam toward the talker recognises it.
  const float broken = static_cast<float>(0.3 * rms);
  const auto steered = run_array(**a, stream, 40.0, true, broken);
  ASSERT_EQ(steered.size(), 1u);
  EXPECT_EQ(steered[0].text, "go forward ten meters");
  (*a)->reset();
  EXPECT_TRUE(run_array(**a, stream, 40.0, false, broken).empty())
      << "without a direction the analyser decodes channel 0";
}

TEST(SpeechAnalyzer, ArrayWithTheWrongChannelCountIsAnError) {
  if (!has_goforward()) GTEST_SKIP() << "needs pocketsphinx-en-us and pocketsphinx-testdata";
  SpeechAnalyzerOptions o = goforward_options();
  o.mic_positions_m = {{0.1, 0, 0}, {0, 0, 0}, {-0.1, 0, 0}};
  auto a = make_speech_analyzer(o);
  ASSERT_TRUE(a);
  AudioChunk c;
  c.channels = 2;
  c.samples.assign(1280, 0.f);
  MultiFrame mf;
  mf.stamp = Timestamp::from_ns(0);
  mf.chunks["mic"].push_back(make_frame("mic", mf.stamp, 0, c));
  Blackboard bb;
  BlackboardWriter w("speech");
  auto s = (*a)->process(mf, bb.snapshot(), w);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("3 microphones"), std::string::npos) << s.error().message;
}

TEST(SpeechAnalyzer, OptionsAreChecked) {
  SpeechAnalyzerOptions o;
  EXPECT_FALSE(make_speech_analyzer(o)) << "no grammar";
  o.grammar = "/nonexistent.gram";
  auto a = make_speech_analyzer(o);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("/nonexistent.gram"), std::string::npos);
  o.fade_in_s = -0.1;
  auto fade = o.check();
  ASSERT_FALSE(fade);
  EXPECT_NE(fade.error().message.find("fade_in_s"), std::string::npos);
  EXPECT_EQ(SpeechAnalyzerOptions{}.recognizer.garbage_phone_weight, 0.5);
}

}  // namespace
}  // namespace dreamsense::speech
