#include "dreamsense/sim/demo_session.hpp"

#include "dreamsense/sources/session.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
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
    EXPECT_FALSE(e.calibration.empty()) << e.id;
    EXPECT_TRUE(fs::exists(root_ / "s" / e.calibration)) << e.calibration;
  }
  EXPECT_EQ(ids,
            (std::vector<std::string>{"camera_left", "camera_middle", "camera_right", "front.color",
                                      "front.depth", "front.skeleton", "top.color", "mic_array"}));
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
  for (const auto& r : read_jsonl(root_ / "p" / "truth.jsonl"))
    if (r["type"] == "face") EXPECT_EQ(r["eye_gaze_dir"], r["head_gaze_dir"]);  // painted eyes
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
      if (i > 0 && j < mutual.size())
        EXPECT_GE(j - i, 13u) << "seed " << seed << " run at frame " << i;
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
