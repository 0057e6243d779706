#include "dreamsense/perception/face_detection.hpp"

#include "dreamsense/face_detection/camera_selection.hpp"
#include "dreamsense/face_detection/face_detection_analyzer.hpp"
#include "dreamsense/face_detection/face_detector.hpp"
#include "dreamsense/face_detection/face_tracker.hpp"
#include "dreamsense/face_detection/hog_face_detector.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/testing/demo_cache.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cstdio>

#include "demo_frames.hpp"

namespace dreamsense::face_detection {
namespace {

using testing::DemoFrames;
using testing::FaceMetrics;
using testing::kCameras;

// A 3 s demo session (seed 3), generated once for the whole binary (testing/demo_cache.hpp).
const DemoFrames& demo() {
  static const DemoFrames frames = [] {
    auto dir = dreamsense::testing::cached_demo_session("classic_s3_3s",
                                                        testing::face_demo_options(3.0, 3));
    if (!dir) throw std::runtime_error(dir.error().to_string());
    auto r = testing::load_demo(*dir);
    if (!r) throw std::runtime_error(r.error().to_string());
    return std::move(*r);
  }();
  return frames;
}

const cv::Mat& image_of(const MultiFrame& mf, const SensorId& cam) {
  return mf.frame(cam)->as<ColorImage>()->image;
}

FaceDetector make_detector(FaceDetectorOptions o = {}) {
  auto d = FaceDetector::create(o);
  if (!d) throw std::runtime_error(d.error().to_string());
  return std::move(*d);
}

// Runs an analyser over ticks; returns the metrics against the demo truth.
FaceMetrics run_analyzer(Analyzer& a, const DemoFrames& d, const std::vector<MultiFrame>& ticks) {
  Blackboard bb;
  FaceMetrics m;
  for (const MultiFrame& mf : ticks) {
    BlackboardWriter w("face_detection");
    auto s = a.process(mf, bb.snapshot(), w);
    EXPECT_TRUE(s) << s.error().to_string();
    bb.commit(w, mf.stamp);
    const BlackboardView v = bb.snapshot();
    auto det = v.get(keys::kFaceDetections);
    auto sel = v.get(keys::kSelectedCamera);
    std::vector<SensorId> searched;
    for (const auto& [id, f] : mf.frames) searched.push_back(id);
    const bool fresh = det && det->stamp == mf.stamp;
    testing::accumulate(m, d.truth.at(mf.stamp.ns()), searched, fresh ? det->value.get() : nullptr,
                        sel && sel->stamp == mf.stamp ? sel->value.get() : nullptr);
  }
  return m;
}

TEST(FaceDetectorOptions, RejectsBadValuesAndMissingModels) {
  FaceDetectorOptions o;
  EXPECT_TRUE(o.check());
  o.scale_factor = 1.0;
  o.min_neighbors = 0;
  auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("scale_factor"), std::string::npos);
  EXPECT_NE(s.error().message.find("min_neighbors"), std::string::npos);
  FaceDetectorOptions missing;
  missing.frontal_cascade = "/nonexistent/cascade.xml";
  auto d = FaceDetector::create(missing);
  ASSERT_FALSE(d);
  EXPECT_EQ(d.error().code, ErrorCode::kNotFound);
  EXPECT_NE(d.error().message.find("opencv-data"), std::string::npos);
  FaceDetectionAnalyzerOptions ao;
  ao.cameras = {"camera_left", "camera_left"};
  EXPECT_FALSE(make_face_detection_analyzer(ao));
  FaceTrackerOptions t;
  t.full_search_interval = 0;
  EXPECT_FALSE(t.check());
  FaceTrackerOptions narrow;
  narrow.roi_narrow_min_scale = 1.1;  // the narrow range must hold the last size
  EXPECT_FALSE(narrow.check());
  FaceTrackerOptions turned;
  turned.turned_away_search_interval = 0;
  EXPECT_FALSE(turned.check());
  CameraSelectorOptions c;
  c.switch_ticks = 0;
  EXPECT_FALSE(c.check());
}

TEST(FaceDetector, NoFaceGivesAnEmptyList) {
  FaceDetector d = make_detector();
  EXPECT_TRUE(d.detect(cv::Mat()).empty());
  EXPECT_TRUE(d.detect(cv::Mat(960, 1280, CV_8UC3, cv::Scalar(128, 128, 128))).empty());
  cv::Mat noise(960, 1280, CV_8UC3);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  EXPECT_TRUE(d.detect(noise).empty());
  const cv::Mat fruits = cv::imread("/usr/share/doc/opencv-doc/examples/data/fruits.jpg");
  ASSERT_FALSE(fruits.empty()) << "install opencv-doc";
  EXPECT_TRUE(d.detect(fruits).empty());
  cv::Mat big;
  cv::resize(fruits, big, cv::Size(1280, 960));
  EXPECT_TRUE(d.detect(big).empty());
}

TEST(FaceDetector, GreyOddSizedAndUnusableImagesDoNotCrash) {
  FaceDetector d = make_detector();
  const cv::Mat& colour = image_of(demo().ticks[0], "camera_middle");
  cv::Mat grey;
  cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(d.detect(grey).size(), 1u);
  cv::Mat odd;
  cv::resize(colour, odd, cv::Size(1001, 757));
  EXPECT_EQ(d.detect(odd).size(), 1u);
  cv::Mat bgra;
  cv::cvtColor(colour, bgra, cv::COLOR_BGR2BGRA);
  EXPECT_EQ(d.detect(bgra).size(), 1u);
  EXPECT_TRUE(d.detect(cv::Mat(1, 1, CV_8UC1, cv::Scalar(0))).empty());
  EXPECT_TRUE(d.detect(cv::Mat(7, 3001, CV_8UC3, cv::Scalar(0))).empty());
  EXPECT_TRUE(d.detect(cv::Mat(100, 100, CV_16UC1, cv::Scalar(0))).empty());
  EXPECT_TRUE(d.detect(cv::Mat(100, 100, CV_8UC2, cv::Scalar(0))).empty());
  // A search region outside the image or smaller than the cascade window.
  EXPECT_TRUE(d.detect(colour, SearchRegion{cv::Rect(5000, 5000, 100, 100)}).empty());
  EXPECT_TRUE(d.detect(colour, SearchRegion{cv::Rect(600, 450, 10, 10)}).empty());
  EXPECT_EQ(d.frontalness(cv::Mat(), cv::Rect2d(0, 0, 10, 10)), 0.f);
}

TEST(FaceDetector, FindsTheDemoFaceWhereTheTruthIs) {
  FaceDetector d = make_detector();
  const MultiFrame& mf = demo().ticks[0];
  const auto& truth = demo().truth.at(mf.stamp.ns());
  for (const SensorId& cam : kCameras) {
    const auto& t = truth.cameras.at(cam);
    if (!t.visible || std::abs(t.yaw_deg) > 45) continue;
    auto faces = d.detect(image_of(mf, cam));
    ASSERT_EQ(faces.size(), 1u) << cam;
    EXPECT_TRUE(testing::matches(faces[0], t)) << cam;
    EXPECT_GT(faces[0].score, 0.5f);
    EXPECT_EQ(faces[0].view, FaceView::kFrontal);
    EXPECT_GE(faces[0].frontalness, 0.f);
    EXPECT_LE(faces[0].frontalness, 1.f);
  }
}

// The self-calibration's search: the full frame shrunk as always, only face sizes near the last
// one. The cascade windows at those sizes are the full search's, so the box is the same.
TEST(FaceDetector, SizeLimitedSearchAtTheFullFrameScaleKeepsTheFullSearchBox) {
  FaceDetector d = make_detector();
  const MultiFrame& mf = demo().ticks[0];
  const auto& truth = demo().truth.at(mf.stamp.ns());
  int compared = 0;
  for (const SensorId& cam : kCameras) {
    const auto& t = truth.cameras.at(cam);
    if (!t.visible || std::abs(t.yaw_deg) > 45) continue;
    const cv::Mat& image = image_of(mf, cam);
    const auto full = d.detect(image, std::nullopt, false);
    ASSERT_EQ(full.size(), 1u) << cam;
    const double size = full[0].box_px.width;
    const cv::Rect whole(0, 0, image.cols, image.rows);
    const auto limited = d.detect(image, SearchRegion{whole, 0.5 * size, 2.0 * size, false}, false);
    ASSERT_EQ(limited.size(), 1u) << cam;
    EXPECT_EQ(limited[0].box_px, full[0].box_px) << cam;
    EXPECT_EQ(limited[0].score, full[0].score) << cam;
    // Sizes that exclude the face: nothing.
    EXPECT_TRUE(d.detect(image, SearchRegion{whole, 2.5 * size, 4 * size, false}, false).empty())
        << cam;
    ++compared;
  }
  EXPECT_GE(compared, 1);
}

TEST(HogFaceDetector, FindsTheDemoFaceAndNothingInBlankImages) {
  EXPECT_FALSE(HogFaceDetector::create({.min_face_px = 5}));
  auto d = HogFaceDetector::create();
  ASSERT_TRUE(d) << d.error().message;
  const MultiFrame& mf = demo().ticks[0];
  const auto& truth = demo().truth.at(mf.stamp.ns());
  int checked = 0;
  for (const SensorId& cam : kCameras) {
    const auto& t = truth.cameras.at(cam);
    if (!t.visible || std::abs(t.yaw_deg) > 30) continue;
    const cv::Mat& colour = image_of(mf, cam);
    auto faces = d->detect(colour);
    ASSERT_GE(faces.size(), 1u) << cam;
    EXPECT_TRUE(testing::matches(faces[0], t)) << cam;
    cv::Mat grey;
    cv::cvtColor(colour, grey, cv::COLOR_BGR2GRAY);
    EXPECT_GE(d->detect(grey).size(), 1u) << cam;
    ++checked;
  }
  EXPECT_GE(checked, 1);
  EXPECT_TRUE(d->detect(cv::Mat()).empty());
  EXPECT_TRUE(d->detect(cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(128))).empty());
  EXPECT_TRUE(d->detect(cv::Mat(100, 100, CV_16UC1, cv::Scalar(0))).empty());
  EXPECT_TRUE(d->detect(cv::Mat(7, 3001, CV_8UC1, cv::Scalar(0))).empty());
  // A huge image is searched shrunk to max_work_side_px (no crash, no face in a blank one).
  EXPECT_TRUE(d->detect(cv::Mat(6000, 8000, CV_8UC1, cv::Scalar(0))).empty());
}

TEST(FaceDetector, FrontalnessFallsWithYaw) {
  // Over the demo frames: faces within 15 deg of a camera are more frontal than those beyond 30.
  FaceDetector d = make_detector();
  double near_sum = 0, far_sum = 0;
  int near_n = 0, far_n = 0;
  for (size_t i = 0; i < demo().ticks.size(); i += 3) {
    const MultiFrame& mf = demo().ticks[i];
    for (const SensorId& cam : kCameras) {
      const auto& t = demo().truth.at(mf.stamp.ns()).cameras.at(cam);
      if (!t.visible) continue;
      auto faces = d.detect(image_of(mf, cam));
      if (faces.empty() || !testing::matches(faces[0], t)) continue;
      const double yaw = std::abs(t.yaw_deg);
      if (yaw < 15) near_sum += faces[0].frontalness, ++near_n;
      if (yaw > 30) far_sum += faces[0].frontalness, ++far_n;
    }
  }
  ASSERT_GT(near_n, 0);
  ASSERT_GT(far_n, 0);
  std::printf("mean frontalness: |yaw| < 15: %.3f (%d), |yaw| > 30: %.3f (%d)\n", near_sum / near_n,
              near_n, far_sum / far_n, far_n);
  EXPECT_GT(near_sum / near_n, far_sum / far_n + 0.1);
}

TEST(FaceTracker, SearchesAroundTheFaceAndAgreesWithFullSearch) {
  FaceTrackerOptions o;
  FaceTracker tracker(make_detector(), o);
  FaceDetector full = make_detector();
  int roi_frames = 0;
  for (size_t i = 0; i < 20; ++i) {
    const cv::Mat& image = image_of(demo().ticks[i], "camera_middle");
    const TrackedFrameFaces r = tracker.process(image);
    if (i == 0) {
      EXPECT_TRUE(r.full_search);
    }
    roi_frames += !r.full_search;
    const auto reference = full.detect(image);
    ASSERT_EQ(r.faces.size(), reference.size()) << "frame " << i;
    for (size_t k = 0; k < r.faces.size(); ++k)
      EXPECT_GT(box_iou(r.faces[k].box_px, reference[k].box_px), 0.7) << "frame " << i;
  }
  EXPECT_GE(roi_frames, 18);
  // A frame without the face: nothing, then the tracker searches the full frame again.
  const TrackedFrameFaces blank = tracker.process(cv::Mat(960, 1280, CV_8UC3, cv::Scalar(90)));
  EXPECT_TRUE(blank.faces.empty());
  EXPECT_TRUE(blank.full_search);
  EXPECT_TRUE(tracker.process(image_of(demo().ticks[0], "camera_middle")).full_search);
}

TEST(FaceTracker, AFaceThatJumpsInSizeIsFollowedWithoutAFullSearch) {
  // Frame 0 as is, then the same frame magnified 1.4x about the face, three times: beyond the
  // narrow size range (0.8-1.25 of the last size). The narrow pass alone finds the face too
  // small (1.12x: its windows stop at 1.25), so its result is refused when the size moved by
  // more than roi_narrow_max_change, and the wide range finds the new size at once, as the
  // wide-only search (the baseline) does. Neither needs a full-frame search.
  const cv::Mat& image = image_of(demo().ticks[0], "camera_middle");
  const auto faces = make_detector().detect(image);
  ASSERT_FALSE(faces.empty());
  const cv::Rect2d b = faces[0].box_px;
  const cv::Point2d c(b.x + b.width / 2, b.y + b.height / 2);
  cv::Mat magnified;
  cv::warpAffine(image, magnified, cv::getRotationMatrix2D(c, 0, 1.4), image.size());
  for (const bool narrow_first : {false, true}) {
    FaceTrackerOptions o;
    o.roi_narrow_first = narrow_first;
    FaceTracker tracker(make_detector(), o);
    ASSERT_TRUE(tracker.process(image).full_search);
    std::vector<double> ratios;
    for (int i = 0; i < 3; ++i) {
      const TrackedFrameFaces r = tracker.process(magnified);
      EXPECT_FALSE(r.full_search) << "narrow first " << narrow_first << ", frame " << i;
      ASSERT_EQ(r.faces.size(), 1u) << "narrow first " << narrow_first << ", frame " << i;
      ratios.push_back(r.faces[0].box_px.width / b.width);
    }
    EXPECT_NEAR(ratios[0], 1.4, 0.1) << "narrow first " << narrow_first << ": " << ratios[0] << " "
                                     << ratios[1] << " " << ratios[2];
  }
}

TEST(FaceTracker, LostFaceTurnedAwaySearchesTheFullFrameLessOften) {
  // No face in the frame: every frame is a full search, unless the head is known to be turned
  // away from this camera (then every turned_away_search_interval frames).
  const cv::Mat blank(960, 1280, CV_8UC3, cv::Scalar(90, 90, 90));
  FaceTrackerOptions o;
  o.turned_away_yaw_deg = 60;
  o.turned_away_search_interval = 4;
  auto searches = [&](std::optional<double> yaw) {
    FaceTracker tracker(make_detector(), o);
    int n = 0;
    for (int i = 0; i < 12; ++i) {
      const TrackedFrameFaces r = tracker.process(blank, {}, yaw);
      EXPECT_TRUE(r.faces.empty());
      n += r.full_search;
    }
    return n;
  };
  EXPECT_EQ(searches(std::nullopt), 12);
  EXPECT_EQ(searches(30.0), 12);
  EXPECT_EQ(searches(-80.0), 3);  // frames 0, 4, 8
  EXPECT_EQ(searches(170.0), 3);
  o.turned_away_search_interval = 1;  // the baseline
  EXPECT_EQ(searches(-80.0), 12);
}

// A head tilted sideways: the demo frame turned by 35 degrees about the face, beyond the frontal
// cascade's reach. Upright searches alone (the baseline) never find it; with rotated searches
// the lost tracker finds it in its first frame (the full frame rotated by -lost_roll_deg) and
// then follows it in its region rotated by the roll it was found at, without full searches, as
// it tilts 10 degrees further. The boxes are where the upright face's box turns to.
TEST(FaceTracker, RolledFaceIsFoundAndFollowedByRotatedSearches) {
  const cv::Mat& image = image_of(demo().ticks[0], "camera_middle");
  const auto upright = make_detector().detect(image);
  ASSERT_FALSE(upright.empty());
  const cv::Rect2d b = upright[0].box_px;
  const cv::Point2d c(b.x + b.width / 2, b.y + b.height / 2);
  // Turned by -35 deg on screen (clockwise): the eye line then descends to the right, roll +35.
  auto turned = [&](double deg) {
    cv::Mat out;
    cv::warpAffine(image, out, cv::getRotationMatrix2D(c, -deg, 1.0), image.size(),
                   cv::INTER_LINEAR, cv::BORDER_REPLICATE);
    return out;
  };
  const cv::Mat rolled = turned(35), further = turned(45);
  auto found_at_face = [&](const TrackedFrameFaces& r) {
    for (const DetectedFace& f : r.faces)
      if (std::hypot(f.box_px.x + f.box_px.width / 2 - c.x,
                     f.box_px.y + f.box_px.height / 2 - c.y) < 0.25 * b.width)
        return true;
    return false;
  };
  // The sign convention of FaceGuide::roll_deg: this face's eye line descends to the right
  // (roll +35), and the search rotated by +35 finds it where -35 does not.
  FaceDetector detector = make_detector();
  const cv::Rect around(cv::Rect2d(c.x - b.width, c.y - b.height, 2 * b.width, 2 * b.height));
  EXPECT_FALSE(detect_rolled(detector, rolled, around, 35).empty());
  EXPECT_TRUE(detect_rolled(detector, rolled, around, -35).empty());
  FaceTrackerOptions baseline;
  baseline.roll_step_deg = 0;
  baseline.lost_roll_deg = 0;
  FaceTracker plain(make_detector(), baseline);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(found_at_face(plain.process(rolled))) << i;

  FaceTrackerOptions o;
  o.lost_roll_deg = 35;
  FaceTracker tracker(make_detector(), o);
  const TrackedFrameFaces first = tracker.process(rolled);
  EXPECT_TRUE(first.full_search);
  ASSERT_TRUE(found_at_face(first));
  EXPECT_NEAR(first.faces[0].box_px.width, b.width, 0.25 * b.width);
  for (int i = 0; i < 2; ++i) {
    const TrackedFrameFaces r = tracker.process(rolled);
    EXPECT_FALSE(r.full_search) << i;
    EXPECT_TRUE(found_at_face(r)) << i;
  }
  // Ten degrees further: the region at 35 misses it, a step of roll_step_deg finds it.
  const TrackedFrameFaces r = tracker.process(further);
  EXPECT_FALSE(r.full_search);
  EXPECT_TRUE(found_at_face(r));
  // An upright face stays an upright search: same box as the detector's.
  FaceTracker fresh(make_detector(), o);
  const TrackedFrameFaces u = fresh.process(image);
  ASSERT_EQ(u.faces.size(), upright.size());
  EXPECT_GT(box_iou(u.faces[0].box_px, b), 0.99);
}

TEST(FaceTracker, LandmarksRollIsTheEyeLineAngle) {
  std::vector<cv::Point2d> points(68, cv::Point2d(0, 0));
  for (size_t i = 36; i < 42; ++i) points[i] = {100, 200};  // subject's right eye (image left)
  for (size_t i = 42; i < 48; ++i) points[i] = {160, 200};
  EXPECT_NEAR(eye_line_roll_deg(points), 0, 1e-9);
  for (size_t i = 42; i < 48; ++i) points[i] = {160, 260};  // descends to the right
  EXPECT_NEAR(eye_line_roll_deg(points), 45, 1e-9);
  EXPECT_EQ(eye_line_roll_deg(std::vector<cv::Point2d>(10)), 0);
  FaceTrackerOptions bad;
  bad.lost_roll_search_interval = 0;
  EXPECT_FALSE(bad.check());
  bad = {};
  bad.roll_step_deg = -1;
  EXPECT_FALSE(bad.check());
}

TEST(FaceTracker, BoxOnExtentPlacesTheBoxItWasLearnedFrom) {
  const cv::Rect2d box(100, 80, 60, 70), extent(104, 95, 50, 52);
  const auto r = box_on_extent(box, extent);
  ASSERT_TRUE(r);
  const cv::Rect2d back = place_box(*r, extent);
  EXPECT_NEAR(back.x, box.x, 1e-9);
  EXPECT_NEAR(back.y, box.y, 1e-9);
  EXPECT_NEAR(back.width, box.width, 1e-9);
  EXPECT_NEAR(back.height, box.height, 1e-9);
  // The same relation on an extent moved by (10, -5) and twice as large: the box is twice as
  // large, and its offset from the extent's centre, (1, -6) px, doubles too.
  const cv::Rect2d moved = place_box(*r, cv::Rect2d(139 - 50, 116 - 52, 100, 104));
  EXPECT_NEAR(moved.width, 120, 1e-9);
  EXPECT_NEAR(moved.height, 140, 1e-9);
  EXPECT_NEAR(moved.x + moved.width / 2, 139 + 2, 1e-9);
  EXPECT_NEAR(moved.y + moved.height / 2, 116 - 12, 1e-9);
  EXPECT_FALSE(box_on_extent(box, cv::Rect2d(1, 1, 0, 5)));
}

// The guide a landmark fit of the previous frame would give: the face's last box moved by `shift`.
std::vector<FaceGuide> moved_guides(const TrackedFrameFaces& last, cv::Point2d shift) {
  std::vector<FaceGuide> g;
  for (const DetectedFace& f : last.faces) g.push_back({f.box_px, f.box_px + shift});
  return g;
}

TEST(FaceTracker, GuidedFramesSkipTheCascadeBetweenSearches) {
  FaceTrackerOptions o;
  o.cascade_interval = 3;
  o.full_search_interval = 7;  // a periodic full search at frame 7 (a guided frame otherwise)
  FaceTracker tracker(make_detector(), o);
  TrackedFrameFaces last;
  std::string pattern;
  for (size_t i = 0; i < 10; ++i) {
    const cv::Mat& image = image_of(demo().ticks[i], "camera_middle");
    const std::vector<FaceGuide> guides = moved_guides(last, {2, -1});
    const TrackedFrameFaces r = tracker.process(image, {}, std::nullopt, guides);
    ASSERT_FALSE(r.faces.empty()) << "frame " << i;
    pattern += r.full_search ? 'F' : r.guided ? 'G' : 'S';
    if (r.guided) {
      // Placed where the guide says, with the face's last score and view.
      ASSERT_EQ(r.faces.size(), last.faces.size());
      EXPECT_EQ(r.faces[0].box_px, guides[0].box) << "frame " << i;
      EXPECT_EQ(r.faces[0].score, last.faces[0].score) << "frame " << i;
      EXPECT_EQ(r.faces[0].view, last.faces[0].view) << "frame " << i;
    }
    last = r;
  }
  // A cascade search at least every third frame; the periodic full search is never skipped.
  EXPECT_EQ(pattern, "FGGSGGSFGG");
}

TEST(FaceTracker, UnusableGuidesLeaveTheCascadeSearching) {
  FaceTrackerOptions o;
  o.cascade_interval = 4;
  auto searched = [&](auto make_guides) {
    FaceTracker tracker(make_detector(), o);
    TrackedFrameFaces last;
    int guided = 0;
    for (size_t i = 0; i < 6; ++i) {
      last = tracker.process(image_of(demo().ticks[i], "camera_middle"), {}, std::nullopt,
                             make_guides(last));
      EXPECT_FALSE(last.faces.empty()) << "frame " << i;
      guided += last.guided;
    }
    return guided;
  };
  EXPECT_EQ(searched([](const TrackedFrameFaces& l) { return moved_guides(l, {3, 3}); }), 4);
  // No guide (no landmarks), one far from the face (IoU < guide_min_iou), one made from
  // another box than the tracker returned: every frame is searched.
  EXPECT_EQ(searched([](const TrackedFrameFaces&) { return std::vector<FaceGuide>{}; }), 0);
  EXPECT_EQ(searched([](const TrackedFrameFaces& l) { return moved_guides(l, {80, 0}); }), 0);
  EXPECT_EQ(searched([](const TrackedFrameFaces& l) {
              auto g = moved_guides(l, {0, 0});
              for (FaceGuide& x : g) x.tracked_box.x += 20;
              return g;
            }),
            0);
  // The baseline interval 1 ignores guides.
  o.cascade_interval = 1;
  EXPECT_EQ(searched([](const TrackedFrameFaces& l) { return moved_guides(l, {3, 3}); }), 0);
  o.cascade_interval = 0;
  EXPECT_FALSE(o.check());
  o.cascade_interval = 2;
  o.guide_min_iou = 0;
  EXPECT_FALSE(o.check());
}

TEST(FaceTracker, KnownFrontalnessSkipsTheProxyOnlyForThatFace) {
  // Two trackers on the same frames: one estimates the proxy for every face, the other is given
  // the frontalness of the best face on odd frames. Detections must be identical; the given value
  // must be used as is; a frame without a given value gets a fresh proxy estimate.
  FaceTrackerOptions o;
  o.frontalness_interval = 2;
  FaceTracker proxy(make_detector(), o), given(make_detector(), o);
  FaceDetector reference = make_detector();
  int skipped = 0;
  for (size_t i = 0; i < 12; ++i) {
    const cv::Mat& image = image_of(demo().ticks[i], "camera_middle");
    const bool known = i % 2 == 1;
    KnownFrontalness k = [&](const std::vector<DetectedFace>& faces, size_t index) {
      EXPECT_LT(index, faces.size());
      return known && index == 0 ? std::optional<float>(0.25f) : std::nullopt;
    };
    const TrackedFrameFaces a = proxy.process(image);
    const TrackedFrameFaces b = given.process(image, k);
    ASSERT_EQ(a.full_search, b.full_search) << "frame " << i;
    ASSERT_EQ(a.faces.size(), b.faces.size()) << "frame " << i;
    ASSERT_FALSE(b.faces.empty()) << "frame " << i;
    for (size_t f = 0; f < a.faces.size(); ++f) {
      EXPECT_EQ(a.faces[f].box_px, b.faces[f].box_px) << "frame " << i;
      EXPECT_EQ(a.faces[f].score, b.faces[f].score) << "frame " << i;
    }
    if (known) {
      EXPECT_EQ(b.faces[0].frontalness, 0.25f) << "frame " << i;
      ++skipped;
    } else {
      // After a known value the track holds no proxy estimate: this frame estimates afresh.
      EXPECT_EQ(b.faces[0].frontalness, reference.frontalness(image, b.faces[0].box_px))
          << "frame " << i;
    }
  }
  EXPECT_EQ(skipped, 6);
}

DetectedFace face(float score, float frontalness) {
  return DetectedFace{cv::Rect2d(100, 100, 150, 150), score, FaceView::kFrontal, frontalness};
}
FaceDetections dets(std::map<SensorId, std::vector<DetectedFace>> faces) {
  FaceDetections d;
  for (auto& [id, f] : faces) d.cameras[id].faces = f;
  return d;
}

TEST(CameraSelector, HysteresisAndImmediateFallback) {
  CameraSelectorOptions o;
  o.switch_margin = 0.05;
  o.switch_ticks = 3;
  CameraSelector s(o);
  EXPECT_FALSE(s.update(dets({})));
  EXPECT_FALSE(s.update(dets({{"camera_left", {}}, {"camera_right", {}}})));
  auto a = s.update(dets({{"camera_left", {face(0.9f, 0.8f)}}, {"camera_middle", {}}}));
  ASSERT_TRUE(a);
  EXPECT_EQ(a->camera, "camera_left");
  EXPECT_NEAR(a->quality, 0.8, 1e-6);
  // camera_middle is better by more than the margin: it takes over on the third tick only.
  for (int k = 0; k < 3; ++k) {
    auto r = s.update(dets({{"camera_left", {face(0.9f, 0.8f)}},
                            {"camera_middle", {face(0.3f, 0.1f), face(0.95f, 0.95f)}}}));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->camera, k < 2 ? "camera_left" : "camera_middle") << k;
    if (k == 2) {
      EXPECT_EQ(r->face_index, 1u);
    }
  }
  // Better, but within the margin: no switch.
  for (int k = 0; k < 5; ++k)
    EXPECT_EQ(s.update(dets({{"camera_left", {face(0.95f, 0.92f)}},
                             {"camera_middle", {face(0.95f, 0.9f)}}}))
                  ->camera,
              "camera_middle");
  // The selected camera loses its face (or its frame): the best other camera at once.
  EXPECT_EQ(s.update(dets({{"camera_left", {face(0.5f, 0.5f)}}, {"camera_middle", {}}}))->camera,
            "camera_left");
  EXPECT_EQ(s.update(dets({{"camera_right", {face(0.5f, 0.5f)}}}))->camera, "camera_right");
}

TEST(CameraSelector, HeadYawHintsOverrideTheProxy) {
  CameraSelectorOptions o;
  o.yaw_switch_margin = 0.02;
  o.yaw_switch_ticks = 1;
  CameraSelector s(o);
  const cv::Rect2d box(100, 100, 150, 150);
  // The proxy prefers camera_left; the head yaw says camera_middle is the frontal one.
  auto d = dets({{"camera_left", {face(0.9f, 0.9f)}}, {"camera_middle", {face(0.9f, 0.5f)}}});
  std::vector<HeadYawHint> hints{{"camera_left", box, 30.0}, {"camera_middle", box, 5.0}};
  auto r = s.update(d, hints);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->camera, "camera_middle");
  EXPECT_NEAR(r->quality, 1.0 - 5.0 / 90, 1e-6);
  // 1 deg better is within the yaw margin (1.8 deg): no switch; 4 deg better switches at once.
  hints = {{"camera_left", box, 4.0}, {"camera_middle", box, 5.0}};
  EXPECT_EQ(s.update(d, hints)->camera, "camera_middle");
  hints = {{"camera_left", box, -1.0}, {"camera_middle", box, 5.0}};
  EXPECT_EQ(s.update(d, hints)->camera, "camera_left");
  // A hint for another box (another person) does not apply to this face.
  CameraSelector fresh(o);
  hints = {{"camera_middle", cv::Rect2d(400, 100, 150, 150), 0.0}};
  EXPECT_EQ(fresh.update(d, hints)->camera, "camera_left");
}

TEST(FaceDetectionAnalyzer, DemoRecallFalsePositivesAndCameraSelection) {
  auto a = make_face_detection_analyzer();
  ASSERT_TRUE(a) << a.error().to_string();
  const auto t0 = std::chrono::steady_clock::now();
  const FaceMetrics m = run_analyzer(**a, demo(), demo().ticks);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
      demo().ticks.size();
  std::printf(
      "3 s demo (seed 3): recall(|yaw|<=45) %.4f (%d/%d), false-positive frames %.4f (%d/%d), "
      "camera selection exact %.4f, within %d deg %.4f (%d ticks), %.1f ms/tick\n",
      m.recall(), m.hits, m.positives, m.false_positive_rate(), m.fp_frames, m.camera_frames,
      m.selection_exact_rate(), 10, m.selection_accuracy(), m.selection_ticks, ms);
  EXPECT_GE(m.recall(), 0.98);
  EXPECT_LE(m.false_positive_rate(), 0.01);
  EXPECT_GE(m.selection_accuracy(), 0.95);
}

TEST(FaceDetectionAnalyzer, ParallelAndSerialGiveTheSameResult) {
  FaceDetectionAnalyzerOptions o;
  o.parallel = true;
  auto par = make_face_detection_analyzer(o);
  o.parallel = false;
  auto ser = make_face_detection_analyzer(o);
  ASSERT_TRUE(par && ser);
  Blackboard b1, b2;
  for (size_t i = 0; i < 30; ++i) {
    const MultiFrame& mf = demo().ticks[i];
    BlackboardWriter w1("p"), w2("s");
    ASSERT_TRUE((*par)->process(mf, b1.snapshot(), w1));
    ASSERT_TRUE((*ser)->process(mf, b2.snapshot(), w2));
    b1.commit(w1, mf.stamp);
    b2.commit(w2, mf.stamp);
    auto d1 = b1.snapshot().get(keys::kFaceDetections);
    auto d2 = b2.snapshot().get(keys::kFaceDetections);
    ASSERT_TRUE(d1 && d2 && d1->present() && d2->present());
    ASSERT_EQ(d1->value->cameras.size(), d2->value->cameras.size());
    for (const auto& [id, c] : d1->value->cameras) {
      const auto& c2 = d2->value->cameras.at(id);
      ASSERT_EQ(c.faces.size(), c2.faces.size());
      for (size_t k = 0; k < c.faces.size(); ++k) {
        EXPECT_EQ(c.faces[k].box_px, c2.faces[k].box_px);
        EXPECT_EQ(c.faces[k].score, c2.faces[k].score);
        EXPECT_EQ(c.faces[k].frontalness, c2.faces[k].frontalness);
      }
    }
    EXPECT_EQ(b1.snapshot().get(keys::kSelectedCamera)->value->camera,
              b2.snapshot().get(keys::kSelectedCamera)->value->camera);
  }
}

TEST(FaceDetectionAnalyzer, HeadYawHintReplacesTheProxyWithoutChangingDetections) {
  // camera_middle calibrated (pinhole at the world origin), a head pose that projects into its
  // face, turned 20 deg: that face's frontalness comes from the yaw (no proxy), every box and
  // score is as without the pose, and the other cameras keep the proxy.
  CameraModel m;
  m.image_size = cv::Size(1280, 960);
  m.K = cv::Matx33d(1000, 0, 640, 0, 1000, 480, 0, 0, 1);
  FaceDetectionAnalyzerOptions o;
  o.camera_models["camera_middle"] = m;
  auto hinted = make_face_detection_analyzer(o);
  auto plain = make_face_detection_analyzer();
  ASSERT_TRUE(hinted && plain);
  const double yaw = 20;
  Blackboard b1, b2;
  int with_hint = 0;
  for (size_t i = 0; i < 12; ++i) {
    const MultiFrame& mf = demo().ticks[i];
    BlackboardWriter w2("plain");
    ASSERT_TRUE((*plain)->process(mf, b2.snapshot(), w2));
    b2.commit(w2, mf.stamp);
    const auto d2 = b2.snapshot().get(keys::kFaceDetections);
    ASSERT_TRUE(d2 && d2->present());
    const auto& middle = d2->value->cameras.at("camera_middle").faces;
    ASSERT_FALSE(middle.empty());
    // Head pose of the previous tick: in the middle of the best face of camera_middle.
    const cv::Point2d c(middle[0].box_px.x + middle[0].box_px.width / 2,
                        middle[0].box_px.y + middle[0].box_px.height / 2);
    HeadPose pose;
    pose.position_world_m = cv::Vec3d((c.x - 640) / 1000, (c.y - 480) / 1000, 1.0);
    const double r = yaw * CV_PI / 180;
    pose.gaze_direction_world = cv::Vec3d(-std::sin(r), 0, -std::cos(r));
    BlackboardWriter wp("head_pose");
    wp.set(keys::kHeadPose, pose, mf.stamp - Duration::from_ms(40), 1.f);
    b1.commit(wp, mf.stamp - Duration::from_ms(40));
    BlackboardWriter w1("hinted");
    ASSERT_TRUE((*hinted)->process(mf, b1.snapshot(), w1));
    b1.commit(w1, mf.stamp);
    const auto d1 = b1.snapshot().get(keys::kFaceDetections);
    ASSERT_TRUE(d1 && d1->present());
    for (const auto& [id, cam] : d2->value->cameras) {
      const auto& faces = d1->value->cameras.at(id).faces;
      // The child's face is marked where the pose projects (the calibrated camera only).
      EXPECT_EQ(d1->value->cameras.at(id).head_face,
                id == "camera_middle" ? std::optional<size_t>(0) : std::nullopt)
          << id << " tick " << i;
      EXPECT_FALSE(cam.head_face) << "no pose, no head face: " << id;
      ASSERT_EQ(faces.size(), cam.faces.size()) << id << " tick " << i;
      for (size_t k = 0; k < faces.size(); ++k) {
        EXPECT_EQ(faces[k].box_px, cam.faces[k].box_px) << id << " tick " << i;
        EXPECT_EQ(faces[k].score, cam.faces[k].score) << id << " tick " << i;
        if (id == "camera_middle" && k == 0) {
          EXPECT_FLOAT_EQ(faces[k].frontalness, frontalness_from_yaw(yaw)) << "tick " << i;
          ++with_hint;
        } else {
          EXPECT_EQ(faces[k].frontalness, cam.faces[k].frontalness) << id << " tick " << i;
        }
      }
    }
  }
  EXPECT_EQ(with_hint, 12);
}

TEST(FaceDetectionAnalyzer, HeadYawIsExtrapolatedToTheCurrentTick) {
  // The head turns 3 deg per 40-ms frame; the pose on the blackboard is a frame old. With
  // prediction the face is rated at the current tick's yaw (last + 3), without at the last one.
  CameraModel m;
  m.image_size = cv::Size(1280, 960);
  m.K = cv::Matx33d(1000, 0, 640, 0, 1000, 480, 0, 0, 1);
  for (bool predict : {true, false}) {
    FaceDetectionAnalyzerOptions o;
    o.camera_models["camera_middle"] = m;
    o.predict_head_yaw = predict;
    auto a = make_face_detection_analyzer(o);
    ASSERT_TRUE(a);
    Blackboard bb;
    for (size_t i = 0; i < 6; ++i) {
      const MultiFrame& mf = demo().ticks[i];
      const Timestamp pose_stamp = mf.stamp - Duration::from_ms(40);
      HeadPose pose;
      pose.frame_stamp = pose_stamp;
      const double last_yaw = 3.0 * static_cast<double>(i);
      const double r = last_yaw * CV_PI / 180;
      pose.gaze_direction_world = cv::Vec3d(-std::sin(r), 0, -std::cos(r));
      // Where the face of camera_middle is (its detections do not depend on the pose).
      if (i > 0) {
        const auto prev = bb.snapshot().get(keys::kFaceDetections);
        ASSERT_TRUE(prev && prev->present());
        const cv::Rect2d box = prev->value->cameras.at("camera_middle").faces.at(0).box_px;
        pose.position_world_m = cv::Vec3d((box.x + box.width / 2 - 640) / 1000,
                                          (box.y + box.height / 2 - 480) / 1000, 1.0);
        BlackboardWriter wp("head_pose");
        wp.set(keys::kHeadPose, pose, pose_stamp, 1.f);
        bb.commit(wp, pose_stamp);
      }
      BlackboardWriter w("face_detection");
      ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
      bb.commit(w, mf.stamp);
      if (i < 2) continue;  // the first poses: nothing to extrapolate from yet
      const auto d = bb.snapshot().get(keys::kFaceDetections);
      ASSERT_TRUE(d && d->present());
      const float got = d->value->cameras.at("camera_middle").faces.at(0).frontalness;
      const double expected_yaw = predict ? last_yaw + 3.0 : last_yaw;
      EXPECT_NEAR(got, frontalness_from_yaw(expected_yaw), 1e-4)
          << "tick " << i << (predict ? " (predicted)" : " (last pose)");
    }
  }
  FaceDetectionAnalyzerOptions bad;
  bad.max_yaw_prediction_deg = -1;
  EXPECT_FALSE(bad.check());
}

TEST(FaceDetectionAnalyzer, MissingCameraNoFramesAndNoFaces) {
  auto a = make_face_detection_analyzer();
  ASSERT_TRUE(a);
  EXPECT_EQ((*a)->contract().optional_inputs, kCameras);
  Blackboard bb;
  auto step = [&](const MultiFrame& mf) {
    BlackboardWriter w("face_detection");
    auto s = (*a)->process(mf, bb.snapshot(), w);
    EXPECT_TRUE(s);
    const bool wrote = !w.empty();
    bb.commit(w, mf.stamp);
    return wrote;
  };
  // No camera frame in the tick: nothing written.
  MultiFrame empty;
  empty.stamp = Timestamp::from_ns(0);
  EXPECT_FALSE(step(empty));
  // camera_middle missing for 20 ticks: never listed, no face made up for it; the others go on.
  for (size_t i = 0; i < 40; ++i) {
    MultiFrame mf = demo().ticks[i];
    const bool drop = i >= 5 && i < 25;
    if (drop) mf.frames.erase("camera_middle");
    ASSERT_TRUE(step(mf));
    auto det = bb.snapshot().get(keys::kFaceDetections);
    ASSERT_TRUE(det && det->present());
    EXPECT_EQ(det->value->cameras.count("camera_middle"), drop ? 0u : 1u) << i;
    auto sel = bb.snapshot().get(keys::kSelectedCamera);
    ASSERT_TRUE(sel && sel->present());
    if (drop) {
      EXPECT_NE(sel->value->camera, "camera_middle");
    }
    for (const auto& [id, c] : det->value->cameras) {
      EXPECT_EQ(c.frame_stamp, mf.stamp);
      EXPECT_EQ(c.image_size, cv::Size(1280, 960));
    }
  }
  // Frames without any face: absent entries (not errors).
  MultiFrame blank;
  blank.stamp = Timestamp::from_ns(10'000'000'000);
  for (size_t k = 0; k < kCameras.size(); ++k)
    blank.frames[kCameras[k]] =
        make_frame(kCameras[k], blank.stamp, 1000,
                   ColorImage{cv::Mat(960, 1280, CV_8UC3, cv::Scalar(60, 90, 120))});
  ASSERT_TRUE(step(blank));
  auto det = bb.snapshot().get(keys::kFaceDetections);
  ASSERT_TRUE(det);
  EXPECT_FALSE(det->present());
  EXPECT_FALSE(bb.snapshot().get(keys::kSelectedCamera)->present());
  // A non-colour stream under a camera id is a wiring error.
  MultiFrame wrong;
  wrong.stamp = Timestamp::from_ns(11'000'000'000);
  wrong.frames["camera_left"] = make_frame("camera_left", wrong.stamp, 0, Skeleton{});
  BlackboardWriter w("face_detection");
  auto s = (*a)->process(wrong, bb.snapshot(), w);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
}

TEST(FaceDetectionAnalyzer, LandmarkFitsOfTheLastFramePlaceTheFaceBetweenSearches) {
  // cascade_interval 3. After each tick a "fit" of camera_middle's face is put on the
  // blackboard: points around the box's centre (moved by `shift` in frame 1). The fit of a
  // searched frame teaches how the box sits on the points, so the next frame gets the same box;
  // the fit of a guided frame moves the next box by the points' motion. Tick 4's fit names
  // another frame, so tick 5 is searched. Ticks: 0 full, 1 guided (= box 0), 2 guided (box 1 +
  // shift), 3 searched, 4 guided (= box 3), 5 searched.
  FaceDetectionAnalyzerOptions o;
  o.tracker.cascade_interval = 3;
  auto a = make_face_detection_analyzer(o);
  ASSERT_TRUE(a);
  const auto contract = (*a)->contract();
  EXPECT_NE(std::find(contract.reads_previous.begin(), contract.reads_previous.end(),
                      keys::kFaceLandmarks.name),
            contract.reads_previous.end());
  const cv::Point2d shift(3.25, 2.5);  // fractions: a cascade box never lands on it
  Blackboard bb;
  cv::Rect2d previous;
  for (size_t i = 0; i < 6; ++i) {
    const MultiFrame& mf = demo().ticks[i];
    BlackboardWriter w("face_detection");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, mf.stamp);
    const auto d = bb.snapshot().get(keys::kFaceDetections);
    ASSERT_TRUE(d && d->present());
    const CameraFaces& middle = d->value->cameras.at("camera_middle");
    ASSERT_FALSE(middle.faces.empty());
    const cv::Rect2d box = middle.faces[0].box_px;
    auto near = [](const cv::Rect2d& x, const cv::Rect2d& y) {
      return std::abs(x.x - y.x) + std::abs(x.y - y.y) + std::abs(x.width - y.width) +
                 std::abs(x.height - y.height) <
             1e-6;
    };
    if (i == 1 || i == 4) {
      EXPECT_TRUE(near(box, previous)) << "tick " << i << ": " << box << " " << previous;
    }
    if (i == 2) {
      EXPECT_TRUE(near(box, previous + shift)) << box << " " << previous;
    }
    if (i == 5) {
      EXPECT_FALSE(near(box, previous))
          << "tick 5 must be searched (tick 4's fit is of another frame)";
    }
    previous = box;
    // The fit of this frame, as face_landmarks would write it.
    FaceLandmarks fit;
    fit.camera = "camera_middle";
    fit.frame_stamp = middle.frame_stamp;
    fit.frame_sequence = i == 4 ? middle.frame_sequence + 100 : middle.frame_sequence;
    fit.box_px = box;
    // The face moved by `shift` since frame 1 was placed (and nowhere else).
    const cv::Point2d c = cv::Point2d(box.x + box.width / 2, box.y + box.height / 2) +
                          (i == 1 ? shift : cv::Point2d());
    for (int k = 0; k < 68; ++k) {
      const double t = 2 * CV_PI * k / 68;
      fit.points_px.push_back(
          c + cv::Point2d(0.4 * box.width * std::cos(t), 0.4 * box.height * std::sin(t)));
    }
    BlackboardWriter lw("face_landmarks");
    lw.set(keys::kFaceLandmarks, fit, mf.stamp, 1.f);
    lw.set(keys::kFaceLandmarkViews, FaceLandmarkViews{}, mf.stamp, 1.f);
    bb.commit(lw, mf.stamp);
  }
}

TEST(FaceDetectionAnalyzer, RepeatedFrameIsNotSearchedAgain) {
  auto a = make_face_detection_analyzer();
  ASSERT_TRUE(a);
  Blackboard bb;
  MultiFrame mf = demo().ticks[0];
  BlackboardWriter w1("f");
  ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w1));
  bb.commit(w1, mf.stamp);
  auto first = *bb.snapshot().get(keys::kFaceDetections)->value;
  mf.stamp = mf.stamp + Duration::from_ms(33);  // a faster pipeline clock, same camera frames
  BlackboardWriter w2("f");
  ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w2));
  bb.commit(w2, mf.stamp);
  auto second = *bb.snapshot().get(keys::kFaceDetections)->value;
  for (const auto& [id, c] : first.cameras) {
    ASSERT_EQ(c.faces.size(), second.cameras.at(id).faces.size());
    for (size_t k = 0; k < c.faces.size(); ++k)
      EXPECT_EQ(c.faces[k].box_px, second.cameras.at(id).faces[k].box_px);
  }
}

}  // namespace
}  // namespace dreamsense::face_detection
