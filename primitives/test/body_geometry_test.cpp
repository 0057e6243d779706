#include "dreamsense/primitives/body.hpp"

#include <gtest/gtest.h>

namespace dreamsense::primitives {
namespace {

// A child facing the front sensor (looking along -z) at 1.1 m; world y is down.
SkeletonBody standing_child(cv::Vec3d offset = {0, 0, 0}) {
  SkeletonBody b;
  auto set = [&](JointId j, cv::Vec3d p) { b.joint(j) = {p + offset, 1.f}; };
  set(JointId::kHead, {0, -0.25, 1.1});
  set(JointId::kShoulderCenter, {0, -0.05, 1.1});
  set(JointId::kSpine, {0, 0.15, 1.1});
  set(JointId::kHipCenter, {0, 0.3, 1.1});
  // The child's left is the sensor's right (+x).
  set(JointId::kShoulderLeft, {0.15, -0.05, 1.1});
  set(JointId::kShoulderRight, {-0.15, -0.05, 1.1});
  set(JointId::kElbowLeft, {0.15, 0.2, 1.1});     // hanging down
  set(JointId::kElbowRight, {-0.4, -0.05, 1.1});  // straight out sideways
  set(JointId::kWristLeft, {0.15, 0.4, 1.1});
  set(JointId::kWristRight, {-0.6, -0.05, 1.1});
  set(JointId::kHandLeft, {0.15, 0.45, 1.1});
  set(JointId::kHandRight, {-0.65, -0.05, 1.1});
  return b;
}

TEST(ArmGeometry, HangingAndSidewaysArms) {
  ArmAnglesValue a = arm_angles(standing_child());
  ASSERT_TRUE(a.left && a.right);
  EXPECT_NEAR(a.left->elevation_deg, -90, 1e-6);
  EXPECT_NEAR(a.right->elevation_deg, 0, 1e-6);
  EXPECT_NEAR(a.right->azimuth_deg, 0, 1e-6);
}

TEST(ArmGeometry, ArmPointingForwardHasAzimuth90) {
  SkeletonBody b = standing_child();
  // Forward for the child is towards the sensor: -z.
  b.joint(JointId::kElbowLeft).position_m = {0.15, -0.05, 0.85};
  ArmAnglesValue a = arm_angles(b);
  ASSERT_TRUE(a.left);
  EXPECT_NEAR(a.left->azimuth_deg, 90, 1e-6);
  EXPECT_NEAR(a.left->elevation_deg, 0, 1e-6);
}

TEST(ArmGeometry, UntrackedShoulderGivesNoAngle) {
  SkeletonBody b = standing_child();
  b.joint(JointId::kShoulderLeft).confidence = 0;
  ArmAnglesValue a = arm_angles(b);
  EXPECT_FALSE(a.left.has_value());
  EXPECT_FALSE(a.right.has_value());
}

}  // namespace
}  // namespace dreamsense::primitives
