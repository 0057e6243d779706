// GMM-UBM speaker models on synthetic speakers: enrolment, identification, open set, the model
// file (round trip, missing, corrupt, other version).

#include "dreamsense/voice_id/voice_model.hpp"

#include "dreamsense/voice_id/audio_files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "synthetic_voice.hpp"

namespace dreamsense::voice_id {
namespace {

namespace fs = std::filesystem;
using testing::synth_utterance;
using testing::SyntheticSpeaker;

const SyntheticSpeaker kLow{110, 1.0}, kHigh{230, 1.2}, kOther{160, 1.1};
constexpr int kRate = 16000;

std::vector<LabelledAudio> enrolment() {
  std::vector<LabelledAudio> out;
  for (uint32_t i = 0; i < 4; ++i) {
    out.push_back({"low", synth_utterance(kLow, 1.5, kRate, 100 + i), kRate, "low"});
    out.push_back({"high", synth_utterance(kHigh, 1.5, kRate, 200 + i), kRate, "high"});
  }
  return out;
}

const VoiceModel& model() {
  static const VoiceModel m = [] {
    VoiceTrainOptions o;
    o.ubm.components = 16;
    o.ubm.min_frames_per_component = 20;
    auto r = train_voice_model(enrolment(), {}, o);
    EXPECT_TRUE(r) << r.error().message;
    return r ? *r : VoiceModel{};
  }();
  return m;
}

fs::path temp_file(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / "dreamsense_voice_model_test";
  fs::create_directories(d);
  return d / name;
}

TEST(VoiceModel, EnrolsSpeakersInOrderAndIdentifiesNewUtterances) {
  const VoiceModel& m = model();
  ASSERT_EQ(m.speakers.size(), 2u);
  EXPECT_EQ(m.speakers[0].id, "low");
  EXPECT_EQ(m.speakers[1].id, "high");
  EXPECT_EQ(m.speakers[0].utterances, 4);
  EXPECT_GT(m.speakers[0].frames, 400);
  EXPECT_EQ(m.ubm.components(), 16);
  EXPECT_EQ(m.cmn_prior.cols, m.features.dimension());
  // Closed set: the best-scoring speaker (the synthetic voices are too regular for the open-set
  // threshold; the real-speech test below covers it).
  for (uint32_t seed = 0; seed < 4; ++seed) {
    auto a = identify(m, synth_utterance(kLow, 1.0, kRate, 900 + seed), kRate);
    ASSERT_TRUE(a);
    EXPECT_EQ(a->best_id, "low") << "llr " << a->llr;
    auto b = identify(m, synth_utterance(kHigh, 1.0, kRate, 950 + seed), kRate);
    ASSERT_TRUE(b);
    EXPECT_EQ(b->best_id, "high") << "llr " << b->llr;
    ASSERT_EQ(b->scores.size(), 2u);
    EXPECT_GE(b->scores[0].llr, b->scores[1].llr);
    EXPECT_GT(b->scores[0].llr - b->scores[1].llr, 0.2) << "a clear margin";
  }
}

TEST(VoiceModel, ThresholdDecidesUnknownAndSilenceIsUnknown) {
  VoiceModel m = model();
  const auto x = synth_utterance(kLow, 1.0, kRate, 901);
  m.threshold = -100;
  auto named = identify(m, x, kRate);
  ASSERT_TRUE(named);
  EXPECT_EQ(named->speaker_id, "low");
  EXPECT_EQ(named->name, "low");
  EXPECT_GT(named->score, 0.99);
  m.threshold = named->llr + 0.5;
  auto rejected = identify(m, x, kRate);
  ASSERT_TRUE(rejected);
  EXPECT_TRUE(rejected->unknown());
  EXPECT_EQ(rejected->best_id, "low") << "the closed-set answer is kept";
  EXPECT_NEAR(rejected->score, 1 - 1 / (1 + std::exp(0.5 / m.score_scale)), 1e-9);
  auto s = identify(m, std::vector<float>(kRate, 0.f), kRate);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->unknown());
  EXPECT_EQ(s->frames, 0);
}

// Real speech (Debian's pocketsphinx-testdata): the cards talker and the LibriVox reader
// enrolled, new recordings of both named, the goforward talker (three recordings) unknown.
TEST(VoiceModel, RealSpeakersAreNamedAndAStrangerIsUnknown) {
  const fs::path d = "/usr/share/pocketsphinx/test/data";
  const std::string lv = "librivox/sense_and_sensibility_01_austen_64kb-0";
  if (!fs::exists(d / "goforward.raw") || !fs::exists(d / (lv + "930.wav")))
    GTEST_SKIP() << "needs pocketsphinx-testdata";
  std::vector<LabelledAudio> enrol;
  for (const char* f : {"cards/001.wav", "cards/002.wav", "cards/003.wav"})
    enrol.push_back(*read_audio_file(d / f, "cards"));
  for (const char* f : {"870.wav", "880.wav", "890.wav"})
    enrol.push_back(*read_audio_file(d / (lv + f), "reader"));
  auto m = train_voice_model(enrol, {}, VoiceTrainOptions{});
  ASSERT_TRUE(m) << m.error().message;
  auto who = [&](const std::string& f) {
    auto a = read_audio_file(d / f);
    EXPECT_TRUE(a) << f;
    auto r = identify(*m, a->samples, a->sample_rate);
    EXPECT_TRUE(r);
    return *r;
  };
  double genuine_min = 1e9, stranger_max = -1e9;
  for (const auto& [f, id] : std::vector<std::pair<std::string, std::string>>{
           {"cards/005.wav", "cards"}, {lv + "930.wav", "reader"}, {lv + "920.wav", "reader"}}) {
    const auto r = who(f);
    EXPECT_EQ(r.speaker_id, id) << f << " llr " << r.llr;
    genuine_min = std::min(genuine_min, r.llr);
  }
  int unknown = 0;
  for (const char* f : {"goforward.raw", "numbers.raw", "something.raw"}) {
    const auto r = who(f);
    unknown += r.unknown();
    stranger_max = std::max(stranger_max, r.llr);
  }
  EXPECT_GE(unknown, 2) << "most of the stranger's recordings are unknown";
  EXPECT_GT(genuine_min, stranger_max) << "every genuine score above every stranger's";
}

TEST(VoiceModel, FileRoundTripGivesTheSameModel) {
  const VoiceModel& m = model();
  const fs::path p = temp_file("round_trip.yaml");
  ASSERT_TRUE(m.save(p));
  EXPECT_FALSE(fs::exists(p.string() + ".part"));
  auto l = VoiceModel::load(p);
  ASSERT_TRUE(l) << l.error().message;
  EXPECT_EQ(l->speakers.size(), 2u);
  EXPECT_EQ(l->speakers[1].id, "high");
  EXPECT_EQ(l->speakers[1].utterances, 4);
  EXPECT_EQ(l->features.filters, m.features.filters);
  EXPECT_DOUBLE_EQ(l->features.high_hz, m.features.high_hz);
  EXPECT_DOUBLE_EQ(l->threshold, m.threshold);
  EXPECT_LT(cv::norm(l->ubm.means(), m.ubm.means(), cv::NORM_INF), 1e-9);
  EXPECT_LT(cv::norm(l->speakers[0].model.means(), m.speakers[0].model.means(), cv::NORM_INF),
            1e-9);
  EXPECT_LT(
      cv::norm(l->speakers[0].model.variances(), m.speakers[0].model.variances(), cv::NORM_INF),
      1e-9);
  EXPECT_LT(cv::norm(l->cmn_prior, m.cmn_prior, cv::NORM_INF), 1e-9);
  EXPECT_EQ(l->map.adapt_variances, m.map.adapt_variances);
  const auto x = synth_utterance(kHigh, 1.0, kRate, 77);
  auto a = identify(m, x, kRate);
  auto b = identify(*l, x, kRate);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->speaker_id, b->speaker_id);
  EXPECT_NEAR(a->llr, b->llr, 1e-9);
}

TEST(VoiceModel, MissingCorruptAndOtherVersionFilesGiveOneLineErrors) {
  auto missing = VoiceModel::load(temp_file("does_not_exist.yaml"));
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("does_not_exist.yaml"), std::string::npos);

  const fs::path garbage = temp_file("garbage.yaml");
  std::ofstream(garbage) << "%YAML:1.0\n---\nformat: [unclosed\n  : : \x01\x02 }}}\n";
  auto g = VoiceModel::load(garbage);
  ASSERT_FALSE(g);
  EXPECT_EQ(g.error().code, ErrorCode::kCorruptData);
  EXPECT_EQ(g.error().message.find('\n'), std::string::npos) << g.error().message;
  EXPECT_NE(g.error().message.find("garbage.yaml"), std::string::npos);

  // A valid file cut in half.
  const fs::path good = temp_file("good.yaml"), cut = temp_file("cut.yaml");
  ASSERT_TRUE(model().save(good));
  std::ifstream in(good);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(cut) << text.substr(0, text.size() / 2);
  auto c = VoiceModel::load(cut);
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().message.find('\n'), std::string::npos) << c.error().message;

  const fs::path other = temp_file("other.yaml");
  std::ofstream(other) << "%YAML:1.0\n---\nformat: something_else\nversion: 1\n";
  auto o = VoiceModel::load(other);
  ASSERT_FALSE(o);
  EXPECT_EQ(o.error().code, ErrorCode::kCorruptData);

  const fs::path v2 = temp_file("v2.yaml");
  std::string t2 = text;
  t2.replace(t2.find("version: 1"), 10, "version: 2");
  std::ofstream(v2) << t2;
  auto v = VoiceModel::load(v2);
  ASSERT_FALSE(v);
  EXPECT_EQ(v.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(v.error().message.find("version 2"), std::string::npos);
}

TEST(VoiceModel, TrainingRejectsBadInput) {
  VoiceTrainOptions o;
  EXPECT_FALSE(train_voice_model({}, {}, o));
  std::vector<LabelledAudio> silent{{"quiet", std::vector<float>(kRate, 0.f), kRate, "quiet.wav"}};
  auto r = train_voice_model(silent, {}, o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no speech"), std::string::npos);
  std::vector<LabelledAudio> bad{{"unknown", synth_utterance(kLow, 1.0, kRate, 1), kRate, "x"}};
  EXPECT_FALSE(train_voice_model(bad, {}, o)) << "'unknown' is reserved";
}

}  // namespace
}  // namespace dreamsense::voice_id
