// face_landmarks: DlibLandmarker unit tests, the analyser's blackboard behaviour, and landmark
// sanity on a 3 s demo session (eye landmarks vs truth eyes_px).

#include "dreamsense/perception/face_landmarks.hpp"

#include "dreamsense/face_landmarks/face_landmarks_analyzer.hpp"
#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/perception/face_detection.hpp"
#include "dreamsense/sim/face_renderer.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"
#include "dreamsense/vision/face_api_net.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <dlib/image_processing/shape_predictor.h>
#include <dlib/opencv/cv_image.h>
#include <fstream>
#include <iostream>

#include "demo_face.hpp"

namespace dreamsense::face_landmarks {
namespace {

// The 100 MB model is loaded once per test binary (the process's shared one).
std::shared_ptr<const Landmarker> shared_landmarker() {
  auto r = shared_dlib_landmarker();
  if (!r) throw std::runtime_error(r.error().to_string());
  return *r;
}

DlibLandmarkerOptions float_leaves() {
  DlibLandmarkerOptions o;
  o.quantized_leaves = false;
  return o;
}

// dlib's float leaves (DlibLandmarkerOptions::quantized_leaves false), the bit-exact baseline.
std::shared_ptr<const Landmarker> float_landmarker() {
  auto r = shared_dlib_landmarker(float_leaves());
  if (!r) throw std::runtime_error(r.error().to_string());
  return *r;
}

const sim::PlanarFaceOptions kPortrait;

cv::Mat portrait() { return cv::imread(kPortrait.portrait.string(), cv::IMREAD_COLOR); }

TEST(DlibLandmarkerOptions, CheckListsBadFields) {
  DlibLandmarkerOptions o;
  o.refit_passes = -1;
  o.min_box_px = 1;
  auto s = o.check();
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("refit_passes"), std::string::npos);
  EXPECT_NE(s.error().message.find("min_box_px"), std::string::npos);
  EXPECT_TRUE(DlibLandmarkerOptions{}.check());
}

TEST(DlibLandmarker, MissingModelNamesFileAndPackage) {
  DlibLandmarkerOptions o;
  o.model = "/nonexistent/shape_predictor_68_face_landmarks.dat";
  auto r = make_dlib_landmarker(o);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
  EXPECT_NE(r.error().message.find("/nonexistent/shape_predictor_68"), std::string::npos);
  EXPECT_NE(r.error().message.find("libdlib-data"), std::string::npos);
}

TEST(DlibLandmarker, PortraitEyesAtHandMeasuredIrises) {
  const cv::Mat img = portrait();
  ASSERT_FALSE(img.empty());
  auto l = shared_landmarker();
  EXPECT_EQ(l->point_count(), kFaceLandmarkCount);
  for (bool grey : {false, true}) {
    cv::Mat in = img;
    if (grey) cv::cvtColor(img, in, cv::COLOR_BGR2GRAY);
    auto r = l->fit(in, kPortrait.face_region_px);
    ASSERT_TRUE(r);
    ASSERT_TRUE(r->has_value());
    FaceLandmarks lm;
    lm.points_px = **r;
    ASSERT_EQ(lm.points_px.size(), 68u);
    // Eye-contour centroids vs the irises measured by hand (sim/face_renderer.hpp).
    EXPECT_LT(cv::norm(lm.right_eye_px() - kPortrait.right_eye_px), 3.0) << "grey " << grey;
    EXPECT_LT(cv::norm(lm.left_eye_px() - kPortrait.left_eye_px), 3.0) << "grey " << grey;
    // Nose tip below the eyes, mouth below the nose.
    EXPECT_GT(lm.points_px[30].y, lm.right_eye_px().y + 10);
    EXPECT_GT(lm.points_px[57].y, lm.points_px[30].y + 5);
  }
}

// Reference: dlib's cascade exactly as shape_predictor::operator() runs it (`shape +=
// tree(...)`, one tree after the other), without the final rounding, plus the box re-derivation
// of DlibLandmarkerOptions::refit_passes. The landmarker's prefetching evaluation must match it
// bit for bit.
struct ReferenceCascade {
  dlib::matrix<float, 0, 1> initial_shape;
  std::vector<std::vector<dlib::impl::regression_tree>> forests;
  std::vector<std::vector<unsigned long>> anchor_idx;
  std::vector<std::vector<dlib::vector<float, 2>>> deltas;

  ReferenceCascade() {
    std::ifstream in(DlibLandmarkerOptions{}.model, std::ios::binary);
    int version = 0;
    dlib::deserialize(version, in);
    dlib::deserialize(initial_shape, in);
    dlib::deserialize(forests, in);
    dlib::deserialize(anchor_idx, in);
    dlib::deserialize(deltas, in);
  }
  template <typename Image>
  std::vector<cv::Point2d> predict(const Image& img, const cv::Rect2d& b) const {
    const dlib::rectangle rect(std::lround(b.x), std::lround(b.y), std::lround(b.x + b.width - 1),
                               std::lround(b.y + b.height - 1));
    dlib::matrix<float, 0, 1> shape = initial_shape;
    std::vector<float> values;
    for (unsigned long iter = 0; iter < forests.size(); ++iter) {
      dlib::impl::extract_feature_pixel_values(img, rect, shape, initial_shape, anchor_idx[iter],
                                               deltas[iter], values);
      unsigned long leaf = 0;
      for (const auto& tree : forests[iter]) shape += tree(values, leaf);
    }
    const dlib::point_transform_affine to_img = dlib::impl::unnormalizing_tform(rect);
    std::vector<cv::Point2d> out(shape.size() / 2);
    for (size_t i = 0; i < out.size(); ++i) {
      const dlib::vector<double, 2> p = to_img(dlib::impl::location(shape, i));
      out[i] = {p.x(), p.y()};
    }
    return out;
  }
  template <typename Image>
  std::vector<cv::Point2d> fit(const Image& img, cv::Rect2d box) const {
    double mx0 = 1e300, my0 = 1e300, mx1 = -1e300, my1 = -1e300;
    for (long i = 0; i < initial_shape.size() / 2; ++i) {
      mx0 = std::min<double>(mx0, initial_shape(2 * i)),
      mx1 = std::max<double>(mx1, initial_shape(2 * i));
      my0 = std::min<double>(my0, initial_shape(2 * i + 1)),
      my1 = std::max<double>(my1, initial_shape(2 * i + 1));
    }
    std::vector<cv::Point2d> pts = predict(img, box);
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
    for (const cv::Point2d& p : pts) {
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
      x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
    }
    const double w = (x1 - x0) / (mx1 - mx0), h = (y1 - y0) / (my1 - my0);
    box = cv::Rect2d(x0 - mx0 * w, y0 - my0 * h, w, h);
    return predict(img, box);
  }
};

TEST(DlibLandmarker, PrefetchingCascadeMatchesDlibExactly) {
  ASSERT_EQ(DlibLandmarkerOptions{}.refit_passes, 1);  // what ReferenceCascade::fit does
  const ReferenceCascade ref;
  auto l = float_landmarker();
  const cv::Mat img = portrait();
  ASSERT_FALSE(img.empty());
  cv::Mat grey;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  const cv::Rect2d b = kPortrait.face_region_px;
  int compared = 0;
  for (const cv::Rect2d& box :
       {b, cv::Rect2d(b.x - 0.1 * b.width, b.y + 0.05 * b.height, 1.2 * b.width, 1.2 * b.height),
        cv::Rect2d(b.x + 7.3, b.y - 4.6, 0.9 * b.width, 0.9 * b.height)}) {
    for (bool use_grey : {false, true}) {
      auto r = l->fit(use_grey ? grey : img, box);
      ASSERT_TRUE(r && r->has_value());
      const std::vector<cv::Point2d> expected =
          use_grey ? ref.fit(dlib::cv_image<unsigned char>(grey), box)
                   : ref.fit(dlib::cv_image<dlib::bgr_pixel>(img), box);
      ASSERT_EQ((*r)->size(), expected.size());
      for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_EQ((**r)[i].x, expected[i].x) << "point " << i << " grey " << use_grey;
        EXPECT_EQ((**r)[i].y, expected[i].y) << "point " << i << " grey " << use_grey;
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 6);
}

TEST(DlibLandmarker, QuantizedLeavesFitAsTheFloatLeavesDo) {
  // The int16 leaves (the default) against dlib's float leaves, on the portrait from several
  // boxes, colour and grey. Quantisation alone moves points by ~1e-4 px; but the cascade is
  // chaotic (a split that flips picks another leaf), so some fits move by a few tenths of a pixel,
  // as a fit from a box shifted by a pixel does. Asserted: the median fit within 0.05 px (mean
  // point distance), every fit within 0.5 px.
  ASSERT_TRUE(DlibLandmarkerOptions{}.quantized_leaves);
  auto q = shared_landmarker();
  auto f = float_landmarker();
  const cv::Mat img = portrait();
  cv::Mat grey;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  const cv::Rect2d b = kPortrait.face_region_px;
  std::vector<double> mean_distances;
  for (const cv::Rect2d& box :
       {b, cv::Rect2d(b.x - 0.1 * b.width, b.y + 0.05 * b.height, 1.2 * b.width, 1.2 * b.height),
        cv::Rect2d(b.x + 7.3, b.y - 4.6, 0.9 * b.width, 0.9 * b.height)}) {
    for (const cv::Mat* image : {&img, static_cast<const cv::Mat*>(&grey)}) {
      auto a = f->fit(*image, box);
      auto c = q->fit(*image, box);
      ASSERT_TRUE(a && *a && c && *c);
      ASSERT_EQ((*a)->size(), (*c)->size());
      double sum = 0;
      for (size_t i = 0; i < (*a)->size(); ++i) sum += cv::norm((**a)[i] - (**c)[i]);
      mean_distances.push_back(sum / static_cast<double>((*a)->size()));
    }
  }
  ASSERT_EQ(mean_distances.size(), 6u);
  std::sort(mean_distances.begin(), mean_distances.end());
  EXPECT_LT((mean_distances[2] + mean_distances[3]) / 2, 0.05);
  EXPECT_LT(mean_distances.back(), 0.5);
}

TEST(DlibLandmarker, BoxConventionDoesNotMatterMuch) {
  // A box 20% larger and shifted (another detector's convention) gives nearly the same eyes.
  auto l = shared_landmarker();
  const cv::Mat img = portrait();
  const cv::Rect2d b = kPortrait.face_region_px;
  const cv::Rect2d big(b.x - 0.1 * b.width, b.y - 0.2 * b.height, 1.2 * b.width, 1.2 * b.height);
  auto a = l->fit(img, b), c = l->fit(img, big);
  ASSERT_TRUE(a && *a && c && *c);
  for (int i : {36, 39, 42, 45, 30}) EXPECT_LT(cv::norm((**a)[i] - (**c)[i]), 2.5) << i;
}

TEST(DlibLandmarker, SpreadConfidenceAndAugmentation) {
  // spread_confidence: 1 up to spread_ok, 0 from spread_bad, linear between; NaN = 1.
  EXPECT_DOUBLE_EQ(spread_confidence(0.01), 1.0);
  EXPECT_DOUBLE_EQ(spread_confidence(0.065), 0.5);
  EXPECT_DOUBLE_EQ(spread_confidence(0.2), 0.0);
  EXPECT_DOUBLE_EQ(spread_confidence(std::nan("")), 1.0);

  auto l = shared_landmarker();
  const cv::Mat img = portrait();
  const cv::Rect2d b = kPortrait.face_region_px;
  auto plain = l->fit_with_spread(img, b);
  ASSERT_TRUE(plain && *plain);
  // A clear frontal face: the two passes agree (small spread, full confidence).
  EXPECT_LT((*plain)->spread, 0.03);
  // box_for_extent maps the fitted points' extent to a box that gives the same points back.
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (const auto& p : (*plain)->points)
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  auto again = l->fit(img, l->box_for_extent(cv::Rect2d(x0, y0, x1 - x0, y1 - y0)));
  ASSERT_TRUE(again && *again);
  for (int i : {36, 45, 30, 48, 54}) EXPECT_LT(cv::norm((**again)[i] - (*plain)->points[i]), 2.0);

  // Mirrored + scaled fits: left/right mapped back correctly (eyes stay at the irises).
  DlibLandmarkerOptions o;
  o.mirror = true;
  o.box_scales = {0.9, 1.1};
  auto tta = make_dlib_landmarker(o);
  ASSERT_TRUE(tta) << tta.error().message;
  auto r = (*tta)->fit_with_spread(img, b);
  ASSERT_TRUE(r && *r);
  FaceLandmarks lm;
  lm.points_px = (*r)->points;
  EXPECT_LT(cv::norm(lm.right_eye_px() - kPortrait.right_eye_px), 3.0);
  EXPECT_LT(cv::norm(lm.left_eye_px() - kPortrait.left_eye_px), 3.0);
  EXPECT_LT(lm.points_px[36].x, lm.points_px[45].x);  // subject's right eye on the image left
  EXPECT_LT((*r)->spread, 0.03);
  // A face-sized box on a face-free textured patch: the fits disagree.
  cv::Mat noise(img.size(), CV_8UC3);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(255));
  auto n = (*tta)->fit_with_spread(noise, b);
  ASSERT_TRUE(n && *n);
  EXPECT_GT((*n)->spread, (*r)->spread);
  o.box_scales = {3.0};
  EXPECT_FALSE(o.check());
}

// face-api's CNN landmarker and tiny face detector (npm @vladmandic/face-api, compared with dlib
// in `eval landmarks`): the portrait's face found once, eyes near the hand-measured irises.
TEST(FaceApiLandmarker, PortraitTinyDetectorAndEyes) {
  auto l = make_face_api_landmarker();
  if (!l && l.error().code == ErrorCode::kNotFound)
    GTEST_SKIP() << "npm @vladmandic/face-api not installed: " << l.error().message;
  ASSERT_TRUE(l) << l.error().message;
  auto det = vision::FaceApiTinyFaceDetector::load(vision::default_face_api_model_dir());
  ASSERT_TRUE(det) << det.error().message;
  const cv::Mat img = portrait();
  const auto faces = det->detect(img, 512);
  ASSERT_EQ(faces.size(), 1u);
  EXPECT_TRUE(faces[0].box.contains(kPortrait.right_eye_px));
  EXPECT_TRUE(faces[0].box.contains(kPortrait.left_eye_px));
  auto r = (*l)->fit_with_spread(img, faces[0].box);
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->has_value());
  const auto& p = (*r)->points;
  ASSERT_EQ(p.size(), 68u);
  cv::Point2d right(0, 0), left(0, 0);
  for (int k = 36; k < 42; ++k) right += p[k] / 6.0;
  for (int k = 42; k < 48; ++k) left += p[k] / 6.0;
  std::printf("cnn eyes (%.1f, %.1f) (%.1f, %.1f), spread %.4f\n", right.x, right.y, left.x, left.y,
              (*r)->spread);
  EXPECT_LT(cv::norm(right - kPortrait.right_eye_px), 5.0);
  EXPECT_LT(cv::norm(left - kPortrait.left_eye_px), 5.0);
  EXPECT_LT((*r)->spread, 0.03);
  // Negatives: no face in a uniform grey image; a uniform or tiny box gives no landmarks.
  const cv::Mat grey_image(480, 640, CV_8UC3, cv::Scalar(128, 128, 128));
  EXPECT_TRUE(det->detect(grey_image).empty());
  auto g = (*l)->fit(grey_image, cv::Rect2d(200, 150, 120, 120));
  ASSERT_TRUE(g);
  EXPECT_FALSE(g->has_value());
  g = (*l)->fit(img, cv::Rect2d(200, 100, 10, 10));
  ASSERT_TRUE(g);
  EXPECT_FALSE(g->has_value());
  FaceApiLandmarkerOptions bad;
  bad.margin = -0.1;
  EXPECT_FALSE(make_face_api_landmarker(bad));
}

// One load per options and process; other options another model; a missing file an error.
TEST(DlibLandmarker, SharedLandmarkerIsLoadedOncePerOptions) {
  const auto a = shared_dlib_landmarker(), b = shared_dlib_landmarker();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->get(), b->get());
  const auto f = shared_dlib_landmarker(float_leaves());
  ASSERT_TRUE(f);
  EXPECT_NE(f->get(), a->get());
  EXPECT_EQ(f->get(), float_landmarker().get());
  DlibLandmarkerOptions missing;
  missing.model = "/nonexistent/shape_predictor.dat";
  const auto e = shared_dlib_landmarker(missing);
  ASSERT_FALSE(e);
  EXPECT_NE(e.error().message.find("/nonexistent/shape_predictor.dat"), std::string::npos);
  EXPECT_TRUE(shared_dlib_landmarker());  // a failed load leaves the cache usable
}

TEST(DlibLandmarker, NegativeCases) {
  auto l = shared_landmarker();
  const cv::Mat grey_image(480, 640, CV_8UC3, cv::Scalar(128, 128, 128));
  auto r = l->fit(grey_image, cv::Rect2d(200, 150, 120, 120));
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->has_value()) << "uniform grey box";
  r = l->fit(portrait(), cv::Rect2d(200, 100, 10, 10));
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->has_value()) << "tiny box";
  r = l->fit(portrait(), cv::Rect2d(600, 600, 100, 100));
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->has_value()) << "box outside the image";
  r = l->fit(cv::Mat(100, 100, CV_32F, cv::Scalar(0)), cv::Rect2d(10, 10, 50, 50));
  EXPECT_FALSE(r) << "unsupported image type is an error";
}

// ---- Analyser ----

MultiFrame one_frame(const SensorId& cam, const cv::Mat& img, Timestamp t) {
  MultiFrame mf;
  mf.stamp = t;
  mf.frames[cam] = make_frame(cam, t, 7, ColorImage{img});
  return mf;
}

TEST(FaceLandmarksAnalyzer, BlackboardBehaviour) {
  auto a = make_face_landmarks_analyzer({}, shared_landmarker());
  ASSERT_TRUE(a);
  EXPECT_EQ((*a)->contract().writes,
            (std::vector<std::string>{keys::kFaceLandmarks.name, keys::kFaceLandmarkViews.name}));
  const Timestamp t = Timestamp::from_seconds(1);
  const MultiFrame mf = one_frame("camera_middle", portrait(), t);
  {  // no selection entry this tick: nothing written
    Blackboard bb;
    BlackboardWriter w("face_landmarks");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    EXPECT_TRUE(w.empty());
  }
  {  // absent selection (no face): absent landmarks
    Blackboard bb;
    BlackboardWriter d("face_detection");
    d.set_absent(keys::kSelectedCamera, t);
    bb.commit(d, t);
    BlackboardWriter w("face_landmarks");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t);
    auto e = bb.snapshot().get(keys::kFaceLandmarks);
    ASSERT_TRUE(e);
    EXPECT_FALSE(e->present());
  }
  {  // a selected face: 68 landmarks with the frame's stamp and the detection score
    Blackboard bb;
    BlackboardWriter d("face_detection");
    SelectedCamera s;
    s.camera = "camera_middle";
    s.face.box_px = kPortrait.face_region_px;
    s.face.score = 0.9f;
    d.set(keys::kSelectedCamera, s, t, 0.9f);
    bb.commit(d, t);
    BlackboardWriter w("face_landmarks");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t);
    auto e = bb.snapshot().get(keys::kFaceLandmarks);
    ASSERT_TRUE(e && e->present());
    EXPECT_EQ(e->value->camera, "camera_middle");
    EXPECT_EQ(e->value->frame_sequence, 7u);
    EXPECT_EQ(e->value->points_px.size(), 68u);
    EXPECT_FLOAT_EQ(e->confidence, 0.9f);
    // The selected camera has no frame in this tick: absent.
    s.camera = "camera_left";
    BlackboardWriter d2("face_detection");
    d2.set(keys::kSelectedCamera, s, t + Duration::from_ms(40), 0.9f);
    bb.commit(d2, t + Duration::from_ms(40));
    MultiFrame mf2 = one_frame("camera_middle", portrait(), t + Duration::from_ms(40));
    BlackboardWriter w2("face_landmarks");
    ASSERT_TRUE((*a)->process(mf2, bb.snapshot(), w2));
    bb.commit(w2, t + Duration::from_ms(40));
    e = bb.snapshot().get(keys::kFaceLandmarks);
    ASSERT_TRUE(e);
    EXPECT_FALSE(e->present());
  }
}

// Issue 15: the other cameras' best faces are fitted too (keys::kFaceLandmarkViews); a camera
// whose detection is of another frame, that has no frame this tick, or that sees the face turned
// away is left out; with other_views off the list is empty.
TEST(FaceLandmarksAnalyzer, OtherCamerasFacesAreFittedForAMultiViewPose) {
  const Timestamp t = Timestamp::from_seconds(1);
  MultiFrame mf = one_frame("camera_middle", portrait(), t);
  mf.frames["camera_left"] = make_frame("camera_left", t, 7, ColorImage{portrait()});
  mf.frames["camera_right"] = make_frame("camera_right", t, 7, ColorImage{portrait()});
  FaceDetections det;
  for (const char* c : {"camera_middle", "camera_left", "camera_right", "camera_top"}) {
    CameraFaces& cf = det.cameras[c];
    cf.frame_stamp = t;
    cf.faces.push_back({kPortrait.face_region_px, 0.9f, FaceView::kFrontal, 1.f});
  }
  det.cameras["camera_right"].frame_stamp = t - Duration::from_ms(40);  // an older frame
  SelectedCamera s;
  s.camera = "camera_middle";
  s.face = det.cameras["camera_middle"].faces[0];
  auto views_with = [&](bool other_views, bool parallel = true) {
    FaceLandmarksAnalyzerOptions o;
    o.other_views = other_views;
    o.parallel = parallel;
    auto a = make_face_landmarks_analyzer(o, shared_landmarker());
    EXPECT_TRUE(a);
    Blackboard bb;
    BlackboardWriter d("face_detection");
    d.set(keys::kFaceDetections, det, t, 0.9f);
    d.set(keys::kSelectedCamera, s, t, 0.9f);
    bb.commit(d, t);
    BlackboardWriter w("face_landmarks");
    EXPECT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t);
    auto e = bb.snapshot().get(keys::kFaceLandmarkViews);
    EXPECT_TRUE(e && e->present());
    return e ? *e->value : FaceLandmarkViews{};
  };
  const FaceLandmarkViews on = views_with(true);
  ASSERT_EQ(on.others.size(), 1u);
  EXPECT_EQ(on.others[0].camera, "camera_left");
  EXPECT_EQ(on.others[0].points_px.size(), 68u);
  EXPECT_TRUE(views_with(false).others.empty());
  // The fits run at once by default; one after the other they give the same points.
  det.cameras["camera_right"].frame_stamp = t;  // now two other views
  const FaceLandmarkViews parallel = views_with(true, true);
  const FaceLandmarkViews serial = views_with(true, false);
  ASSERT_EQ(parallel.others.size(), 2u);
  ASSERT_EQ(serial.others.size(), 2u);
  for (size_t v = 0; v < 2; ++v) {
    EXPECT_EQ(parallel.others[v].camera, serial.others[v].camera);
    EXPECT_EQ(parallel.others[v].points_px, serial.others[v].points_px);
  }
  det.cameras["camera_right"].frame_stamp = t - Duration::from_ms(40);
  // A camera that sees the head turned more than 45 degrees away is not fitted (default 0.5).
  det.cameras["camera_left"].faces[0].frontalness = 0.3f;
  EXPECT_TRUE(views_with(true).others.empty());
  FaceLandmarksAnalyzerOptions bad;
  bad.other_view_min_frontalness = 1.5;
  EXPECT_FALSE(bad.check());
  // Two people in camera_left: another face scores higher, but the last head pose projects into
  // the child's (head_face): the child's is fitted; without a pose, the best-scored one.
  det.cameras["camera_left"].faces[0].frontalness = 1.f;
  const cv::Rect2d child = kPortrait.face_region_px;
  const cv::Rect2d other(child.x + 0.3 * child.width, child.y, 0.9 * child.width,
                         0.9 * child.height);
  det.cameras["camera_left"].faces.insert(det.cameras["camera_left"].faces.begin(),
                                          {other, 0.95f, FaceView::kFrontal, 1.f});
  det.cameras["camera_left"].head_face = 1;
  FaceLandmarkViews two = views_with(true);
  ASSERT_EQ(two.others.size(), 1u);
  EXPECT_EQ(two.others[0].box_px, child);
  det.cameras["camera_left"].head_face.reset();
  two = views_with(true);
  ASSERT_EQ(two.others.size(), 1u);
  EXPECT_EQ(two.others[0].box_px, other);
  det.cameras["camera_left"].head_face = 5;  // out of range (a broken writer): not fitted
  EXPECT_TRUE(views_with(true).others.empty());
}

// A landmarker that returns fixed points (a grid over the box, shifted right by offset_px, outer
// eye corners the box's width apart) with a fixed spread, and counts its calls.
class FixedLandmarker final : public Landmarker {
 public:
  FixedLandmarker(double offset_px, double spread) : offset_(offset_px), spread_(spread) {}
  std::string_view name() const override { return "fixed"; }
  int point_count() const override { return kFaceLandmarkCount; }
  Result<std::optional<std::vector<cv::Point2d>>> fit(const cv::Mat&,
                                                      const cv::Rect2d& box) const override {
    ++calls;
    std::vector<cv::Point2d> p;
    for (int i = 0; i < kFaceLandmarkCount; ++i)
      p.emplace_back(box.x + offset_ + box.width * (i % 9) / 8.0,
                     box.y + box.height * (i / 9) / 8.0);
    p[36] = {box.x + offset_, box.y + 0.4 * box.height};  // outer eye corners a box width apart
    p[45] = {box.x + offset_ + box.width, box.y + 0.4 * box.height};
    return std::optional<std::vector<cv::Point2d>>{std::move(p)};
  }
  Result<std::optional<LandmarkFit>> fit_with_spread(const cv::Mat& image,
                                                     const cv::Rect2d& box) const override {
    auto p = fit(image, box);
    if (!p) return tl::unexpected(p.error());
    return std::optional<LandmarkFit>{LandmarkFit{std::move(**p), spread_}};
  }
  mutable std::atomic<int> calls{0};  // fits may run on several threads

 private:
  double offset_, spread_;
};

// cnn_fallback: a dlib fit whose passes disagree (spread 0.2: confidence 0) is replaced by the
// CNN's points, with the confidence of their distance from dlib's; a confident dlib fit is kept
// and the CNN not run; cnn_fallback = false or no CNN: dlib's points whatever their spread.
TEST(FaceLandmarksAnalyzer, CnnReplacesAFitWhosePassesDisagree) {
  const Timestamp t = Timestamp::from_seconds(1);
  const MultiFrame mf = one_frame("camera_middle", portrait(), t);
  SelectedCamera s;
  s.camera = "camera_middle";
  s.face.box_px = cv::Rect2d(100, 100, 80, 80);
  auto run = [&](const FaceLandmarksAnalyzerOptions& o, double dlib_spread,
                 const std::shared_ptr<const FixedLandmarker>& cnn) {
    auto a = make_face_landmarks_analyzer(
        o, std::make_shared<const FixedLandmarker>(0.0, dlib_spread), cnn);
    EXPECT_TRUE(a);
    testing::AnalyzerRunner runner(std::move(*a));
    runner.preset(keys::kSelectedCamera, s, t);
    EXPECT_TRUE(runner.run(mf));
    auto e = runner.output(keys::kFaceLandmarks);
    EXPECT_TRUE(e && e->present());
    return std::make_pair(e->value->points_px[0].x, e->confidence);
  };
  FaceLandmarksAnalyzerOptions o;
  o.other_views = false;
  // The CNN's points lie 1 px right of dlib's; the outer eye corners are 80 px apart: spread
  // 1 / 80 = 0.0125 < spread_ok, confidence 1.
  auto cnn = std::make_shared<const FixedLandmarker>(1.0, 0.0);
  auto [x, conf] = run(o, 0.2, cnn);
  EXPECT_DOUBLE_EQ(x, 101.0);
  EXPECT_FLOAT_EQ(conf, 1.f);
  EXPECT_EQ(cnn->calls, 1);
  // Far from dlib's (8 px = 0.1 of the corner distance = spread_bad): confidence 0.
  auto far = std::make_shared<const FixedLandmarker>(8.0, 0.0);
  std::tie(x, conf) = run(o, 0.2, far);
  EXPECT_DOUBLE_EQ(x, 108.0);
  EXPECT_NEAR(conf, 0.f, 1e-6);
  // A confident dlib fit (spread 0.01): kept, the CNN not asked.
  std::tie(x, conf) = run(o, 0.01, cnn);
  EXPECT_DOUBLE_EQ(x, 100.0);
  EXPECT_FLOAT_EQ(conf, 1.f);
  EXPECT_EQ(cnn->calls, 1);
  // Fallback off, or no CNN given: dlib's points with dlib's confidence (0 at spread 0.2).
  o.cnn_fallback = false;
  std::tie(x, conf) = run(o, 0.2, cnn);
  EXPECT_DOUBLE_EQ(x, 100.0);
  EXPECT_NEAR(conf, 0.f, 1e-6);
  EXPECT_EQ(cnn->calls, 1);
  o.cnn_fallback = true;
  std::tie(x, conf) = run(o, 0.2, nullptr);
  EXPECT_DOUBLE_EQ(x, 100.0);
  FaceLandmarksAnalyzerOptions bad;
  bad.cnn_fallback_below = 1.5;
  EXPECT_FALSE(bad.check());
}

// ---- Demo session ----

TEST(FaceLandmarksDemo, EyeLandmarksNearTruthEyes) {
  const auto& run = face_testing::demo_run(shared_landmarker());
  std::vector<double> err, ms;
  int selected = 0, fitted = 0;
  for (const auto& t : run.ticks) {
    if (!t.selected) continue;
    ++selected;
    if (!t.landmarks) continue;
    ++fitted;
    ms.push_back(t.landmark_ms);
    ASSERT_NE(t.truth, nullptr);
    const auto& ct = t.truth->cameras.at(t.landmarks->camera);
    if (!ct.visible) continue;
    err.push_back(cv::norm(t.landmarks->left_eye_px() - ct.left_eye_px));
    err.push_back(cv::norm(t.landmarks->right_eye_px() - ct.right_eye_px));
  }
  const double med = face_testing::median(err);
  std::vector<double> sorted = err;
  std::sort(sorted.begin(), sorted.end());
  const double p90 = sorted.empty() ? NAN : sorted[sorted.size() * 9 / 10];
  std::cout << "[demo s3 3s] ticks " << run.ticks.size() << ", selected " << selected
            << ", landmarks " << fitted << ", eye error median " << med << " px, p90 " << p90
            << " px, landmarks ms/face median " << face_testing::median(ms) << "\n";
  RecordProperty("eye_error_median_px", std::to_string(med));
  EXPECT_GT(selected, 40);
  EXPECT_EQ(fitted, selected);
  // The truth is the pupil centre, which moves with the eye gaze (up to ~25 deg in the mesh
  // demo), while the contour centroid stays near the middle of the eye opening.
  EXPECT_LT(med, 4.5);
}

}  // namespace
}  // namespace dreamsense::face_landmarks
