// .pts reader (good, iBUG header, wrong count, non-number, missing), the metrics on a synthetic
// shape, the IoU detection rule, folder listing errors, and bad images in a run.

#include "dreamsense/eval/landmarks/landmarks_eval.hpp"

#include "dreamsense/perception/face_landmarks.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace dreamsense::eval::landmarks;

namespace {

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("ds-landmarks-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  fs::path path_;
};

// A 68-point shape: points on a grid, outer eye corners (37, 46) 100 px apart.
std::vector<cv::Point2d> synthetic_shape() {
  std::vector<cv::Point2d> p;
  for (int i = 0; i < 68; ++i) p.emplace_back(100 + (i % 10) * 10.0, 100 + (i / 10) * 10.0);
  p[36] = {150, 200};
  p[45] = {250, 200};
  return p;
}

void write_pts(const fs::path& f, const std::vector<cv::Point2d>& p, bool header) {
  std::ofstream out(f);
  if (header) out << "version: 1\nn_points: " << p.size() << "\n{\n";
  for (const auto& q : p) out << q.x << " " << q.y << "\n";
  if (header) out << "}\n";
}

}  // namespace

TEST(Pts, ReadsBareAndIbugLayouts) {
  TempDir t;
  const auto shape = synthetic_shape();
  write_pts(t.path() / "bare.pts", shape, false);
  write_pts(t.path() / "ibug.pts", shape, true);
  for (const char* name : {"bare.pts", "ibug.pts"}) {
    auto r = read_pts(t.path() / name);
    ASSERT_TRUE(r) << r.error().message;
    ASSERT_EQ(r->size(), 68u);
    EXPECT_DOUBLE_EQ((*r)[36].x, 150);
    EXPECT_DOUBLE_EQ((*r)[67].y, shape[67].y);
  }
}

TEST(Pts, ErrorsNameTheFileOnOneLine) {
  TempDir t;
  auto shape = synthetic_shape();
  // wrong count
  write_pts(t.path() / "short.pts", {shape.begin(), shape.begin() + 67}, false);
  // header count disagreeing with the points
  {
    std::ofstream out(t.path() / "header.pts");
    out << "version: 1\nn_points: 68\n{\n1 2\n3 4\n}\n";
  }
  // non-number
  {
    std::ofstream out(t.path() / "nan.pts");
    for (int i = 0; i < 68; ++i) out << (i == 5 ? "12.5 abc" : "1 2") << "\n";
  }
  // unclosed brace
  {
    std::ofstream out(t.path() / "open.pts");
    out << "version: 1\nn_points: 68\n{\n";
    for (int i = 0; i < 68; ++i) out << "1 2\n";
  }
  const std::vector<std::pair<std::string, std::string>> cases{
      {"short.pts", "67 points (expected 68)"},
      {"header.pts", "n_points says 68"},
      {"nan.pts", "nan.pts:6:"},
      {"open.pts", "closing"},
      {"missing.pts", "no such annotation file"}};
  for (const auto& [name, what] : cases) {
    auto r = read_pts(t.path() / name);
    ASSERT_FALSE(r) << name;
    EXPECT_NE(r.error().message.find(name), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << r.error().message;
  }
}

TEST(Metrics, NmeAndEyeErrorOnAKnownShape) {
  const auto truth = synthetic_shape();
  EXPECT_DOUBLE_EQ(outer_corner_distance(truth), 100.0);
  EXPECT_DOUBLE_EQ(nme_outer_corners(truth, truth), 0.0);
  // Every point moved by (3, 4): error 5 px / 100 px.
  auto moved = truth;
  for (auto& p : moved) p += cv::Point2d(3, 4);
  EXPECT_NEAR(nme_outer_corners(moved, truth), 0.05, 1e-12);
  EXPECT_NEAR(eye_center_error(moved, truth), 0.05, 1e-12);
  // Only the right-eye contour (37-42) moved by 6 px: eye error = (6 + 0) / 2 / 100;
  // NME = 6 points x 6 px / 68 / 100.
  auto eye = truth;
  for (int i = 36; i < 42; ++i) eye[i].x += 6;
  EXPECT_NEAR(eye_center_error(eye, truth), 0.03, 1e-12);
  EXPECT_NEAR(nme_outer_corners(eye, truth), 36.0 / 68 / 100, 1e-12);
  // Wrong sizes: NaN, not a crash.
  EXPECT_TRUE(std::isnan(nme_outer_corners({truth.begin(), truth.begin() + 5}, truth)));
  const cv::Rect2d b = dreamsense::points_extent(truth);
  EXPECT_DOUBLE_EQ(b.x, 100);
  EXPECT_DOUBLE_EQ(b.width, 150);
}

TEST(Metrics, DetectionNeedsIouOfHalf) {
  const cv::Rect2d truth(100, 100, 100, 100);
  // IoU 1/3 (shifted by half), IoU 0.81 (shrunk to 90x90 inside), IoU 0.5 exactly (2x area).
  const cv::Rect2d half_shift(150, 100, 100, 100);
  const cv::Rect2d inside(105, 105, 90, 90);
  const cv::Rect2d twice(100, 100, 200, 100);
  EXPECT_EQ(match_detection({half_shift}, truth), -1);
  EXPECT_EQ(match_detection({twice}, truth), 0);
  EXPECT_EQ(match_detection({half_shift, twice, inside}, truth), 2);  // best IoU wins
  EXPECT_EQ(match_detection({}, truth), -1);
  EXPECT_EQ(match_detection({cv::Rect2d(500, 500, 50, 50)}, truth), -1);  // another face
}

TEST(Dataset, ListingErrorsNameTheFile) {
  TempDir t;
  EXPECT_FALSE(list_300w(t.path() / "absent"));
  auto empty = list_300w(t.path());
  ASSERT_FALSE(empty);
  EXPECT_NE(empty.error().message.find("300-W"), std::string::npos);
  cv::imwrite((t.path() / "a_1.jpg").string(), cv::Mat(64, 64, CV_8UC3, cv::Scalar::all(128)));
  auto no_pts = list_300w(t.path());
  ASSERT_FALSE(no_pts);
  EXPECT_NE(no_pts.error().message.find("a_1.jpg"), std::string::npos) << no_pts.error().message;
  write_pts(t.path() / "a_1.pts", synthetic_shape(), false);
  write_pts(t.path() / "b_1.pts", synthetic_shape(), false);
  auto no_image = list_300w(t.path());
  ASSERT_FALSE(no_image);
  EXPECT_NE(no_image.error().message.find("b_1.pts"), std::string::npos);
  fs::remove(t.path() / "b_1.pts");
  auto ok = list_300w(t.path());
  ASSERT_TRUE(ok) << ok.error().message;
  EXPECT_EQ(ok->size(), 1u);
}

TEST(Options, SsdChainsAndScoreAreChecked) {
  LandmarksEvalOptions o;
  o.detectors = {"ssd",     "union_ssd+switch",      "ssd_union+cnn_switch", "union_tiny_ssd",
                 "ssd+cnn", "union_tiny+cnn_switch", "ssd_paired+switch"};
  EXPECT_TRUE(o.check());
  o.detectors = {"ssd+bogus"};
  auto bad = o.check();
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("ssd+bogus"), std::string::npos);
  o.detectors = {"ssd"};
  o.ssd_min_score = 1.0;
  bad = o.check();
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("ssd_min_score"), std::string::npos);
  o.ssd_min_score = 0.5;
  EXPECT_TRUE(o.ssd_tiles);  // the default since issue 20's third round
  for (double fraction : {0.5, 1.0}) {
    o.ssd_tile_fraction = fraction;  // tiles must overlap and be smaller than the image
    bad = o.check();
    ASSERT_FALSE(bad) << fraction;
    EXPECT_NE(bad.error().message.find("ssd_tile_fraction"), std::string::npos);
  }
}

TEST(Run, GreyFacelessImageIsNotDetectedAndBadFilesAreErrors) {
  if (!fs::exists("/usr/share/dlib/shape_predictor_68_face_landmarks.dat"))
    GTEST_SKIP() << "libdlib-data absent";
  TempDir t;
  cv::imwrite((t.path() / "grey.jpg").string(), cv::Mat(300, 400, CV_8UC1, cv::Scalar(90)));
  write_pts(t.path() / "grey.pts", synthetic_shape(), true);
  LandmarksEvalOptions o;
  o.dir = t.path();
  auto r = run_landmarks_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->items, 1u);
  o.detectors = {"union+tta", "hog_haar", "hog", "haar"};
  r = run_landmarks_eval(o);
  ASSERT_TRUE(r) << r.error().message;
  for (const char* c : {"union+tta", "hog_haar", "hog", "haar"}) {
    EXPECT_EQ(r->metrics[c]["detection_rate"], 0.0) << c;
    EXPECT_TRUE(r->metrics[c]["nme_outer_corners"].is_null()) << c;
  }
  // The annotated box on a uniform image: the landmarker refuses it, a failure (not an error).
  EXPECT_EQ(r->metrics["from_box"]["failure_rate_08"], 1.0);
  EXPECT_EQ(r->metrics["from_box_plain"]["failure_rate_08"], 1.0);

  // A damaged image: an error naming it.
  { std::ofstream(t.path() / "grey.jpg", std::ios::trunc) << "not a jpeg"; }
  auto bad = run_landmarks_eval(o);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("grey.jpg"), std::string::npos) << bad.error().message;
  // A malformed annotation: an error naming it, before any detection.
  { std::ofstream(t.path() / "grey.pts", std::ios::trunc) << "1 2\n"; }
  auto bad_pts = run_landmarks_eval(o);
  ASSERT_FALSE(bad_pts);
  EXPECT_NE(bad_pts.error().message.find("grey.pts"), std::string::npos);
  // Unknown detector.
  o.detectors = {"magic"};
  EXPECT_FALSE(run_landmarks_eval(o));
}
