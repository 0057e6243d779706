// The level of a self-calibrated head frame from gaze fixations (gaze_level.hpp): synthetic
// cameras, a face whose head stops short of the target while its eyes land on it, and the cases
// where the level must not move.

#include "dreamsense/self_calibration/gaze_level.hpp"

#include "dreamsense/core/camera_model.hpp"
#include "dreamsense/head_pose/head_pose_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace dreamsense::self_calibration {
namespace {

constexpr double kDeg = CV_PI / 180;

CameraModel camera_at(double x) {
  CameraModel c;
  c.frame = "camera";
  c.image_size = {1280, 960};
  c.K = cv::Matx33d(1100, 0, 640, 0, 1100, 480, 0, 0, 1);
  look_at({x, -0.05, 0.0}, {0, -0.05, 1.1}, {0, 1, 0}, c.R, c.t);
  return c;
}

cv::Vec3d unit(const cv::Vec3d& v) { return v * (1.0 / cv::norm(v)); }

// World yaw/pitch (deg) of a direction in the convention of rotation_from_ypr_deg: the head
// turned by them looks along it.
cv::Vec2d yaw_pitch_of(const cv::Vec3d& d) {
  return {std::atan2(-d[0], -d[2]) / kDeg, std::asin(d[1]) / kDeg};
}

struct Synthetic {
  std::vector<CameraModel> cams{camera_at(-0.4), camera_at(0.0), camera_at(0.45)};
  std::vector<head_pose::MultiViewLandmarks> ticks;
  std::vector<std::vector<EyeCenters>> pupils;
};

// `n` ticks: every other one the child looks at `robot` with the eyes while the head stops
// `head_short_deg` below it (the eyes do the rest, as in people); the others look at toys on the
// table below, head and eyes together. Landmarks and pupils are projected without noise but for
// `noise_px` on the pupils. The true eyeballs are the anatomical ones moved by
// `eyeball_shift_x_m` along the head's x.
void make_ticks(Synthetic& s, const head_pose::FaceModel3d& truth, const cv::Vec3d& robot, int n,
                double head_short_deg, double noise_px, double eyeball_shift_x_m = 0) {
  auto eyeballs = anatomical_eyeballs(truth, {});
  ASSERT_TRUE(eyeballs);
  eyeballs->first.centre_head_m[0] += eyeball_shift_x_m;
  eyeballs->second.centre_head_m[0] += eyeball_shift_x_m;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-2, 2), toy_x(-0.3, 0.3);
  std::normal_distribution<double> noise(0, noise_px);
  const auto& face68 = head_pose::generic_68_points_m();
  for (int i = 0; i < n; ++i) {
    const cv::Vec3d head(0.03 * (i % 3 - 1), -0.05, 1.1 + 0.02 * (i % 2));
    const cv::Vec3d target = i % 2 == 0 ? robot : cv::Vec3d(toy_x(rng), 0.25, 0.7);
    const cv::Vec2d ypr = yaw_pitch_of(unit(target - head));
    const double short_deg = i % 2 == 0 ? head_short_deg : 0;
    // Pitch is positive downwards here (y down): "below the target" adds to it.
    const cv::Matx33d world_from_head =
        rotation_from_ypr_deg(ypr[0] + jitter(rng), ypr[1] + short_deg + jitter(rng), jitter(rng));
    head_pose::MultiViewLandmarks mv;
    std::vector<EyeCenters> found;
    for (const CameraModel& cam : s.cams) {
      head_pose::CameraLandmarks view{&cam, {}};
      for (const cv::Point3d& p : face68) {
        const auto px = cam.project(world_from_head * cv::Vec3d(p.x, p.y, p.z) + head);
        view.landmarks_px.push_back(px ? *px : cv::Point2d(NAN, NAN));
      }
      EyeCenters e;
      for (auto [eye, ball] :
           {std::pair{&e.right, &eyeballs->first}, std::pair{&e.left, &eyeballs->second}}) {
        const cv::Vec3d centre = world_from_head * ball->centre_head_m + head;
        const cv::Vec3d pupil = centre + ball->radius_m * unit(target - centre);
        if (const auto px = cam.project(pupil)) {
          eye->found = true;
          eye->center_px = *px + cv::Point2d(noise(rng), noise(rng));
        }
      }
      mv.views.push_back(std::move(view));
      found.push_back(e);
    }
    s.ticks.push_back(std::move(mv));
    s.pupils.push_back(std::move(found));
  }
}

TEST(GazeLevel, PitchedModelIsLevelledBackByTheEyesNotTheHead) {
  const auto truth = head_pose::generic_face_model(false);
  const cv::Vec3d robot(0, -0.30, 0.15);
  Synthetic s;
  make_ticks(s, truth, robot, 40, 5.0, 0.3);

  // The true frame: the gaze lands on the robot, so nothing to correct, although the head
  // stops 5 deg short of it (what the head-fixation level would take as the level).
  const auto level = level_from_gaze_fixations(truth, s.ticks, s.pupils, robot, {});
  ASSERT_TRUE(level.applied);
  EXPECT_GE(level.fixation_ticks, 15);
  EXPECT_LE(level.fixation_ticks, 22);  // the robot's ticks, not the toys'
  EXPECT_EQ(level.ticks_with_gaze, 40);
  EXPECT_NEAR(level.correction_deg, 0.0, 0.5);

  // A frame pitched by 6 deg is turned back.
  const auto off = level_from_gaze_fixations(pitched(truth, 6.0), s.ticks, s.pupils, robot, {});
  ASSERT_TRUE(off.applied);
  EXPECT_NEAR(off.correction_deg, -6.0, 0.7);
}

// Eyeballs 1.5 mm to the side of where the eye openings put them: the gaze looks past the robot
// by ~8 deg in yaw; with eye_yaw the fixations give the shift back, and the level stays; without
// it (the default) the shift stays 0.
TEST(GazeLevel, EyesLookingPastTheTargetSidewaysGiveTheEyeballsShift) {
  const auto truth = head_pose::generic_face_model(false);
  const cv::Vec3d robot(0, -0.30, 0.15);
  Synthetic s;
  make_ticks(s, truth, robot, 40, 0.0, 0.3, 0.0015);
  GazeLevelOptions with_yaw;
  with_yaw.eye_yaw = true;
  const auto level = level_from_gaze_fixations(truth, s.ticks, s.pupils, robot, {}, with_yaw);
  ASSERT_TRUE(level.applied);
  EXPECT_NEAR(level.eyeball_shift_x_m, 0.0015, 0.0003);
  EXPECT_NEAR(level.correction_deg, 0.0, 0.7);
  const auto pitch = level_from_gaze_fixations(truth, s.ticks, s.pupils, robot, {});
  ASSERT_TRUE(pitch.applied);
  EXPECT_EQ(pitch.eyeball_shift_x_m, 0.0);
}

// Eyeballs 2.5 mm to the side: the gaze on the robot passes ~13 deg beside it, outside the 10 deg
// window. With follow_yaw_bias the window follows the fixations' median yaw, so the robot's ticks
// still level a frame pitched by 6 deg; centred on the robot (the default) too few are left.
TEST(GazeLevel, TheYawWindowFollowsAConjugateBias) {
  const auto truth = head_pose::generic_face_model(false);
  const cv::Vec3d robot(0, -0.30, 0.15);
  Synthetic s;
  make_ticks(s, truth, robot, 40, 0.0, 0.3, 0.0025);
  GazeLevelOptions following;
  following.follow_yaw_bias = true;
  const auto follow =
      level_from_gaze_fixations(pitched(truth, 6.0), s.ticks, s.pupils, robot, {}, following);
  ASSERT_TRUE(follow.applied);
  EXPECT_GE(follow.fixation_ticks, 15);
  EXPECT_LE(follow.fixation_ticks, 22);
  EXPECT_GT(std::abs(follow.yaw_centre_deg), 8.0);
  EXPECT_NEAR(follow.correction_deg, -6.0, 1.0);
  const auto fixed = level_from_gaze_fixations(pitched(truth, 6.0), s.ticks, s.pupils, robot, {});
  EXPECT_FALSE(fixed.applied);
  EXPECT_LT(fixed.fixation_ticks, GazeLevelOptions{}.min_ticks);
}

TEST(GazeLevel, NoFixationsOrNoPupilsLeaveTheLevel) {
  const auto truth = head_pose::generic_face_model(false);
  const cv::Vec3d robot(0, -0.30, 0.15);
  Synthetic s;
  make_ticks(s, truth, robot, 40, 5.0, 0.3);
  const auto unseen =
      level_from_gaze_fixations(truth, s.ticks, s.pupils, cv::Vec3d(2.0, 0.0, 1.0), {});
  EXPECT_FALSE(unseen.applied);
  EXPECT_EQ(unseen.correction_deg, 0.0);
  EXPECT_LT(unseen.fixation_ticks, GazeLevelOptions{}.min_ticks);

  for (auto& tick : s.pupils)
    for (auto& e : tick) e.right.found = e.left.found = false;
  const auto blind = level_from_gaze_fixations(truth, s.ticks, s.pupils, robot, {});
  EXPECT_FALSE(blind.applied);
  EXPECT_EQ(blind.ticks_with_gaze, 0);

  GazeLevelOptions disabled;
  disabled.enabled = false;
  EXPECT_FALSE(level_from_gaze_fixations(truth, s.ticks, {}, robot, {}, disabled).applied);
}

TEST(GazeLevel, PitchedTurnsTheModelAboutX) {
  const auto truth = head_pose::generic_face_model(false);
  const auto p = pitched(truth, 10.0);
  ASSERT_EQ(p.points_m.size(), truth.points_m.size());
  for (size_t k = 0; k < p.points_m.size(); ++k) {
    EXPECT_DOUBLE_EQ(p.points_m[k].x, truth.points_m[k].x);
    EXPECT_NEAR(cv::norm(p.points_m[k]), cv::norm(truth.points_m[k]), 1e-12);
  }
  const auto back = pitched(p, -10.0);
  for (size_t k = 0; k < p.points_m.size(); ++k)
    EXPECT_NEAR(cv::norm(back.points_m[k] - truth.points_m[k]), 0.0, 1e-12);
  GazeLevelOptions bad;
  bad.max_pitch_deg = 0;
  EXPECT_FALSE(bad.check());
}

}  // namespace
}  // namespace dreamsense::self_calibration
