// Silence check (detect_speech), the libsoxr resampler, and the recogniser with PocketSphinx's
// TIDIGITS model (another phone set for the garbage loop, an 8 kHz front end).
#include "dreamsense/audio/speech_presence.hpp"
#include "dreamsense/eval/speech_eval.hpp"
#include "dreamsense/speech/recognizer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;
constexpr int kRate = 16000;

std::vector<int16_t> to_pcm(const std::vector<double>& x) {
  std::vector<int16_t> s(x.size());
  for (size_t i = 0; i < x.size(); ++i)
    s[i] = static_cast<int16_t>(std::clamp(std::lround(x[i] * 32767), -32768L, 32767L));
  return s;
}

// 1 s: quiet noise with a 0.3 s harmonic "vowel" (f0 `f0`, 10 harmonics) in the middle.
std::vector<int16_t> vowel_clip(double f0, double level, double noise, unsigned seed) {
  std::mt19937 g(seed);
  std::normal_distribution<double> n(0, noise);
  std::vector<double> x(kRate);
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = n(g);
    const double t = static_cast<double>(i) / kRate;
    if (t >= 0.35 && t < 0.65) {
      const double env = std::sin(M_PI * (t - 0.35) / 0.3);
      for (int k = 1; k <= 10; ++k) x[i] += level * env * std::sin(2 * M_PI * f0 * k * t) / k;
    }
  }
  return to_pcm(x);
}

std::vector<int16_t> noise_clip(const std::string& kind, double rms, unsigned seed) {
  std::mt19937 g(seed);
  std::normal_distribution<double> n(0, 1);
  std::vector<double> x(kRate);
  double brown = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double w = n(g), t = static_cast<double>(i) / kRate;
    if (kind == "white") x[i] = w;
    if (kind == "brown") x[i] = brown = 0.995 * brown + w;
    if (kind == "hum") {
      x[i] = 0.05 * w;
      for (int k = 1; k <= 5; ++k) x[i] += std::sin(2 * M_PI * 50 * k * t) / k;
    }
  }
  double e = 0;
  for (double v : x) e += v * v;
  const double scale = rms / std::sqrt(e / static_cast<double>(x.size()));
  for (auto& v : x) v *= scale;
  return to_pcm(x);
}

TEST(DetectSpeech, VoicedSoundIsSpeechNoiseIsNot) {
  for (double f0 : {60.0, 110.0, 220.0, 350.0}) {
    const auto clip = vowel_clip(f0, 0.1, 0.003, 1);
    const auto p = audio::detect_speech(clip, kRate);
    EXPECT_TRUE(p.speech) << "f0 " << f0 << " voiced " << p.voiced_s;
    EXPECT_NEAR(p.start_s, 0.35, 0.08);
    EXPECT_NEAR(p.end_s, 0.65, 0.08);
  }
  // Quiet but clearly above its floor: still speech.
  EXPECT_TRUE(audio::detect_speech(vowel_clip(120, 0.003, 0.0001, 2), kRate).speech);
  for (const char* kind : {"white", "brown", "hum"})
    for (double rms : {0.0003, 0.01, 0.2}) {
      const auto p = audio::detect_speech(noise_clip(kind, rms, 3), kRate);
      EXPECT_FALSE(p.speech) << kind << " " << rms << " voiced " << p.voiced_s;
    }
  const std::vector<int16_t> zeros(kRate, 0);
  EXPECT_FALSE(audio::detect_speech(zeros, kRate).speech);
  EXPECT_FALSE(audio::detect_speech({}, kRate).speech);
  audio::SpeechPresenceOptions bad;
  bad.f0_max_hz = 10;
  EXPECT_FALSE(bad.check());
}

TEST(Resample, SoxrAndSincPreserveATone) {
  std::vector<int16_t> tone(8000);
  for (size_t i = 0; i < tone.size(); ++i)
    tone[i] = static_cast<int16_t>(10000 * std::sin(2 * M_PI * 440 * i / 8000.0));
  for (Resampler m : {Resampler::kSoxr, Resampler::kSinc}) {
    const auto up = resample(tone, 8000, 16000, m);
    ASSERT_EQ(up.size(), 16000u) << to_string(m);
    double err = 0;
    for (size_t i = 400; i < up.size() - 400; ++i)
      err = std::max(err, std::abs(up[i] - 10000 * std::sin(2 * M_PI * 440 * i / 16000.0)));
    EXPECT_LT(err, 60) << to_string(m) << ": aligned, no delay";
  }
  EXPECT_EQ(*parse_resampler("soxr"), Resampler::kSoxr);
  EXPECT_EQ(*parse_resampler("sinc"), Resampler::kSinc);
  EXPECT_FALSE(parse_resampler("linear"));
}

TEST(Recognizer, TidigitsModelWithItsOwnPhoneSet) {
  const fs::path raw = "/usr/share/pocketsphinx/test/data/tidigits/dhd.2934z.raw";
  if (!fs::exists(kTidigitsModel / "mdef") || !fs::exists(raw))
    GTEST_SKIP() << "needs pocketsphinx-testdata";
  std::ifstream in(raw, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
  std::vector<int16_t> audio(bytes.size() / 2);
  std::memcpy(audio.data(), bytes.data(), audio.size() * 2);
  RecognizerOptions o;
  o.model_dir = kTidigitsModel;
  o.dictionary = kTidigitsDictionary;
  o.model_rate_hz = 8000;  // 16 kHz input is resampled to the 8 kHz front end
  o.garbage_phone_weight = 0.01;
  auto g = Grammar::from_jsgf(
      "#JSGF V1.0;\ngrammar d;\npublic <s> = <d> <d> <d> <d> <d>;\n"
      "<d> = zero | oh | one | two | three | four | five | six | seven | eight | nine;\n");
  ASSERT_TRUE(g);
  auto rec = Recognizer::create(o, *g);
  ASSERT_TRUE(rec) << rec.error().to_string();
  auto d = (*rec)->decode(audio, 16000);
  ASSERT_TRUE(d) << d.error().to_string();
  EXPECT_TRUE(d->accepted);
  EXPECT_EQ(d->grammar_hypothesis, "two nine three four zero");
  // A word with an alternative pronunciation comes back without the "(2)" marker.
  for (const auto& w : split_words(d->grammar_hypothesis))
    EXPECT_EQ(w.find('('), std::string::npos) << w;
}

}  // namespace
}  // namespace dreamsense::speech
