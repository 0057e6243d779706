// The voice id analyser through a MultiFrame harness: audio chunks (and, for the direction rule,
// sound directions on the blackboard) in, one SpeakerIdentity per utterance out.

#include "dreamsense/voice_id/voice_id_analyzer.hpp"

#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/perception/sound_direction.hpp"
#include "dreamsense/perception/voice_id.hpp"
#include "dreamsense/voice_id/audio_files.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <optional>
#include <random>

#include "synthetic_voice.hpp"

namespace dreamsense::voice_id {
namespace {

using testing::synth_utterance;
using testing::SyntheticSpeaker;

const SyntheticSpeaker kChild{260, 1.25}, kTherapist{120, 1.0};
constexpr int kAnalyzerRate = 16000;

std::shared_ptr<const VoiceModel> shared_model() {
  static const auto m = [] {
    std::vector<LabelledAudio> enrol;
    for (uint32_t i = 0; i < 4; ++i) {
      enrol.push_back(
          {"child", synth_utterance(kChild, 1.5, kAnalyzerRate, 10 + i), kAnalyzerRate, "c"});
      enrol.push_back({"therapist", synth_utterance(kTherapist, 1.5, kAnalyzerRate, 20 + i),
                       kAnalyzerRate, "t"});
    }
    VoiceTrainOptions o;
    o.ubm.components = 16;
    o.ubm.min_frames_per_component = 20;
    o.threshold = -100;  // closed set: the synthetic voices are too regular for the open set
    auto r = train_voice_model(enrol, {}, o);
    EXPECT_TRUE(r) << r.error().message;
    return std::make_shared<const VoiceModel>(r ? *r : VoiceModel{});
  }();
  return m;
}

// Azimuth (deg) and confidence of the sound direction at a time, or none (silence).
using DirectionAt = std::function<std::optional<std::pair<double, double>>(double seconds)>;

// Feeds `mono` as 2-channel 40 ms chunks, one per 25 Hz tick, with faint noise; a fake sound
// direction analyser runs first when `direction` is given. Returns every identity written.
// World position of the child's head seen by the cameras at a time, or none.
using HeadAt = std::function<std::optional<cv::Vec3d>(double seconds)>;

std::vector<SpeakerIdentity> run(Analyzer& a, const std::vector<float>& mono,
                                 const DirectionAt& direction = {},
                                 const std::vector<float>* reference = nullptr,
                                 const HeadAt& child_head = {}) {
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.f, 3e-4f);
  Blackboard bb;
  std::vector<SpeakerIdentity> out;
  const int64_t chunk = 640;
  for (int64_t k = 0; k * chunk < static_cast<int64_t>(mono.size()); ++k) {
    AudioChunk c;
    c.sample_rate = kAnalyzerRate;
    c.channels = 2;
    for (int64_t i = k * chunk; i < std::min<int64_t>((k + 1) * chunk, mono.size()); ++i) {
      c.samples.push_back(mono[static_cast<size_t>(i)] + noise(rng));
      c.samples.push_back(mono[static_cast<size_t>(i)] + noise(rng));
    }
    MultiFrame mf;
    mf.stamp = Timestamp::from_ns(k * 40'000'000LL);
    mf.chunks["mic"].push_back(make_frame("mic", mf.stamp, static_cast<uint64_t>(k), c));
    if (reference != nullptr) {  // what the robot's loudspeaker played (mono)
      AudioChunk r;
      r.sample_rate = kAnalyzerRate;
      r.channels = 1;
      for (int64_t i = k * chunk; i < std::min<int64_t>((k + 1) * chunk, reference->size()); ++i)
        r.samples.push_back((*reference)[static_cast<size_t>(i)]);
      mf.chunks["robot"].push_back(make_frame("robot", mf.stamp, static_cast<uint64_t>(k), r));
    }
    if (direction) {
      BlackboardWriter w("sound_direction");
      if (auto d = direction(mf.stamp.seconds())) {
        SoundDirection s;
        s.azimuth_deg = d->first;
        w.set(keys::kSoundDirection, s, mf.stamp, static_cast<float>(d->second));
      } else {
        w.set_absent(keys::kSoundDirection, mf.stamp);
      }
      bb.commit(w, mf.stamp);
    }
    if (child_head) {  // a fake head pose analyser (it runs after voice_id in the pipeline)
      BlackboardWriter w("head_pose");
      if (auto p = child_head(mf.stamp.seconds())) {
        HeadPose h;
        h.frame_stamp = mf.stamp;
        h.position_world_m = *p;
        w.set(keys::kHeadPose, h, mf.stamp, 1.f);
      } else {
        w.set_absent(keys::kHeadPose, mf.stamp);
      }
      bb.commit(w, mf.stamp);
    }
    BlackboardWriter w("voice_id");
    EXPECT_TRUE(a.process(mf, bb.snapshot(), w));
    bb.commit(w, mf.stamp);
    auto e = bb.snapshot().get(keys::kSpeakerIdentity);
    if (e && e->present() && e->stamp == mf.stamp) out.push_back(*e->value);
  }
  return out;
}

void append(std::vector<float>& s, const std::vector<float>& x) {
  s.insert(s.end(), x.begin(), x.end());
}
std::vector<float> quiet(double seconds) {
  return std::vector<float>(size_t(seconds * kAnalyzerRate), 0.f);
}

// Privacy: enrolment folders named after people are reported as speaker_<k> (enrolment order)
// unless names are included; role words stay; speaker_id never changes with include_names.
TEST(VoiceIdAnalyzer, PeoplesNamesOnlyWithIncludeNames) {
  VoiceModel named = *shared_model();
  ASSERT_EQ(named.speakers.size(), 2u);
  for (auto& sp : named.speakers) sp.name = sp.id = sp.id == "child" ? "Zoe Example" : "therapist";
  EXPECT_EQ(public_speaker_id(named, "Zoe Example"), "speaker_1");
  EXPECT_EQ(public_speaker_id(named, "therapist"), "therapist");
  EXPECT_EQ(public_speaker_id(named, "unknown"), "unknown");
  EXPECT_EQ(public_speaker_id(named, "not enrolled"), "unknown");
  std::vector<float> s = quiet(0.5);
  append(s, synth_utterance(kChild, 1.2, kAnalyzerRate, 501, 0, 0));
  append(s, quiet(1.0));
  append(s, synth_utterance(kTherapist, 1.2, kAnalyzerRate, 502, 0, 0));
  append(s, quiet(1.0));
  for (bool include : {false, true}) {
    VoiceIdAnalyzerOptions o;
    o.audio_sensor = "mic";
    o.model = std::make_shared<const VoiceModel>(named);
    o.include_names = include;
    auto a = make_voice_id_analyzer(o);
    ASSERT_TRUE(a) << a.error().message;
    const auto ids = run(**a, s);
    ASSERT_EQ(ids.size(), 2u);
    EXPECT_EQ(ids[0].speaker_id, "speaker_1");
    EXPECT_EQ(ids[0].name, include ? "Zoe Example" : "speaker_1");
    EXPECT_EQ(ids[1].speaker_id, "therapist");
    EXPECT_EQ(ids[1].name, "therapist");
  }
}

TEST(VoiceIdAnalyzer, GmmUbmNamesEachUtterance) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = shared_model();
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  std::vector<float> s = quiet(0.5);
  append(s, synth_utterance(kChild, 1.2, kAnalyzerRate, 501, 0, 0));  // 0.5 - 1.7 s
  append(s, quiet(1.0));
  append(s, synth_utterance(kTherapist, 1.2, kAnalyzerRate, 502, 0, 0));  // 2.7 - 3.9 s
  append(s, quiet(1.0));
  append(s, synth_utterance(kChild, 0.8, kAnalyzerRate, 503, 0, 0));  // 4.9 - 5.7 s
  append(s, quiet(1.0));
  const auto ids = run(**a, s);
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_EQ(ids[0].speaker_id, "child");
  EXPECT_EQ(ids[1].speaker_id, "therapist");
  EXPECT_EQ(ids[2].speaker_id, "child");
  EXPECT_EQ(ids[0].method, "gmm_ubm");
  EXPECT_EQ(ids[0].sensor, "mic");
  EXPECT_EQ(ids[0].name, "child");
  EXPECT_GT(ids[0].score, 0.5);
  EXPECT_NEAR(ids[1].start.seconds(), 2.7, 0.1);
  EXPECT_NEAR(ids[1].end.seconds(), 3.9, 0.1);
}

// Issue 16 item 2: decision over voice tracks (default) reads the sound direction of the
// previous ticks; the utterance decision does not. With the directions, the child's two
// utterances in front share a track and the therapist's at the side has her own.
TEST(VoiceIdAnalyzer, TracksReadTheSoundDirectionAndNameEachPlace) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = shared_model();
  o.decision = VoiceDecision::kUtterance;
  auto u = make_voice_id_analyzer(o);
  ASSERT_TRUE(u);
  EXPECT_TRUE((*u)->contract().reads_previous.empty());
  o.decision = VoiceDecision::kTracks;
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ((*a)->contract().reads_previous, std::vector<std::string>{keys::kSoundDirection.name});
  EXPECT_EQ(*parse_voice_decision("utterance"), VoiceDecision::kUtterance);
  EXPECT_FALSE(parse_voice_decision("best"));
  std::vector<float> s = quiet(0.5);
  append(s, synth_utterance(kChild, 1.2, kAnalyzerRate, 801, 0, 0));  // 0.5 - 1.7 s, front
  append(s, quiet(1.0));
  append(s, synth_utterance(kTherapist, 1.2, kAnalyzerRate, 802, 0, 0));  // 2.7 - 3.9 s, side
  append(s, quiet(1.0));
  append(s, synth_utterance(kChild, 0.6, kAnalyzerRate, 803, 0, 0));  // 4.9 - 5.5 s, front
  append(s, quiet(1.0));
  const auto ids = run(**a, s, [](double t) -> std::optional<std::pair<double, double>> {
    if (t >= 0.5 && t < 1.7) return std::pair{1.0, 0.9};
    if (t >= 2.7 && t < 3.9) return std::pair{40.0, 0.9};
    if (t >= 4.9 && t < 5.5) return std::pair{-2.0, 0.9};
    return std::nullopt;
  });
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_EQ(ids[0].speaker_id, "child");
  EXPECT_EQ(ids[1].speaker_id, "therapist");
  EXPECT_EQ(ids[2].speaker_id, "child");
  EXPECT_EQ(ids[2].method, "gmm_ubm");
}

// Issue 16: the child seen by the cameras. The therapist's synthetic voice comes from where the
// child's head is seen: named the child when the array's extrinsics are known (here the array
// is turned 30 deg, so the child straight ahead of the world's z axis is at -30 deg in the
// array frame, where the sound comes from); without extrinsics, or from 50 deg away, the voice
// decides.
TEST(VoiceIdAnalyzer, TheChildSeenWhereTheSoundComesFromIsTheSpeaker) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = shared_model();
  const double turn = 30 * M_PI / 180;
  o.array_from_world_R =
      cv::Matx33d(std::cos(turn), 0, -std::sin(turn), 0, 1, 0, std::sin(turn), 0, std::cos(turn));
  auto with = make_voice_id_analyzer(o);
  ASSERT_TRUE(with) << with.error().message;
  const auto& reads = (*with)->contract().reads_previous;
  EXPECT_NE(std::find(reads.begin(), reads.end(), keys::kHeadPose.name), reads.end());
  VoiceIdAnalyzerOptions no_extrinsics = o;
  no_extrinsics.array_from_world_R.reset();
  auto without = make_voice_id_analyzer(no_extrinsics);
  ASSERT_TRUE(without);
  std::vector<float> s = quiet(0.5);
  append(s, synth_utterance(kTherapist, 1.2, kAnalyzerRate, 811, 0, 0));  // 0.5 - 1.7 s
  append(s, quiet(1.0));
  const auto run_with_sound_at = [&](Analyzer& a, double azimuth) {
    return run(
        a, s,
        [azimuth](double t) -> std::optional<std::pair<double, double>> {
          if (t >= 0.5 && t < 1.7) return std::pair{azimuth, 0.9};
          return std::nullopt;
        },
        nullptr, [](double) { return std::optional<cv::Vec3d>(cv::Vec3d(0, 0, 1.2)); });
  };
  const auto seen = run_with_sound_at(**with, -31.0);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].speaker_id, "child");
  const auto blind = run_with_sound_at(**without, -31.0);
  ASSERT_EQ(blind.size(), 1u);
  EXPECT_EQ(blind[0].speaker_id, "therapist");
  (*with)->reset();
  const auto away = run_with_sound_at(**with, 20.0);
  ASSERT_EQ(away.size(), 1u);
  EXPECT_EQ(away[0].speaker_id, "therapist");
}

// Issue 16: the robot speaks (here with the therapist's synthetic voice) between two child
// utterances. With its reference stream it gets no speaker; without it (negative case) it is
// named, as before.
TEST(VoiceIdAnalyzer, RobotVoiceIsGatedByItsReference) {
  std::vector<float> s = quiet(0.5), ref = quiet(0.5);
  append(s, synth_utterance(kChild, 1.2, kAnalyzerRate, 601, 0, 0));  // 0.5 - 1.7 s
  append(ref, quiet(1.2));
  append(s, quiet(1.0));
  append(ref, quiet(1.0));
  const auto robot = synth_utterance(kTherapist, 1.2, kAnalyzerRate, 602, 0, 0);  // 2.7 - 3.9 s
  append(s, robot);
  append(ref, robot);
  append(s, quiet(1.0));
  append(ref, quiet(1.0));
  append(s, synth_utterance(kChild, 0.9, kAnalyzerRate, 603, 0, 0));  // 4.9 - 5.8 s
  append(s, quiet(1.0));
  append(ref, quiet(1.9));
  for (const bool gated : {true, false}) {
    VoiceIdAnalyzerOptions o;
    o.audio_sensor = "mic";
    o.model = shared_model();
    if (gated) o.reference_sensor = "robot";
    auto a = make_voice_id_analyzer(o);
    ASSERT_TRUE(a) << a.error().message;
    if (gated) {
      const auto& in = (*a)->contract().optional_inputs;
      EXPECT_NE(std::find(in.begin(), in.end(), "robot"), in.end());
    }
    const auto ids = run(**a, s, {}, &ref);
    if (gated) {
      ASSERT_EQ(ids.size(), 2u);
      EXPECT_EQ(ids[0].speaker_id, "child");
      EXPECT_EQ(ids[1].speaker_id, "child");
    } else {
      ASSERT_EQ(ids.size(), 3u);
      EXPECT_EQ(ids[1].speaker_id, "therapist");
    }
  }
}

// A model trained with the noise suppressor says so in its file; the analyser then filters the
// stream the same way (16 ms late, compensated: the utterances keep their times), and the
// one-shot path (identify) names a noisy therapist clip. Known issue (README.md): on these
// synthetic voices the streamed path names the therapist's utterance "child" although the
// one-shot path on the same voice gets it right; not resolved, so the option stays off.
TEST(VoiceIdAnalyzer, NoiseSuppressedModelRoundTripsAndKeepsTimes) {
  std::vector<LabelledAudio> enrol;
  for (uint32_t i = 0; i < 4; ++i) {
    enrol.push_back(
        {"child", synth_utterance(kChild, 1.5, kAnalyzerRate, 10 + i), kAnalyzerRate, "c"});
    enrol.push_back(
        {"therapist", synth_utterance(kTherapist, 1.5, kAnalyzerRate, 20 + i), kAnalyzerRate, "t"});
  }
  VoiceTrainOptions to;
  to.ubm.components = 16;
  to.ubm.min_frames_per_component = 20;
  to.threshold = -100;
  to.features.noise_suppression = true;
  auto m = train_voice_model(enrol, {}, to);
  ASSERT_TRUE(m) << m.error().message;
  const auto file = std::filesystem::temp_directory_path() / "ds_voice_ns_model.yaml";
  ASSERT_TRUE(m->save(file));
  auto back = VoiceModel::load(file);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(back->features.noise_suppression);
  std::filesystem::remove(file);
  auto t = synth_utterance(kTherapist, 1.2, kAnalyzerRate, 702, 0.3, 0.3);
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.f, 3e-4f);
  for (auto& v : t) v += noise(rng);
  auto one = identify(*back, t, kAnalyzerRate);
  ASSERT_TRUE(one);
  EXPECT_EQ(one->best_id, "therapist");
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = std::make_shared<const VoiceModel>(*back);
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  std::vector<float> s = quiet(0.5);
  append(s, synth_utterance(kChild, 1.2, kAnalyzerRate, 701, 0, 0));  // 0.5 - 1.7 s
  append(s, quiet(1.0));
  append(s, synth_utterance(kTherapist, 1.2, kAnalyzerRate, 702, 0, 0));  // 2.7 - 3.9 s
  append(s, quiet(1.0));
  const auto ids = run(**a, s);
  ASSERT_EQ(ids.size(), 2u);
  EXPECT_EQ(ids[0].speaker_id, "child");
  EXPECT_NEAR(ids[0].start.seconds(), 0.5, 0.05);
  EXPECT_NEAR(ids[0].end.seconds(), 1.7, 0.05);
  EXPECT_NEAR(ids[1].start.seconds(), 2.7, 0.05);
  EXPECT_NEAR(ids[1].end.seconds(), 3.9, 0.05);
}

// Real speech (pocketsphinx-testdata): the cards talker enrolled as the child, the LibriVox
// reader as the therapist; a recording of a third talker in the stream is "unknown".
TEST(VoiceIdAnalyzer, RealStrangerIsUnknown) {
  namespace fs = std::filesystem;
  const fs::path d = "/usr/share/pocketsphinx/test/data";
  const std::string lv = "librivox/sense_and_sensibility_01_austen_64kb-0";
  if (!fs::exists(d / "goforward.raw") || !fs::exists(d / (lv + "930.wav")))
    GTEST_SKIP() << "needs pocketsphinx-testdata";
  std::vector<LabelledAudio> enrol;
  for (const char* f : {"cards/001.wav", "cards/002.wav", "cards/003.wav"})
    enrol.push_back(*read_audio_file(d / f, "child"));
  for (const char* f : {"870.wav", "880.wav", "890.wav"})
    enrol.push_back(*read_audio_file(d / (lv + f), "therapist"));
  auto m = train_voice_model(enrol, {}, VoiceTrainOptions{});
  ASSERT_TRUE(m) << m.error().message;
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = std::make_shared<const VoiceModel>(*m);
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a);
  std::vector<float> s = quiet(0.5);
  for (const std::string& f :
       {std::string("cards/005.wav"), lv + "930.wav", std::string("goforward.raw")}) {
    append(s, read_audio_file(d / f)->samples);
    append(s, quiet(1.0));
  }
  const auto ids = run(**a, s);
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_EQ(ids[0].speaker_id, "child");
  EXPECT_EQ(ids[1].speaker_id, "therapist");
  EXPECT_EQ(ids[2].speaker_id, "unknown");
}

TEST(VoiceIdAnalyzer, SilenceWritesNothing) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = shared_model();
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a);
  EXPECT_TRUE(run(**a, quiet(4.0)).empty());
}

TEST(VoiceIdAnalyzer, DirectionRuleFollowsDream) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.method = VoiceIdMethod::kDirectionRule;  // no model needed
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ((*a)->contract().reads, std::vector<std::string>{keys::kSoundDirection.name});
  std::vector<float> s = quiet(0.5);
  append(s,
         synth_utterance(kTherapist, 1.0, kAnalyzerRate, 1, 0, 0));  // 0.5 - 1.5 s, from the side
  append(s, quiet(1.0));
  append(s,
         synth_utterance(kTherapist, 1.0, kAnalyzerRate, 2, 0, 0));  // 2.5 - 3.5 s, from the front
  append(s, quiet(1.0));
  append(s,
         synth_utterance(kTherapist, 1.0, kAnalyzerRate, 3, 0, 0));  // 4.5 - 5.5 s, low confidence
  append(s, quiet(1.0));
  const auto ids = run(**a, s, [](double t) -> std::optional<std::pair<double, double>> {
    if (t >= 0.5 && t < 1.5) return std::pair{-42.0, 0.9};
    if (t >= 2.5 && t < 3.5) return std::pair{6.0, 0.8};
    if (t >= 4.5 && t < 5.5) return std::pair{6.0, 0.3};
    return std::nullopt;
  });
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_EQ(ids[0].speaker_id, "therapist");
  EXPECT_EQ(ids[1].speaker_id, "child");
  EXPECT_EQ(ids[2].speaker_id, "unknown") << "confidence 0.3 <= 0.5 decides nothing";
  EXPECT_EQ(ids[0].method, "direction_rule");
  EXPECT_GT(ids[0].score, 0.8);
}

TEST(VoiceIdAnalyzer, GmmUbmNeedsAModelAndSaysWhichFileIsMissing) {
  VoiceIdAnalyzerOptions o;
  auto a = make_voice_id_analyzer(o);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("needs a voice model"), std::string::npos);
  o.model_file = "/nonexistent/voices.yaml";
  auto b = make_voice_id_analyzer(o);
  ASSERT_FALSE(b);
  EXPECT_NE(b.error().message.find("/nonexistent/voices.yaml"), std::string::npos);
  EXPECT_FALSE(parse_voice_id_method("loudest"));
  EXPECT_EQ(*parse_voice_id_method("direction_rule"), VoiceIdMethod::kDirectionRule);
}

TEST(VoiceIdAnalyzer, AudioBelowTheModelsBandIsAnError) {
  VoiceIdAnalyzerOptions o;
  o.audio_sensor = "mic";
  o.model = shared_model();
  auto a = make_voice_id_analyzer(o);
  ASSERT_TRUE(a);
  AudioChunk c;
  c.sample_rate = 6000;
  c.samples.assign(600, 0.f);
  MultiFrame mf;
  mf.stamp = Timestamp::from_ns(0);
  mf.chunks["mic"].push_back(make_frame("mic", mf.stamp, 0, c));
  BlackboardWriter w("voice_id");
  auto s = (*a)->process(mf, BlackboardView{}, w);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("6000 Hz"), std::string::npos);
}

}  // namespace
}  // namespace dreamsense::voice_id
