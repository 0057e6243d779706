#include "dreamsense/vision/face_alignment.hpp"

#include "dreamsense/vision/face_crops.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

namespace dreamsense::vision {
namespace {

// Landmarks of the mean face moved by a known similarity (scale s, rotation deg, offset).
std::vector<cv::Point2d> moved_face(double s, double deg, cv::Point2d offset) {
  const double a = deg * CV_PI / 180;
  std::vector<cv::Point2d> out;
  for (const cv::Point2d& p : mean_face_landmarks(1.0))
    out.emplace_back(s * (std::cos(a) * p.x - std::sin(a) * p.y) + offset.x,
                     s * (std::sin(a) * p.x + std::cos(a) * p.y) + offset.y);
  return out;
}

cv::Mat noise_image(int w, int h) {
  cv::Mat m(h, w, CV_8UC1);
  cv::randu(m, 30, 220);
  cv::GaussianBlur(m, m, cv::Size(0, 0), 1.5);
  return m;
}

TEST(FaceAlignment, EyesLandOnTheirTargets) {
  AlignmentOptions o;
  o.size = 80;
  const auto t = similarity_from_eyes({30, 50}, {70, 40}, o);
  ASSERT_TRUE(t.has_value());
  const auto p = transform_points(*t, {{30, 50}, {70, 40}});
  EXPECT_NEAR(p[0].x, (0.5 - o.eye_distance / 2) * 80, 1e-9);
  EXPECT_NEAR(p[1].x, (0.5 + o.eye_distance / 2) * 80, 1e-9);
  EXPECT_NEAR(p[0].y, o.eye_row * 80, 1e-9);
  EXPECT_NEAR(p[1].y, o.eye_row * 80, 1e-9);  // level
  EXPECT_FALSE(similarity_from_eyes({5, 5}, {5, 5}, o).has_value());
}

TEST(FaceAlignment, RotatedScaledFaceIsUndone) {
  AlignmentOptions o;
  const auto lm = moved_face(120, 25, {200, 80});
  cv::Mat image = noise_image(400, 300);
  auto face = align_face(image, lm, o);
  ASSERT_TRUE(face.has_value());
  ASSERT_TRUE(face->has_value());
  const auto& f = **face;
  EXPECT_EQ(f.grey.size(), cv::Size(o.size, o.size));
  const auto [right, left] = eye_centres(f.landmarks);
  EXPECT_NEAR(right.y, left.y, 1e-6);
  EXPECT_NEAR(left.x - right.x, o.eye_distance * o.size, 1e-6);
  EXPECT_EQ(f.source, AlignmentSource::kLandmarks);
  // Too few points: no face, not an error.
  auto none = align_face(image, std::vector<cv::Point2d>(10), o);
  ASSERT_TRUE(none.has_value());
  EXPECT_FALSE(none->has_value());
  EXPECT_FALSE(align_face(cv::Mat(10, 10, CV_16UC1), lm, o).has_value());  // bad type: error
}

TEST(FaceAlignment, DlibTemplateRecoversTheSimilarity) {
  AlignmentOptions o;
  o.size = 150;
  o.dlib_template = true;
  const auto lm = moved_face(90, -15, {60, 40});
  const auto t = similarity_from_landmarks(lm, o);
  ASSERT_TRUE(t.has_value());
  // Template points are exactly the mean face: the fit maps them onto (p + mean) * k.
  const double k = o.size / (2 * o.template_padding + 1);
  const auto mapped = transform_points(*t, lm);
  const auto mean = mean_face_landmarks(1.0);
  for (int i : {30, 36, 45, 48, 54})
    EXPECT_NEAR(mapped[i].x, (o.template_padding + mean[i].x) * k, 1e-6) << i;
  const auto [d, r] = eye_geometry(o);
  EXPECT_GT(d, 0.2);
  EXPECT_LT(d, 0.4);
  EXPECT_GT(r, 0.3);
  EXPECT_LT(r, 0.5);
}

TEST(FaceAlignment, RegionGivesTheSameCropAsTheWholeFrame) {
  cv::Mat frame(480, 640, CV_8UC3);
  cv::randu(frame, 0, 255);
  auto lm = mean_face_landmarks(120);
  for (auto& p : lm) p += cv::Point2d(300, 200);
  auto grey = to_grey(frame);
  ASSERT_TRUE(grey);
  auto whole = align_face(*grey, lm, {});
  auto region = face_region(frame, lm);
  ASSERT_TRUE(whole && *whole && region);
  EXPECT_LT(region->grey.cols, frame.cols);
  auto part = align_face(region->grey, region->landmarks, {});
  ASSERT_TRUE(part && *part);
  EXPECT_EQ(cv::norm((*whole)->grey, (*part)->grey, cv::NORM_INF), 0.0);
  // Landmarks outside the frame: an empty region, not an error.
  auto outside = lm;
  for (auto& p : outside) p += cv::Point2d(5000, 0);
  auto none = face_region(frame, outside);
  ASSERT_TRUE(none);
  EXPECT_TRUE(none->grey.empty());
}

TEST(FaceAlignment, MirrorSwapsSidesAndIsAnInvolution) {
  AlignmentOptions o;
  auto face = align_face(noise_image(300, 300), moved_face(100, 10, {100, 100}), o);
  ASSERT_TRUE(face && *face);
  const AlignedFace m = mirror_face(**face);
  const auto [r0, l0] = eye_centres((*face)->landmarks);
  const auto [r1, l1] = eye_centres(m.landmarks);
  EXPECT_NEAR(r1.x, o.size - 1 - l0.x, 1e-9);  // the right eye is where the left one was
  EXPECT_NEAR(l1.x, o.size - 1 - r0.x, 1e-9);
  const AlignedFace mm = mirror_face(m);
  for (size_t i = 0; i < mm.landmarks.size(); ++i)
    EXPECT_NEAR(cv::norm(mm.landmarks[i] - (*face)->landmarks[i]), 0, 1e-9);
  EXPECT_EQ(cv::norm(mm.grey, (*face)->grey, cv::NORM_INF), 0);
  for (int i = 0; i < kLandmarkCount68; ++i)
    EXPECT_EQ(mirrored_landmark_index(mirrored_landmark_index(i)), i);
}

// Crop path with injected detector and landmarker.
struct Fakes {
  std::vector<cv::Rect2d> boxes;
  std::optional<std::vector<cv::Point2d>> landmarks;  // in the working image
  int finder_calls = 0, fitter_calls = 0;
  FaceCropAligner aligner(FaceCropOptions o = {}) {
    return FaceCropAligner(
        o,
        [this](const cv::Mat&) -> Result<std::vector<cv::Rect2d>> {
          ++finder_calls;
          return boxes;
        },
        [this](const cv::Mat&,
               const cv::Rect2d&) -> Result<std::optional<std::vector<cv::Point2d>>> {
          ++fitter_calls;
          return landmarks;
        });
  }
};

TEST(FaceCrops, DetectedFaceWithPlausibleLandmarks) {
  Fakes f;
  f.boxes = {cv::Rect2d(10, 10, 140, 140)};
  f.landmarks = moved_face(140, 0, {10, 10});
  auto r = f.aligner().align(noise_image(48, 48));
  ASSERT_TRUE(r && *r);
  EXPECT_EQ((*r)->source, AlignmentSource::kLandmarks);
  EXPECT_EQ((*r)->landmarks.size(), 68u);
}

TEST(FaceCrops, NoDetectionFallsBackToTheCropBoxThenToTheCropGeometry) {
  Fakes f;
  f.landmarks = moved_face(150, 3, {5, 5});
  auto r = f.aligner().align(noise_image(48, 48));
  ASSERT_TRUE(r && *r);
  EXPECT_EQ((*r)->source, AlignmentSource::kLandmarksFromCrop);
  f.landmarks = std::nullopt;
  r = f.aligner().align(noise_image(48, 48));
  ASSERT_TRUE(r && *r);
  EXPECT_EQ((*r)->source, AlignmentSource::kCropGeometry);
  EXPECT_TRUE((*r)->landmarks.empty());
  FaceCropOptions photos;
  photos.assume_crop = false;
  r = f.aligner(photos).align(noise_image(48, 48));
  ASSERT_TRUE(r.has_value());
  EXPECT_FALSE(r->has_value());  // photos: a face must be detected
}

TEST(FaceCrops, ImplausibleLandmarksAreNotUsed) {
  FaceCropOptions o;
  const cv::Rect2d box(0, 0, 160, 160);
  EXPECT_TRUE(plausible_landmarks(moved_face(160, 0, {0, 0}), box, o));
  EXPECT_FALSE(plausible_landmarks(moved_face(160, 60, {80, 0}), box, o));      // rolled 60 deg
  EXPECT_FALSE(plausible_landmarks(moved_face(20, 0, {70, 70}), box, o));       // eyes too close
  EXPECT_FALSE(plausible_landmarks(moved_face(160, 180, {160, 160}), box, o));  // upside down
  Fakes f;
  f.boxes = {cv::Rect2d(0, 0, 160, 160)};
  f.landmarks = moved_face(160, 60, {80, 0});
  auto r = f.aligner().align(noise_image(48, 48));
  ASSERT_TRUE(r && *r);
  EXPECT_EQ((*r)->source, AlignmentSource::kCropGeometry);
}

TEST(FaceCrops, FlatTinyOrEmptyImagesHaveNoFace) {
  Fakes f;
  f.landmarks = moved_face(150, 0, {5, 5});
  auto a = f.aligner();
  for (const cv::Mat& m :
       {cv::Mat(48, 48, CV_8UC1, cv::Scalar(128)), noise_image(12, 12), cv::Mat()}) {
    auto r = a.align(m);
    ASSERT_TRUE(r.has_value());
    EXPECT_FALSE(r->has_value());
  }
  EXPECT_EQ(f.finder_calls, 0);  // rejected before any search
  EXPECT_FALSE(a.align(cv::Mat(48, 48, CV_32FC1, cv::Scalar(0.5))).has_value());
}

}  // namespace
}  // namespace dreamsense::vision
