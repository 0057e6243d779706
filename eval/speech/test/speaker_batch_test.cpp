// Batch speaker adaptation pieces (eval/speaker_batch.hpp): DTW features and distance, the
// neighbour vote; and the fsdd runner's use of them on a tiny synthetic layout.
#include "dreamsense/eval/speaker_batch.hpp"

#include "dreamsense/eval/speech_eval.hpp"

#include <gtest/gtest.h>
#include <sndfile.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <unistd.h>

namespace dreamsense::speech {
namespace {

namespace fs = std::filesystem;

// A gliding harmonic "word": F0 and a formant-like emphasis move from f_start to f_end (Hz).
std::vector<int16_t> glide(double f_start, double f_end, double seconds, int rate = 8000) {
  const auto n = static_cast<size_t>(seconds * rate);
  std::vector<int16_t> s(n);
  double phase = 0;
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / static_cast<double>(n);
    const double f = f_start + (f_end - f_start) * t;
    phase += 2 * std::numbers::pi * f / rate;
    double v = 0;
    for (int h = 1; h <= 6; ++h) v += std::sin(h * phase) / h;
    s[i] = static_cast<int16_t>(5000 * v * std::sin(std::numbers::pi * t));
  }
  return s;
}

TEST(SpeechDtwFeatures, FramesColumnsAndTooLowRate) {
  const auto f = dtw_features(glide(150, 300, 0.5), 8000);
  // 25 ms frames every 10 ms over 0.5 s: 48 frames; 13 statics + 13 deltas.
  ASSERT_EQ(f.size(), 48u);
  for (const auto& row : f) ASSERT_EQ(row.size(), 26u);
  float peak = -1e9f;
  for (const auto& row : f) peak = std::max(peak, row[0]);
  EXPECT_FLOAT_EQ(peak, 0.0f);  // log energy relative to the loudest frame
  EXPECT_TRUE(dtw_features(glide(150, 300, 0.01), 8000).empty());       // shorter than a frame
  EXPECT_TRUE(dtw_features(glide(150, 300, 0.5, 6000), 6000).empty());  // band ends at 3.8 kHz
}

TEST(SpeechDtwDistance, ZeroForItselfSymmetricAndTimeWarpTolerant) {
  const auto up = dtw_features(glide(120, 400, 0.5), 8000);
  const auto up_slow = dtw_features(glide(120, 400, 0.8), 8000);  // same word, slower
  const auto down = dtw_features(glide(400, 120, 0.5), 8000);
  EXPECT_DOUBLE_EQ(dtw_distance(up, up), 0.0);
  EXPECT_DOUBLE_EQ(dtw_distance(up, down), dtw_distance(down, up));
  EXPECT_LT(dtw_distance(up, up_slow), 0.5 * dtw_distance(up, down));
  EXPECT_TRUE(std::isinf(dtw_distance(up, {})));
}

// 2 classes; clips 0-3 say class 0 (clip 3 only weakly wrong), 4-5 class 1.
struct VoteCase {
  std::vector<std::vector<double>> scores = {{0, -20}, {0, -15}, {0, -25},
                                             {-2, 0},  {-30, 0}, {-25, 0}};
  std::vector<std::vector<double>> dist;
  VoteCase() {
    const double pos[] = {0.0, 0.1, 0.2, 0.15, 10.0, 10.1};
    for (double a : pos) {
      dist.emplace_back();
      for (double b : pos) dist.back().push_back(1.0 + std::abs(a - b));
    }
  }
};

TEST(SpeechNeighbourVote, ConfidentNeighboursCorrectAWeakError) {
  VoteCase c;
  NeighbourVoteOptions o;
  o.neighbours = 3;
  o.max_distance_ratio = 2;
  const auto v = neighbour_vote(c.scores, c.dist, o);
  EXPECT_EQ(v, (std::vector<int>{0, 0, 0, 0, 1, 1}));
  o.weight = 0;  // no vote: each clip's own best
  EXPECT_EQ(neighbour_vote(c.scores, c.dist, o), (std::vector<int>{0, 0, 0, 1, 1, 1}));
}

TEST(SpeechNeighbourVote, DistantClipsDoNotVote) {
  VoteCase c;
  // Clip 3 is now far from everything but clips 4-5 (which say class 1): with the distance
  // ratio only those two vote, and they confirm its weak class 1.
  for (size_t j = 0; j < 6; ++j) c.dist[3][j] = c.dist[j][3] = j == 3 ? 0 : (j >= 4 ? 5 : 50);
  NeighbourVoteOptions o;
  o.neighbours = 5;
  o.max_distance_ratio = 1.15;
  EXPECT_EQ(neighbour_vote(c.scores, c.dist, o)[3], 1);
  o.max_distance_ratio = 20;  // all five vote: three confident class-0 clips win
  EXPECT_EQ(neighbour_vote(c.scores, c.dist, o)[3], 0);
}

TEST(SpeechNeighbourVote, NoPathSingleClipAndNoFeatures) {
  const double inf = std::numeric_limits<double>::infinity();
  const auto v = neighbour_vote({{-inf, -3.0, -inf}}, {{0.0}});
  EXPECT_EQ(v, std::vector<int>{1});
  EXPECT_EQ(neighbour_vote({{-inf, -inf}}, {{0.0}}), std::vector<int>{-1});
  // A clip without features (infinite distances) keeps its own answer.
  VoteCase c;
  for (size_t j = 0; j < 6; ++j) c.dist[3][j] = c.dist[j][3] = j == 3 ? 0 : inf;
  EXPECT_EQ(neighbour_vote(c.scores, c.dist)[3], 1);
}

class SpeakerBatchDir {
 public:
  SpeakerBatchDir() {
    path_ = fs::temp_directory_path() / ("ds_speaker_batch_" + std::to_string(getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~SpeakerBatchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_wav(const fs::path& p, const std::vector<int16_t>& s) {
  SF_INFO info{};
  info.samplerate = 8000;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* sf = sf_open(p.string().c_str(), SFM_WRITE, &info);
  ASSERT_NE(sf, nullptr) << p;
  sf_write_short(sf, s.data(), static_cast<sf_count_t>(s.size()));
  sf_close(sf);
}

// The fsdd runner on 4 synthetic "clips" of 2 speakers: both decodes are reported, the
// per-digit scores are there, and --warp reaches the front end (it once did not).
TEST(SpeechFsddRunner, ReportsPerUtteranceAndVotedResultsAndAppliesTheWarp) {
  if (!fs::exists(kTidigitsModel / "mdef"))
    GTEST_SKIP() << "needs pocketsphinx-testdata (TIDIGITS model)";
  SpeakerBatchDir t;
  write_wav(t.path() / "1_ann_0.wav", glide(120, 300, 0.4));
  write_wav(t.path() / "1_ann_1.wav", glide(120, 310, 0.45));
  write_wav(t.path() / "2_bob_0.wav", glide(300, 120, 0.4));
  write_wav(t.path() / "2_bob_1.wav", glide(310, 120, 0.35));
  SpeechEvalOptions o;
  o.dataset = "fsdd";
  o.dir = t.path();
  o.fsdd_speaker_adapt = true;  // opt-in (--speaker-adapt)
  auto r = run_speech_eval(o);
  ASSERT_TRUE(r) << r.error().to_string();
  const auto m = r->to_json()["metrics"];
  ASSERT_TRUE(m.contains("per_utterance")) << m.dump(1);
  EXPECT_EQ(m["per_utterance"]["per_speaker"].size(), 2u);
  // One document: a range-for over a member of the temporary r->to_json() would read freed
  // memory (ASan found it).
  const auto report = r->to_json();
  ASSERT_EQ(report["items"].size(), 4u);
  for (const auto& it : report["items"]) {
    ASSERT_EQ(it["digit_scores"].size(), 10u);
    EXPECT_TRUE(it.contains("hypothesis_per_utterance"));
  }
  EXPECT_NE(r->to_json()["protocol"].get<std::string>().find("speaker adaptation"),
            std::string::npos);

  o.fsdd_speaker_adapt = false;
  auto plain = run_speech_eval(o);
  ASSERT_TRUE(plain) << plain.error().to_string();
  EXPECT_FALSE(plain->to_json()["metrics"].contains("per_utterance"));
  auto scores = [](const eval::EvalReport& r) {
    std::vector<double> v;
    for (const auto& it : r.extra.at("items")) v.push_back(it["score_per_frame"].get<double>());
    return v;
  };
  o.frequency_warp = kFsddTidigitsWarp;  // the default, explicitly: same decode
  auto same = run_speech_eval(o);
  ASSERT_TRUE(same) << same.error().to_string();
  EXPECT_EQ(scores(*plain), scores(*same));
  o.frequency_warp = 1.0;
  auto unwarped = run_speech_eval(o);
  ASSERT_TRUE(unwarped) << unwarped.error().to_string();
  EXPECT_NE(scores(*plain), scores(*unwarped)) << "the frequency warp changed no score";

  o.fsdd_speaker_adapt = true;
  o.fsdd_vote.temperature = 0;
  EXPECT_FALSE(run_speech_eval(o));
}

// --fsdd-model DIR: a TIDIGITS-family model folder (e.g. an adapted copy) decodes like the
// packaged one; a name that is neither a model nor a folder is an error saying what is allowed.
TEST(SpeechFsddRunner, ModelFolderDecodesLikeThePackagedModel) {
  if (!fs::exists(kTidigitsModel / "mdef"))
    GTEST_SKIP() << "needs pocketsphinx-testdata (TIDIGITS model)";
  SpeakerBatchDir t;
  write_wav(t.path() / "1_ann_0.wav", glide(120, 300, 0.4));
  write_wav(t.path() / "2_bob_0.wav", glide(300, 120, 0.4));
  fs::copy(kTidigitsModel, t.path() / "model");
  SpeechEvalOptions o;
  o.dataset = "fsdd";
  o.dir = t.path();
  auto packaged = run_speech_eval(o);
  ASSERT_TRUE(packaged) << packaged.error().to_string();
  o.fsdd_model = (t.path() / "model").string();
  auto folder = run_speech_eval(o);
  ASSERT_TRUE(folder) << folder.error().to_string();
  ASSERT_EQ(folder->to_json()["items"].size(), 2u);
  for (size_t i = 0; i < 2; ++i)
    EXPECT_EQ(folder->to_json()["items"][i]["hypothesis"],
              packaged->to_json()["items"][i]["hypothesis"]);
  EXPECT_NE(folder->to_json()["protocol"].get<std::string>().find((t.path() / "model").string()),
            std::string::npos);
  o.fsdd_model = "tidigitz";
  auto bad = run_speech_eval(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("TIDIGITS-family model folder"), std::string::npos)
      << bad.error().message;
}

}  // namespace
}  // namespace dreamsense::speech
