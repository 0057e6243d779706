#include "dreamsense/sim/demo_session.hpp"

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sndfile.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace dreamsense::sim {
namespace {

namespace fs = std::filesystem;

bool media_available() {
  const DemoOptions o;
  return fs::exists(o.portrait) && fs::exists(o.opencv_samples_dir / "HappyFish.jpg") &&
         fs::exists(o.pocketsphinx_data_dir / "goforward.raw");
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<nlohmann::json> read_jsonl(const fs::path& p) {
  std::vector<nlohmann::json> out;
  std::ifstream in(p);
  std::string line;
  while (std::getline(in, line))
    if (!line.empty()) out.push_back(nlohmann::json::parse(line));
  return out;
}

class DemoSessionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!media_available()) GTEST_SKIP() << "demo media not installed";
    root_ = fs::temp_directory_path() /
            ("ds_sim_test_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override {
    if (!root_.empty()) fs::remove_all(root_);
  }
  Result<DemoSummary> generate(const std::string& name, uint64_t seed, double duration,
                               int threads = 2) {
    DemoOptions o;
    o.out_dir = root_ / name;
    o.seed = seed;
    o.duration_s = duration;
    o.threads = threads;
    return generate_demo_session(o);
  }
  fs::path root_;
};

TEST_F(DemoSessionTest, SameSeedGivesByteIdenticalFiles) {
  auto a = generate("a", 7, 2.0, 2);
  ASSERT_TRUE(a) << a.error().to_string();
  auto b = generate("b", 7, 2.0, 1);  // a different thread count must not matter
  ASSERT_TRUE(b) << b.error().to_string();
  std::set<std::string> files_a, files_b;
  for (const auto& e : fs::recursive_directory_iterator(root_ / "a"))
    if (e.is_regular_file()) files_a.insert(fs::relative(e.path(), root_ / "a").string());
  for (const auto& e : fs::recursive_directory_iterator(root_ / "b"))
    if (e.is_regular_file()) files_b.insert(fs::relative(e.path(), root_ / "b").string());
  EXPECT_EQ(files_a, files_b);
  EXPECT_TRUE(files_a.count("truth.jsonl"));
  for (const auto& f : files_a)
    EXPECT_TRUE(slurp(root_ / "a" / f) == slurp(root_ / "b" / f)) << f << " differs";
  auto c = generate("c", 8, 2.0);
  ASSERT_TRUE(c) << c.error().to_string();
  EXPECT_NE(slurp(root_ / "a" / "truth.jsonl"), slurp(root_ / "c" / "truth.jsonl"));
  EXPECT_NE(slurp(root_ / "a" / "camera_middle.mjpg"), slurp(root_ / "c" / "camera_middle.mjpg"));
}

// Issue 16: the robot speaks in the gaps of the human utterances, with truth and a reference
// stream; --audio-only writes only the audio; without the robot voice the demo is the old one.
TEST_F(DemoSessionTest, RobotVoiceInTheGapsWithTruthAndReference) {
  for (const bool robot : {true, false}) {
    DemoOptions o;
    o.out_dir = root_ / (robot ? "robot" : "no_robot");
    o.seed = 105;
    o.duration_s = 40;
    o.audio_only = true;
    o.robot_voice = robot;
    auto s = generate_demo_session(o);
    ASSERT_TRUE(s) << s.error().to_string();
    auto m = sources::read_manifest(o.out_dir);
    ASSERT_TRUE(m) << m.error().to_string();
    std::vector<std::string> ids;
    for (const auto& e : m->streams) ids.push_back(e.id);
    const std::vector<std::string> want = robot
                                              ? std::vector<std::string>{"mic_array", "robot_audio"}
                                              : std::vector<std::string>{"mic_array"};
    EXPECT_EQ(ids, want);
    std::vector<std::pair<int64_t, int64_t>> human, robot_spans;
    for (const auto& r : read_jsonl(o.out_dir / "truth.jsonl")) {
      if (r["type"] == "speech") human.emplace_back(r["start_ns"], r["end_ns"]);
      if (r["type"] == "robot_speech") {
        robot_spans.emplace_back(r["start_ns"], r["end_ns"]);
        EXPECT_TRUE(r.contains("text") && r.contains("in_grammar") && r.contains("azimuth_deg"));
      }
    }
    EXPECT_EQ(s->robot_utterances, static_cast<int>(robot_spans.size()));
    EXPECT_FALSE(human.empty());
    if (!robot) {
      EXPECT_TRUE(robot_spans.empty());
      continue;
    }
    EXPECT_GE(robot_spans.size(), 1u);
    for (const auto& [a, b] : robot_spans)
      for (const auto& [c, d] : human)  // >= 0.5 s of silence between robot and human speech
        EXPECT_TRUE(b + 500'000'000 <= c || d + 500'000'000 <= a) << a << " vs " << c;
    // The reference is silent outside the robot's prompts and loud inside them.
    SF_INFO info{};
    SNDFILE* f = sf_open((o.out_dir / "robot_audio.wav").string().c_str(), SFM_READ, &info);
    ASSERT_NE(f, nullptr);
    std::vector<float> x(static_cast<size_t>(info.frames));
    sf_readf_float(f, x.data(), info.frames);
    sf_close(f);
    EXPECT_EQ(info.channels, 1);
    EXPECT_EQ(info.samplerate, 16000);
    const size_t mid = static_cast<size_t>((robot_spans[0].first + robot_spans[0].second) / 2 *
                                           16000 / 1'000'000'000);
    float peak_in = 0;
    for (size_t i = mid - 4000; i < mid + 4000; ++i) peak_in = std::max(peak_in, std::abs(x[i]));
    EXPECT_GT(peak_in, 0.05f);
    const size_t hmid =
        static_cast<size_t>((human[0].first + human[0].second) / 2 * 16000 / 1'000'000'000);
    for (size_t i = hmid - 4000; i < hmid + 4000; ++i) ASSERT_EQ(x[i], 0.0f);
  }
}

TEST(RobotVoicePlan, UsesOnlyGapsWithMargins) {
  const std::vector<std::pair<double, double>> busy = {{2, 5}, {9, 10}, {20, 24}};
  const std::vector<double> durations = {1.0, 1.5, 2.5};
  int placed = 0;
  for (uint64_t seed = 1; seed <= 50; ++seed)
    for (const auto& u : plan_robot_utterances(seed, 30, busy, durations)) {
      ++placed;
      const double a = u.clip_start_s, b = a + durations[u.prompt];
      EXPECT_GE(a, 1.0 - 1e-9);
      EXPECT_LE(b, 29.5 - 1.0 + 1e-9);
      for (const auto& [c, d] : busy) EXPECT_TRUE(b + 1.0 <= c + 1e-9 || d + 1.0 <= a + 1e-9);
    }
  EXPECT_GT(placed, 50);  // most gaps are used (probability 0.7)
  EXPECT_TRUE(plan_robot_utterances(1, 30, busy, {}).empty());
}

TEST_F(DemoSessionTest, ManifestAndTruthAreSane) {
  auto s = generate("s", 3, 2.0);
  ASSERT_TRUE(s) << s.error().to_string();
  EXPECT_EQ(s->frames.at("camera_left"), 50);
  EXPECT_EQ(s->frames.at("front.depth"), 60);
  auto m = sources::read_manifest(root_ / "s");
  ASSERT_TRUE(m) << m.error().to_string();
  EXPECT_EQ(m->name, "demo-seed-3");
  EXPECT_TRUE(m->complete);
  EXPECT_EQ(m->truth, "truth.jsonl");
  std::vector<std::string> ids;
  for (const auto& e : m->streams) {
    ids.push_back(e.id);
    if (e.id == "robot_audio") {  // a signal, not a sensor with a geometry
      EXPECT_EQ(e.roles, std::vector<std::string>{"robot_audio"});
      EXPECT_EQ(e.channels, 1);
      continue;
    }
    EXPECT_FALSE(e.calibration.empty()) << e.id;
    EXPECT_TRUE(fs::exists(root_ / "s" / e.calibration)) << e.calibration;
  }
  EXPECT_EQ(ids, (std::vector<std::string>{"camera_left", "camera_middle", "camera_right",
                                           "front.color", "front.depth", "front.skeleton",
                                           "top.color", "mic_array", "robot_audio"}));
  auto cam = read_camera_model(root_ / "s" / "calib" / "camera_right.yaml");
  ASSERT_TRUE(cam) << cam.error().to_string();
  EXPECT_EQ(cam->image_size, cv::Size(1280, 960));

  const auto truth = read_jsonl(root_ / "s" / "truth.jsonl");
  ASSERT_FALSE(truth.empty());
  EXPECT_EQ(truth.front()["type"], "meta");
  std::map<std::string, int> counts;
  int64_t prev_face = -1;
  for (const auto& r : truth) {
    counts[r["type"]]++;
    if (r["type"] == "face") {
      EXPECT_GT(r["stamp_ns"].get<int64_t>(), prev_face);
      prev_face = r["stamp_ns"];
      for (const auto& [id, c] : r["cameras"].items()) {
        if (!c["visible"].get<bool>()) continue;
        for (const char* eye : {"left", "right"}) {
          const double u = c["eyes_px"][eye][0], v = c["eyes_px"][eye][1];
          EXPECT_GE(u, 0);
          EXPECT_LT(u, 1280);
          EXPECT_GE(v, 0);
          EXPECT_LT(v, 960);
        }
      }
    }
  }
  EXPECT_EQ(counts["face"], 50);
  // Eye truth: pupils, eyeballs, per-eye gaze, eyes_open; eyes_px = projected pupils.
  int differs = 0;
  for (const auto& r : truth) {
    if (r["type"] != "face") continue;
    for (const char* key : {"eyes_m", "eyeballs_m", "eye_gaze_dirs"}) {
      ASSERT_TRUE(r.contains(key)) << key;
      ASSERT_TRUE(r[key].contains("left") && r[key].contains("right")) << key;
    }
    ASSERT_TRUE(r["eyes_open"].is_boolean());
    ASSERT_TRUE(r["gaze_target"].is_string());
    auto v3 = [](const nlohmann::json& j) {
      return cv::Vec3d(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
    };
    const cv::Vec3d pupil = v3(r["eyes_m"]["left"]), ball = v3(r["eyeballs_m"]["left"]);
    EXPECT_NEAR(cv::norm(pupil - ball), 0.012, 2e-6);
    const cv::Vec3d eye = v3(r["eye_gaze_dir"]), head = v3(r["head_gaze_dir"]);
    if (std::acos(std::min(1.0, eye.dot(head))) > 5 * CV_PI / 180) ++differs;
    const auto p = cam->project(pupil);
    ASSERT_TRUE(p.has_value());
    EXPECT_NEAR(r["cameras"]["camera_right"]["eyes_px"]["left"][0].get<double>(), p->x, 2e-3);
    EXPECT_NEAR(r["cameras"]["camera_right"]["eyes_px"]["left"][1].get<double>(), p->y, 2e-3);
  }
  EXPECT_GT(differs, 0) << "eye gaze should differ from head gaze in some frames";
  EXPECT_EQ(counts["skeleton"], 60);
  EXPECT_EQ(counts["object"], 60 * 4);
  EXPECT_GE(counts["action"], 1);
}

TEST_F(DemoSessionTest, SessionReadsBack) {
  auto s = generate("r", 11, 1.0);
  ASSERT_TRUE(s) << s.error().to_string();
  auto reader = sources::SessionReader::open(root_ / "r");
  ASSERT_TRUE(reader) << reader.error().to_string();
  std::map<std::string, int> n;
  for (;;) {
    auto f = (*reader)->next();
    if (!f) {
      EXPECT_EQ(f.error().code, ErrorCode::kEndOfStream) << f.error().to_string();
      break;
    }
    n[(*f)->sensor]++;
    if (const auto* d = (*f)->as<DepthImage>()) {
      // The back wall is 2.5 m away at the top of the image.
      EXPECT_NEAR(d->depth_mm.at<uint16_t>(5, 320), 2500, 150);
    }
  }
  EXPECT_EQ(n["camera_middle"], 25);
  EXPECT_EQ(n["front.skeleton"], 30);
  EXPECT_GT(n["mic_array"], 0);
}

TEST_F(DemoSessionTest, MissingMediaNamesTheDebianPackage) {
  DemoOptions o;
  o.out_dir = root_ / "m";
  o.duration_s = 1;
  o.pocketsphinx_data_dir = "/nonexistent/pocketsphinx";
  auto r = generate_demo_session(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("pocketsphinx-testdata"), std::string::npos)
      << r.error().message;
  o.opencv_samples_dir = "/nonexistent/opencv";
  r = generate_demo_session(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("opencv-doc"), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
}

TEST_F(DemoSessionTest, PlanarFaceOptionStillWorks) {
  DemoOptions o;
  o.out_dir = root_ / "p";
  o.seed = 2;
  o.duration_s = 1.0;
  o.face_model = DemoOptions::FaceModel::kPlanar;
  auto s = generate_demo_session(o);
  ASSERT_TRUE(s) << s.error().to_string();
  for (const auto& r : read_jsonl(root_ / "p" / "truth.jsonl")) {
    if (r["type"] == "face") {
      EXPECT_EQ(r["eye_gaze_dir"], r["head_gaze_dir"]);  // painted eyes
    }
  }
}

// The same computation as the face truth: script -> face state -> the mesh's eyes.
TEST(DemoMutualGaze, FractionIsInTheBandAndRunsLastInEverySeed) {
  const DemoOptions defaults;
  if (!fs::exists(defaults.portrait) || !fs::exists(defaults.portrait_landmarks))
    GTEST_SKIP() << "portrait or landmark file missing";
  auto face = MeshFaceRenderer::create({});
  ASSERT_TRUE(face) << face.error().to_string();
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    const DemoScript script(seed, 20);
    const DemoGeometry& g = script.geometry();
    std::vector<bool> mutual;
    for (int k = 0; k < 500; ++k) {  // the 25 Hz camera frames
      const EyesState e = (*face)->eyes(demo_face_state(script, k / 25.0));
      mutual.push_back(ray_point_distance(e.eye_midpoint(), e.gaze_dir(), g.robot_head_m) <=
                       g.gaze_radius_m);
    }
    const double fraction =
        static_cast<double>(std::count(mutual.begin(), mutual.end(), true)) / mutual.size();
    EXPECT_GE(fraction, 0.30) << "seed " << seed;
    EXPECT_LE(fraction, 0.50) << "seed " << seed;
    // Runs of mutual gaze last >= 0.5 s (unless cut by the end of the session).
    for (size_t i = 0; i < mutual.size();) {
      if (!mutual[i]) {
        ++i;
        continue;
      }
      size_t j = i;
      while (j < mutual.size() && mutual[j]) ++j;
      if (i > 0 && j < mutual.size()) {
        EXPECT_GE(j - i, 13u) << "seed " << seed << " run at frame " << i;
      }
      i = j;
    }
  }
}

TEST(DemoOptions, CheckRejectsBadValues) {
  DemoOptions o;
  EXPECT_FALSE(o.check());  // no out_dir
  o.out_dir = "/tmp/x";
  EXPECT_TRUE(o.check());
  o.duration_s = 0;
  EXPECT_FALSE(o.check());
}

TEST(DemoUtterances, PlacementIsNonOverlappingAndSpeakersAlternate) {
  std::vector<SpeechClipInfo> clips;
  for (int i = 0; i < 5; ++i)
    clips.push_back({"c", "x", "child", 1.5 + 0.3 * i, 0.2, 1.3 + 0.3 * i});
  for (int i = 0; i < 3; ++i) clips.push_back({"t", "y", "therapist", 3.0 + i, 0.2, 2.8 + i});
  for (uint64_t seed = 1; seed < 30; ++seed) {
    const DemoScript script(seed, 20);
    const auto u = plan_utterances(script, clips);
    EXPECT_GE(u.size(), 3u);
    EXPECT_LE(u.size(), 5u);
    for (size_t i = 0; i < u.size(); ++i) {
      double az = 0, el = 0;
      array_direction(script.geometry(), u[i].source_m, az, el);
      EXPECT_LE(std::abs(az), 60.0);
      const double d = cv::norm(u[i].source_m - script.geometry().mic_array_m);
      EXPECT_GE(d, 1.0);
      EXPECT_LE(d, 2.05);
      if (i > 0) {
        EXPECT_GE(u[i].clip_start_s, u[i - 1].clip_start_s + clips[u[i - 1].clip].duration_s);
      }
      if (clips[u[i].clip].speaker == "therapist") {
        EXPECT_EQ(u[i].source_m[0] > 0, script.therapist_side() > 0);  // where the child looks
      }
      EXPECT_LE(u[i].clip_start_s + clips[u[i].clip].duration_s, 20.0);
    }
  }
}

}  // namespace
}  // namespace dreamsense::sim
