// The face identity analyser through testing::AnalyzerRunner: nothing without a landmarks entry,
// absent without a face, an enrolled person found, a stranger answered -1 (negative cases), the
// per-track reuse of a result, and clear errors for missing / empty / foreign galleries.
#include "dreamsense/face_identity/face_identity_analyzer.hpp"

#include "dreamsense/perception/face_identity.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/face_tracks.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"
#include "dreamsense/vision/face_alignment.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace dreamsense::face_identity {
namespace {
namespace fs = std::filesystem;

const SensorId kCam = "front.color";

std::vector<cv::Point2d> landmarks() {
  auto lm = vision::mean_face_landmarks(100);
  for (auto& p : lm) p += cv::Point2d(110, 60);
  return lm;
}

// Person `p`'s face: a fixed blurred texture (its "identity") plus a little per-image noise.
cv::Mat person_image(int person, int image) {
  cv::RNG rng(1000 + person);
  cv::Mat base(240, 320, CV_8UC1);
  rng.fill(base, cv::RNG::UNIFORM, 0, 255);
  cv::Mat small;
  cv::resize(base, small, cv::Size(40, 30), 0, 0, cv::INTER_AREA);
  cv::resize(small, base, base.size(), 0, 0, cv::INTER_CUBIC);
  cv::Mat noise(base.size(), CV_8UC1);
  cv::RNG(image + 1).fill(noise, cv::RNG::UNIFORM, 0, 12);
  base += noise;
  cv::Mat bgr;
  cv::cvtColor(base, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

fs::path temp(const std::string& stem) {
  return fs::temp_directory_path() / (stem + std::to_string(::getpid()) + ".yaml");
}

fs::path make_gallery() {
  auto m = identity_method("lbp_tt");
  EXPECT_TRUE(m);
  auto e = IdentityFeatureExtractor::create(*m);
  EXPECT_TRUE(e);
  FaceGallery g(*m, e->weights_hash());
  for (int p = 0; p < 3; ++p)
    for (int i = 0; i < 4; ++i) {
      auto grey = vision::to_grey(person_image(p, i));
      auto face = vision::align_face(*grey, landmarks(), m->alignment);
      EXPECT_TRUE(g.add(p, e->extract(*grey, **face)));
    }
  g.set_name(1, "child");
  const fs::path path = temp("ds_face_gallery_");
  EXPECT_TRUE(g.save(path));
  return path;
}

FaceLandmarks face_landmarks() {
  FaceLandmarks l;
  l.camera = kCam;
  l.image_size = cv::Size(320, 240);
  l.points_px = landmarks();
  return l;
}

class FaceIdentityAnalyzerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { gallery_ = new fs::path(make_gallery()); }
  static void TearDownTestSuite() {
    fs::remove(*gallery_);
    delete gallery_;
  }
  testing::AnalyzerRunner runner(double refresh_s, bool include_names = true) {
    FaceIdentityAnalyzerOptions o;
    o.cameras = {kCam};
    o.gallery = *gallery_;
    o.refresh_s = refresh_s;
    o.include_names = include_names;
    auto a = make_face_identity_analyzer(o);
    EXPECT_TRUE(a) << a.error().message;
    return testing::AnalyzerRunner(std::move(*a));
  }
  // One tick showing `image`; returns the written identity (nullopt: absent).
  std::optional<FaceIdentity> tick(testing::AnalyzerRunner& r, Timestamp t, const cv::Mat& image,
                                   int track = -1) {
    r.preset(keys::kFaceLandmarks, face_landmarks(), t, 0.9f);
    if (track >= 0) {
      FaceTracks tracks;
      tracks.tracks.push_back(FaceTrack{track});
      r.preset(keys::kFaceTracks, tracks, t - Duration::from_ms(40));
    }
    EXPECT_TRUE(r.run(t, {make_frame(kCam, t, 1, ColorImage{image})}));
    auto e = r.output(keys::kFaceIdentity);
    EXPECT_TRUE(e);
    if (!e || !e->present()) return std::nullopt;
    return *e->value;
  }
  static fs::path* gallery_;
};
fs::path* FaceIdentityAnalyzerTest::gallery_ = nullptr;

TEST_F(FaceIdentityAnalyzerTest, NothingWithoutLandmarksAbsentWithoutAFace) {
  auto r = runner(0);
  const Timestamp t = Timestamp::from_seconds(1);
  ASSERT_TRUE(r.run(t, {make_frame(kCam, t, 1, ColorImage{person_image(0, 9)})}));
  EXPECT_TRUE(r.last_writes().empty());
  r.preset_absent(keys::kFaceLandmarks, t + Duration::from_ms(40));
  ASSERT_TRUE(r.run(t + Duration::from_ms(40), {}));
  ASSERT_TRUE(r.output(keys::kFaceIdentity));
  EXPECT_FALSE(r.output(keys::kFaceIdentity)->present());
}

TEST_F(FaceIdentityAnalyzerTest, EnrolledPersonFoundStrangerUnknown) {
  auto r = runner(0);
  Timestamp t = Timestamp::from_seconds(1);
  auto id = tick(r, t, person_image(1, 7));  // an image that was not enrolled
  ASSERT_TRUE(id);
  EXPECT_EQ(id->id, 1);
  EXPECT_EQ(id->name, "child");
  EXPECT_EQ(id->method, "lbp_tt");
  EXPECT_TRUE(id->refreshed);
  id = tick(r, t + Duration::from_ms(40), person_image(2, 8));
  ASSERT_TRUE(id);
  EXPECT_EQ(id->id, 2);
  id = tick(r, t + Duration::from_ms(80), person_image(17, 0));  // never enrolled
  ASSERT_TRUE(id);
  EXPECT_EQ(id->id, -1) << "a stranger must be rejected, score " << id->score;
}

// Privacy: the gallery's name only when asked for (--include-names); the id identifies.
TEST_F(FaceIdentityAnalyzerTest, IdsOnlyUnlessNamesAreIncluded) {
  auto r = runner(0, /*include_names=*/false);
  const auto id = tick(r, Timestamp::from_seconds(1), person_image(1, 7));
  ASSERT_TRUE(id);
  EXPECT_EQ(id->id, 1);
  EXPECT_EQ(id->name, "");
}

TEST_F(FaceIdentityAnalyzerTest, ResultReusedWithinATrackUntilRefresh) {
  auto r = runner(1.0);
  Timestamp t = Timestamp::from_seconds(1);
  auto id = tick(r, t, person_image(0, 5), 3);
  ASSERT_TRUE(id);
  EXPECT_TRUE(id->refreshed);
  EXPECT_EQ(id->track_id, 3);
  id = tick(r, t + Duration::from_ms(400), person_image(0, 6), 3);
  ASSERT_TRUE(id);
  EXPECT_FALSE(id->refreshed) << "same track within refresh_s";
  EXPECT_EQ(id->id, 0);
  id = tick(r, t + Duration::from_ms(440), person_image(2, 6), 4);
  ASSERT_TRUE(id);
  EXPECT_TRUE(id->refreshed) << "a new track is identified at once";
  EXPECT_EQ(id->id, 2);
  id = tick(r, t + Duration::from_ms(1500), person_image(2, 7), 4);
  EXPECT_TRUE(id->refreshed) << "after refresh_s";
}

TEST(FaceIdentityAnalyzer, BadGalleries) {
  FaceIdentityAnalyzerOptions o;
  o.cameras = {kCam};
  EXPECT_FALSE(make_face_identity_analyzer(o)) << "no gallery";
  o.gallery = "/nonexistent/gallery.yaml";
  auto a = make_face_identity_analyzer(o);
  ASSERT_FALSE(a);
  EXPECT_NE(a.error().message.find("/nonexistent/gallery.yaml"), std::string::npos);
  auto m = identity_method("lbp_tt");
  ASSERT_TRUE(m);
  const fs::path empty = temp("ds_face_gallery_empty_");
  ASSERT_TRUE(FaceGallery(*m).save(empty));
  o.gallery = empty;
  a = make_face_identity_analyzer(o);
  ASSERT_FALSE(a) << "an empty gallery identifies nobody";
  EXPECT_NE(a.error().message.find(empty.string()), std::string::npos);
  fs::remove(empty);
  const fs::path corrupt = temp("ds_face_gallery_bad_");
  { std::ofstream(corrupt) << "%YAML:1.0\nformat: something-else\n"; }
  o.gallery = corrupt;
  EXPECT_FALSE(make_face_identity_analyzer(o));
  fs::remove(corrupt);
}

}  // namespace
}  // namespace dreamsense::face_identity
