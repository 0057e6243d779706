#include "dreamsense/gaze/mutual_gaze.hpp"

#include "dreamsense/perception/gaze.hpp"

#include <gtest/gtest.h>

namespace dreamsense::gaze {
namespace {

GazeRay ray(cv::Vec3d origin, cv::Vec3d towards) {
  GazeRay r;
  r.valid = true;
  r.origin_world_m = origin;
  r.direction_world = (towards - origin) / cv::norm(towards - origin);
  return r;
}

TEST(MutualGaze, ThreeDModeTestsTheRayToRobotHeadDistance) {
  MutualGazeOptions o;
  o.robot_head_m = {0, -0.1, 0.2};
  o.radius_m = 0.2;
  double miss = -1;
  EXPECT_TRUE(gaze_hits_robot_3d(ray({0, 0, 1.2}, {0.1, -0.1, 0.2}), o, miss));
  EXPECT_EQ(miss, 0.0);
  EXPECT_FALSE(gaze_hits_robot_3d(ray({0, 0, 1.2}, {0.5, -0.1, 0.2}), o, miss));
  // Robot 0.448 m from that oblique ray: it misses the 0.2 m sphere by 0.248 m.
  EXPECT_NEAR(miss, 0.248, 0.002);
  // Looking away from the robot (it is behind the gaze): never mutual.
  EXPECT_FALSE(gaze_hits_robot_3d(ray({0, 0, 1.2}, {0, -0.1, 2.2}), o, miss));
}

TEST(MutualGaze, CameraPlaneModeTestsTheDreamRectangle) {
  CameraModel cam;  // at the world origin, looking along +z
  cam.image_size = {640, 480};
  cam.K = cv::Matx33d(500, 0, 320, 0, 500, 240, 0, 0, 1);
  MutualGazeOptions o;
  o.mode = MutualGazeMode::kCameraPlane;
  double miss = -1;
  EXPECT_TRUE(gaze_hits_camera_rect(ray({0, 0, 1}, {0.0, 0.2, 0}), cam, o, miss));
  EXPECT_EQ(miss, 0.0);
  EXPECT_FALSE(gaze_hits_camera_rect(ray({0, 0, 1}, {0.17, 0.2, 0}), cam, o, miss));
  EXPECT_NEAR(miss, 0.10, 1e-9);
  EXPECT_FALSE(gaze_hits_camera_rect(ray({0, 0, 1}, {0, 0, 2}), cam, o, miss));  // away
}

TEST(MutualGaze, HoldRuleIgnoresOneFrameFlickerAndCountsHeldTime) {
  MutualGazeOptions o;
  o.onset_s = 0.04;
  o.release_s = 0.08;
  MutualGazeTracker t(o);
  auto at = [](int frame) { return Timestamp::from_ns(int64_t{frame} * 40'000'000); };
  EXPECT_FALSE(t.update(at(0), false, 0.1).mutual);
  EXPECT_FALSE(t.update(at(1), true, 0).mutual);  // one frame is not enough
  EXPECT_FALSE(t.update(at(2), false, 0.1).mutual);
  EXPECT_FALSE(t.update(at(3), true, 0).mutual);
  MutualGaze m = t.update(at(4), true, 0);  // held for 0.04 s: starts, dated from frame 3
  EXPECT_TRUE(m.mutual);
  EXPECT_NEAR(m.held_s, 0.04, 1e-9);
  EXPECT_TRUE(t.update(at(5), false, 0.1).mutual);  // a blink does not end it
  m = t.update(at(6), true, 0);
  EXPECT_TRUE(m.mutual);
  EXPECT_NEAR(m.held_s, 0.12, 1e-9);
  EXPECT_TRUE(t.update(at(7), false, 0.1).mutual);
  EXPECT_TRUE(t.update(at(8), false, 0.1).mutual);
  m = t.update(at(9), false, 0.1);  // failed for 0.08 s: ends
  EXPECT_FALSE(m.mutual);
  EXPECT_EQ(m.held_s, 0.0);
  t.reset();
  EXPECT_FALSE(t.update(at(10), true, 0).mutual);
}

}  // namespace
}  // namespace dreamsense::gaze
