#include "dreamsense/geometry/intrinsics.hpp"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <random>
#include <unistd.h>

namespace dreamsense::geometry {
namespace {
namespace fs = std::filesystem;

// A 9x6-inner-corner board (10x7 squares of 40 px) with a white margin, warped by a homography.
cv::Mat board_image(const cv::Matx33d& H, cv::Size size, std::vector<cv::Point2f>& corners) {
  const int sq = 40, margin = 60;
  cv::Mat flat(7 * sq + 2 * margin, 10 * sq + 2 * margin, CV_8U, cv::Scalar(255));
  for (int r = 0; r < 7; ++r)
    for (int c = 0; c < 10; ++c)
      if ((r + c) % 2 == 0)
        cv::rectangle(flat, cv::Rect(margin + c * sq, margin + r * sq, sq, sq), cv::Scalar(0),
                      cv::FILLED);
  std::vector<cv::Point2f> flat_corners;
  for (int r = 1; r <= 6; ++r)
    for (int c = 1; c <= 9; ++c)
      flat_corners.emplace_back(margin + c * sq - 0.5f, margin + r * sq - 0.5f);
  cv::Mat out;
  cv::warpPerspective(flat, out, cv::Mat(H), size, cv::INTER_AREA, cv::BORDER_CONSTANT,
                      cv::Scalar(255));
  cv::perspectiveTransform(flat_corners, corners, cv::Mat(H));
  return out;
}

TEST(Intrinsics, DetectsARenderedBoardToSubPixelAccuracy) {
  const cv::Matx33d H(0.9, 0.1, 40, -0.05, 0.95, 30, 0.0001, 0.0002, 1);
  std::vector<cv::Point2f> truth;
  const cv::Mat img = board_image(H, {640, 480}, truth);
  auto found = detect_chessboard(img, {9, 6});
  ASSERT_TRUE(found);
  ASSERT_EQ(found->size(), 54u);
  // OpenCV may order the corners from either end; compare as sets via nearest truth corner.
  double worst = 0;
  for (const auto& p : *found) {
    double best = 1e9;
    for (const auto& q : truth) best = std::min(best, cv::norm(p - q));
    worst = std::max(worst, best);
  }
  EXPECT_LT(worst, 0.3);
  EXPECT_FALSE(detect_chessboard(img, {7, 5}).has_value() &&
               detect_chessboard(img, {7, 5})->size() == 54u);
  EXPECT_FALSE(detect_chessboard(cv::Mat(480, 640, CV_8U, cv::Scalar(128)), {9, 6}));
}

TEST(Intrinsics, RecoversAKnownCameraAndRejectsABadView) {
  const cv::Matx33d K(800, 0, 322, 0, 805, 236, 0, 0, 1);
  const cv::Mat dist = (cv::Mat_<double>(1, 5) << -0.2, 0.1, 0, 0, 0);
  IntrinsicsOptions o;
  o.model = DistortionModel::kRadial2;
  const auto board = chessboard_object_points(o.board, o.square_size);
  std::vector<std::vector<cv::Point3f>> obj;
  std::vector<std::vector<cv::Point2f>> img;
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0, 0.1f);
  for (int v = 0; v < 8; ++v) {
    const cv::Vec3d rvec(0.3 * std::sin(v), 0.3 * std::cos(v), 0.1 * v);
    const cv::Vec3d tvec(-0.12 + 0.01 * v, -0.08, 0.45 + 0.03 * v);
    std::vector<cv::Point2f> px;
    cv::projectPoints(board, rvec, tvec, cv::Mat(K), dist, px);
    for (auto& p : px) p += cv::Point2f(noise(rng), noise(rng));
    if (v == 5)
      for (auto& p : px) p += cv::Point2f(noise(rng) * 40, noise(rng) * 40);  // a blurred view
    obj.push_back(board);
    img.push_back(px);
  }
  auto r = calibrate_from_points(obj, img, {640, 480}, o);
  ASSERT_TRUE(r) << r.error().message;
  // Within 0.4 % (3 px): the clang/ASan build lands at 802.4 / 807.4, gcc's within 2 px.
  EXPECT_NEAR(r->camera.K(0, 0), 800, 3);
  EXPECT_NEAR(r->camera.K(1, 1), 805, 3);
  EXPECT_NEAR(r->camera.distortion.at<double>(0), -0.2, 0.01);
  EXPECT_FALSE(r->views[5].used) << "the bad view is rejected";
  EXPECT_EQ(r->views_used, 7);
  EXPECT_LT(r->rms_px, 0.2);
  EXPECT_EQ(r->flags & cv::CALIB_FIX_K3, cv::CALIB_FIX_K3);
}

class IntrinsicsFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("ds_intr_" + std::to_string(::getpid()));
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  fs::path dir;
};

TEST_F(IntrinsicsFiles, NoBoardMismatchedSizesAndMissingFilesAreErrors) {
  cv::imwrite((dir / "a.png").string(), cv::Mat(480, 640, CV_8U, cv::Scalar(128)));
  cv::imwrite((dir / "b.png").string(), cv::Mat(480, 640, CV_8U, cv::Scalar(60)));
  cv::imwrite((dir / "c.png").string(), cv::Mat(240, 320, CV_8U, cv::Scalar(60)));
  IntrinsicsOptions o;
  auto none = calibrate_from_images({dir / "a.png", dir / "b.png"}, o);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("no 9x6 chessboard"), std::string::npos)
      << none.error().message;
  auto sizes = calibrate_from_images({dir / "a.png", dir / "c.png"}, o);
  ASSERT_FALSE(sizes);
  EXPECT_NE(sizes.error().message.find("320x240"), std::string::npos) << sizes.error().message;
  EXPECT_FALSE(calibrate_from_images({dir / "missing.png"}, o));
  EXPECT_FALSE(calibrate_from_images({}, o));
  o.board = {1, 6};
  EXPECT_FALSE(o.check());
}

TEST_F(IntrinsicsFiles, CalibratesFromRenderedImages) {
  std::vector<fs::path> files;
  for (int v = 0; v < 6; ++v) {
    const double a = 0.15 * (v - 2.5), b = 0.0002 * ((v % 3) - 1);
    const cv::Matx33d H(0.9 + 0.05 * v, a, 60 + 10 * v, -a, 0.9, 40 + 5 * v, b, 0.00015 * (v % 2),
                        1);
    std::vector<cv::Point2f> truth;
    const fs::path f = dir / ("view" + std::to_string(v) + ".png");
    cv::imwrite(f.string(), board_image(H, {640, 480}, truth));
    files.push_back(f);
  }
  IntrinsicsOptions o;
  o.model = DistortionModel::kRadial2;
  auto r = calibrate_from_images(files, o);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->camera.image_size, cv::Size(640, 480));
  // Arbitrary homographies are not all views of one pinhole camera: ~1 px is expected here.
  EXPECT_LT(r->rms_px, 2.0);
  EXPECT_EQ(r->views.size(), 6u);
}

}  // namespace
}  // namespace dreamsense::geometry
