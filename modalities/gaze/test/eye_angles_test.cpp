#include "dreamsense/gaze/eye_angles.hpp"

#include "dreamsense/gaze/gaze_estimator.hpp"
#include "dreamsense/perception/eye_centers.hpp"
#include "dreamsense/perception/face_landmarks.hpp"
#include "dreamsense/perception/head_pose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace dreamsense::gaze {
namespace {

CameraModel test_camera() {
  CameraModel c;
  c.image_size = {1280, 960};
  c.K = cv::Matx33d(1000, 0, 640, 0, 1000, 480, 0, 0, 1);
  return c;
}

TEST(EyeAngles, ImageOffsetIsAlongAndAcrossTheCornerLine) {
  // Corners 40 px apart, pupil 4 px right of and 2 px below their midpoint.
  const auto o = pupil_offset_image({{100, 200}, {140, 200}, {124, 202}});
  ASSERT_TRUE(o);
  EXPECT_NEAR((*o)[0], 0.1, 1e-12);
  EXPECT_NEAR((*o)[1], 0.05, 1e-12);
  // Corner order does not matter; a tilted eye measures along its own axis.
  const auto swapped = pupil_offset_image({{140, 200}, {100, 200}, {124, 202}});
  ASSERT_TRUE(swapped);
  EXPECT_NEAR((*swapped)[0], 0.1, 1e-12);
  const double c = std::cos(0.3), s = std::sin(0.3);
  auto rot = [&](cv::Point2d p) { return cv::Point2d(c * p.x - s * p.y, s * p.x + c * p.y); };
  const auto tilted = pupil_offset_image({rot({-20, 0}), rot({20, 0}), rot({4, 2})});
  ASSERT_TRUE(tilted);
  EXPECT_NEAR((*tilted)[0], 0.1, 1e-9);
  EXPECT_NEAR((*tilted)[1], 0.05, 1e-9);
  EXPECT_FALSE(pupil_offset_image({{5, 5}, {5, 5}, {6, 6}}));
}

TEST(EyeAngles, AnglesFollowEquationFourAndRoundTrip) {
  EyeAngleModel m;
  m.gamma = 3.0;
  m.epsilon = 4.0;
  m.rest_x = 0.01;
  m.rest_y = -0.02;
  const EyeAngles a = eye_angles({-0.09, 0.08}, m);
  EXPECT_NEAR(a.theta_deg, std::atan(0.3) * 180 / M_PI, 1e-9);  // pupil to the right: theta > 0
  EXPECT_NEAR(a.phi_deg, std::atan(0.4) * 180 / M_PI, 1e-9);    // pupil down: looks down
  const EyeAngles back = angles_of_head_direction(eye_direction_head(a));
  EXPECT_NEAR(back.theta_deg, a.theta_deg, 1e-9);
  EXPECT_NEAR(back.phi_deg, a.phi_deg, 1e-9);
  // Positive theta turns the gaze towards head -x (the subject's right), as head yaw does.
  EXPECT_LT(eye_direction_head({20, 0})[0], 0);
  EXPECT_GT(eye_direction_head({0, 20})[1], 0);
}

TEST(EyeAngles, FitRecoversGainsAndRestFromNoisySamples) {
  EyeAngleModel truth;
  truth.gamma = 2.6;
  truth.epsilon = 3.4;
  truth.rest_x = 0.02;
  truth.rest_y = 0.04;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  std::normal_distribution<double> noise(0, 0.004);
  std::vector<EyeAngleSample> samples;
  for (int i = 0; i < 200; ++i) {
    const cv::Vec2d o(u(rng), u(rng));
    samples.push_back({o + cv::Vec2d(noise(rng), noise(rng)), eye_angles(o, truth)});
  }
  samples[3].truth.theta_deg = 60;  // a gross outlier (a misdetected pupil)
  auto fit = fit_eye_angle_model(samples);
  ASSERT_TRUE(fit) << fit.error().message;
  EXPECT_NEAR(fit->gamma, truth.gamma, 0.1);
  EXPECT_NEAR(fit->epsilon, truth.epsilon, 0.15);
  EXPECT_NEAR(fit->rest_x, truth.rest_x, 0.005);
  EXPECT_NEAR(fit->rest_y, truth.rest_y, 0.005);
}

TEST(EyeAngles, FitRejectsTooFewOrDegenerateSamples) {
  std::vector<EyeAngleSample> few(5);
  EXPECT_FALSE(fit_eye_angle_model(few));
  std::vector<EyeAngleSample> flat(50, EyeAngleSample{{0.01, 0.0}, {0, 0}});
  EXPECT_FALSE(fit_eye_angle_model(flat));
}

// A head 0.8 m in front of the camera, turned 35 deg: the head-plane offset of a synthetic eye
// is the same as for the frontal head, the image offset is foreshortened.
TEST(EyeAngles, HeadPlaneOffsetUndoesHeadRotation) {
  const CameraModel cam = test_camera();
  auto eye_in_image = [&](double yaw, EyeObservation& obs) {
    const cv::Matx33d R = rotation_from_ypr_deg(yaw, 0, 0);
    const cv::Vec3d p(0.0, 0.0, 0.8);
    // Camera frame = world here; a head-frame point h maps to R h + p.
    auto px = [&](cv::Vec3d h) { return *cam.project_camera_point(R * h + p); };
    obs = {px({0.015, 0, 0}), px({0.045, 0, 0}), px({0.034, 0.002, 0})};
    return std::pair{R, p};
  };
  EyeObservation frontal, turned;
  auto [R0, p0] = eye_in_image(0, frontal);
  auto [R1, p1] = eye_in_image(35, turned);
  const auto a = pupil_offset_head_plane(frontal, cam, R0, p0);
  const auto b = pupil_offset_head_plane(turned, cam, R1, p1);
  ASSERT_TRUE(a && b);
  // Corners 30 mm apart, pupil 4 mm beside and 2 mm below their midpoint.
  EXPECT_NEAR((*a)[0], 4.0 / 30, 1e-9);
  EXPECT_NEAR((*b)[0], 4.0 / 30, 1e-9);
  EXPECT_NEAR((*b)[1], 2.0 / 30, 1e-9);
  const auto img = pupil_offset_image(turned);
  ASSERT_TRUE(img);
  EXPECT_GT(std::abs((*img)[0] - 4.0 / 30), 0.002);  // the image measure is distorted
}

TEST(GazeEstimator, ComposesEyeAnglesWithHeadPoseAndFusesEyes) {
  const CameraModel cam = test_camera();
  FaceLandmarks lm;
  lm.camera = "cam";
  lm.points_px.assign(kFaceLandmarkCount, {0, 0});
  lm.points_px[36] = {600, 480};
  lm.points_px[39] = {630, 480};
  lm.points_px[42] = {650, 480};
  lm.points_px[45] = {680, 480};
  EyeCenters pupils;
  pupils.right = {true, {615, 480}, 1};  // centred: looks straight ahead
  pupils.left = {false, {}, 0};          // e.g. a glint
  HeadPose head;
  head.world_from_head = rotation_from_ypr_deg(20, 0, 0);
  head.camera_from_head = head.world_from_head;
  head.position_world_m = head.position_camera_m = {0, 0, 0.8};
  GazeEstimatorOptions o;
  o.plane = OffsetPlane::kImage;
  const auto g = estimate_gaze(lm, pupils, head, cam, o);
  ASSERT_TRUE(g);
  EXPECT_TRUE(g->right.valid);
  EXPECT_FALSE(g->left.valid);
  ASSERT_TRUE(g->both.valid);
  // Eyes straight ahead in the head: the gaze is the head gaze.
  const cv::Vec3d head_gaze = head.world_from_head * cv::Vec3d(0, 0, -1);
  EXPECT_NEAR(g->both.direction_world.dot(head_gaze), 1.0, 1e-9);
  EXPECT_NEAR(g->both.theta_deg, 0.0, 1e-6);
  // Pupil moved towards the image left (the subject's right): the gaze turns further right.
  pupils.right.center_px = {612, 480};
  const auto g2 = estimate_gaze(lm, pupils, head, cam, o);
  ASSERT_TRUE(g2);
  EXPECT_GT(g2->right.theta_deg, 1.0);
  pupils.right.found = false;
  EXPECT_FALSE(estimate_gaze(lm, pupils, head, cam, o));
}

}  // namespace
}  // namespace dreamsense::gaze

namespace dreamsense::gaze {
namespace {

TEST(GazeModelFile, RoundTripsAndRejectsBadFiles) {
  const auto dir = std::filesystem::temp_directory_path() / "dreamsense_gaze_model_test";
  std::filesystem::create_directories(dir);
  GazeModelFile m;
  m.plane = OffsetPlane::kImage;
  m.right_eye = {2.5, 3.5, 0.01, 0.05};
  m.left_eye = {2.7, 3.1, -0.01, 0.04};
  m.provenance = "unit test";
  m.samples = 42;
  ASSERT_TRUE(write_gaze_model(dir / "g.yaml", m));
  auto back = read_gaze_model(dir / "g.yaml");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->plane, OffsetPlane::kImage);
  EXPECT_DOUBLE_EQ(back->left_eye.epsilon, 3.1);
  EXPECT_DOUBLE_EQ(back->right_eye.rest_y, 0.05);
  EXPECT_EQ(back->samples, 42);
  EXPECT_EQ(back->provenance, "unit test");

  EXPECT_FALSE(read_gaze_model(dir / "missing.yaml"));
  std::ofstream(dir / "bad.yaml") << "%YAML:1.0\nformat: something-else\n";
  auto bad = read_gaze_model(dir / "bad.yaml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("not a dreamsense gaze model"), std::string::npos);
  m.right_eye.gamma = -1;  // written by hand: must be refused on reading
  ASSERT_TRUE(write_gaze_model(dir / "neg.yaml", m));
  EXPECT_FALSE(read_gaze_model(dir / "neg.yaml"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace dreamsense::gaze
