// head_pose on demo frames: face_detection -> dlib landmarks -> PnP on a 3 s demo session (seed
// 3), compared with the truth head pose. The demo face is a PLANAR photo (sim/face_renderer.hpp),
// so a 3-D face model shows a model-mismatch bias; a planar model built from the same photo
// separates method error from model mismatch.

#include "dreamsense/face_landmarks/landmarker.hpp"
#include "dreamsense/head_pose/head_pose_analyzer.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"
#include "dreamsense/sim/face_renderer.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <iostream>

#include "../../face_landmarks/test/demo_face.hpp"

namespace dreamsense::head_pose {
namespace {

std::shared_ptr<const face_landmarks::Landmarker> shared_landmarker() {
  static std::shared_ptr<const face_landmarks::Landmarker> l = [] {
    auto r = face_landmarks::make_dlib_landmarker();
    if (!r) throw std::runtime_error(r.error().to_string());
    return std::shared_ptr<const face_landmarks::Landmarker>(std::move(*r));
  }();
  return l;
}

// The renderer's own geometry: dlib landmarks on the portrait, mapped onto the photo's plane
// (z = 0) with the renderer's pixel -> head-frame mapping. 51 points (no jaw).
FaceModel3d planar_model() {
  const sim::PlanarFaceOptions po;
  auto renderer = sim::PlanarFaceRenderer::create(po);
  if (!renderer) throw std::runtime_error(renderer.error().to_string());
  const cv::Mat img = cv::imread(po.portrait.string(), cv::IMREAD_COLOR);
  auto pts = shared_landmarker()->fit(img, po.face_region_px);
  if (!pts || !*pts) throw std::runtime_error("no landmarks on the portrait");
  FaceModel3d m;
  m.name = "planar_51";
  for (int i = 17; i < 68; ++i) {
    m.landmark_index.push_back(i);
    const cv::Vec3d h = (*renderer)->head_point((**pts)[static_cast<size_t>(i)]);
    m.points_m.emplace_back(h[0], h[1], h[2]);
  }
  return m;
}

struct Errors {
  std::vector<double> rot, yaw, pitch, roll, pos, gaze, pitch_signed;
  int fitted = 0, rejected = 0;
};

void add(Errors& e, const HeadPose& p, const face_testing::FaceTruth& t) {
  const cv::Matx33d R = rotation_from_ypr_deg(t.yaw_deg, t.pitch_deg, t.roll_deg);
  e.rot.push_back(rotation_angle_deg(p.world_from_head, R));
  e.yaw.push_back(std::abs(p.yaw_deg - t.yaw_deg));
  e.pitch.push_back(std::abs(p.pitch_deg - t.pitch_deg));
  e.roll.push_back(std::abs(p.roll_deg - t.roll_deg));
  e.pitch_signed.push_back(p.pitch_deg - t.pitch_deg);
  e.pos.push_back(cv::norm(p.position_world_m - t.head_position_m));
  const double c = std::clamp(p.gaze_direction_world.dot(t.head_gaze_dir), -1.0, 1.0);
  e.gaze.push_back(std::acos(c) * 180 / CV_PI);
  ++e.fitted;
}

void report(const std::string& name, const Errors& e) {
  using face_testing::median;
  std::printf(
      "[demo s3 3s] %-22s fitted %3d rejected %2d | median deg: rotation %.2f yaw %.2f pitch "
      "%.2f (signed %+.2f) roll %.2f gaze %.2f | position %.1f mm\n",
      name.c_str(), e.fitted, e.rejected, median(e.rot), median(e.yaw), median(e.pitch),
      median(e.pitch_signed), median(e.roll), median(e.gaze), 1000 * median(e.pos));
  std::fflush(stdout);
}

Errors evaluate(const FaceModel3d& model, bool smooth) {
  const auto& run = face_testing::demo_run(shared_landmarker());
  HeadPoseEstimatorOptions o;
  o.model = model;
  PoseFilterOptions fo;
  fo.enabled = smooth;
  PoseFilter filter(fo);
  Errors e;
  for (const auto& t : run.ticks) {
    if (!t.landmarks || t.truth == nullptr) continue;
    const CameraModel& cam = run.cameras.at(t.landmarks->camera);
    auto fit = fit_head_pose(t.landmarks->points_px, cam, o);
    if (!fit) throw std::runtime_error(fit.error().to_string());
    if (!*fit) {
      ++e.rejected;
      continue;
    }
    HeadPose p = make_head_pose(**fit, cam, t.landmarks->camera, t.landmarks->frame_stamp);
    filter.apply(p);
    add(e, p, *t.truth);
  }
  return e;
}

TEST(HeadPoseDemo, GenericModelVsPlanarModel) {
  const Errors generic = evaluate(generic_face_model(), false);
  const Errors generic68 = evaluate(generic_face_model(true), false);
  const Errors dream = evaluate(dream13_face_model(), false);
  const Errors planar = evaluate(planar_model(), false);
  const Errors generic_smoothed = evaluate(generic_face_model(), true);
  const Errors planar_smoothed = evaluate(planar_model(), true);
  report("generic_51", generic);
  report("generic_68", generic68);
  report("dream_13", dream);
  report("planar_51 (renderer)", planar);
  report("generic_51 smoothed", generic_smoothed);
  report("planar_51 smoothed", planar_smoothed);
  RecordProperty("head_pose_median_deg_generic", std::to_string(face_testing::median(generic.rot)));
  RecordProperty("head_pose_median_deg_planar", std::to_string(face_testing::median(planar.rot)));
  ASSERT_GT(generic.fitted, 40);
  // The demo face is a 3-D mesh over the portrait on an analytic head (sim/README.md): no model
  // matches it exactly. The flat model and the generic 3-D model both miss by a pitch bias
  // (face proportions); `train gaze` calibrates that per subject. Regression guards:
  EXPECT_LT(face_testing::median(planar.rot), 6.0);
  EXPECT_LT(face_testing::median(generic.rot), 35.0);
  EXPECT_LT(face_testing::median(generic.yaw), 5.0);
  EXPECT_LT(face_testing::median(generic.roll), 6.0);
  EXPECT_LT(face_testing::median(generic.pos), 0.08);
}

TEST(HeadPoseDemo, AnalyzerOverTheDemo) {
  const auto& run = face_testing::demo_run(shared_landmarker());
  HeadPoseAnalyzerOptions o;
  o.cameras = run.cameras;
  auto a = make_head_pose_analyzer(o);
  ASSERT_TRUE(a);
  Blackboard bb;
  int poses = 0, absent = 0, landmarks = 0;
  for (const auto& t : run.ticks) {
    BlackboardWriter l("face_landmarks");
    if (t.landmarks) {
      l.set(keys::kFaceLandmarks, *t.landmarks, t.stamp, 1.f);
      ++landmarks;
    } else {
      l.set_absent(keys::kFaceLandmarks, t.stamp);
    }
    bb.commit(l, t.stamp);
    MultiFrame mf;
    mf.stamp = t.stamp;
    BlackboardWriter w("head_pose");
    ASSERT_TRUE((*a)->process(mf, bb.snapshot(), w));
    bb.commit(w, t.stamp);
    auto e = bb.snapshot().get(keys::kHeadPose);
    ASSERT_TRUE(e);
    ASSERT_EQ(e->stamp, t.stamp);
    if (e->present()) {
      ++poses;
      EXPECT_GT(e->confidence, 0.f);
      EXPECT_LE(e->confidence, 1.f);
    } else {
      ++absent;
    }
  }
  EXPECT_GE(poses, landmarks * 9 / 10);
  EXPECT_EQ(poses + absent, static_cast<int>(run.ticks.size()));
}

}  // namespace
}  // namespace dreamsense::head_pose
