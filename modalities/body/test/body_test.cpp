#include "dreamsense/body/arm_geometry.hpp"
#include "dreamsense/body/body_analyzer.hpp"

#include <gtest/gtest.h>

namespace dreamsense::body {
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
  ArmAngles a = arm_angles(standing_child());
  ASSERT_TRUE(a.left && a.right);
  EXPECT_NEAR(a.left->elevation_deg, -90, 1e-6);
  EXPECT_NEAR(a.right->elevation_deg, 0, 1e-6);
  EXPECT_NEAR(a.right->azimuth_deg, 0, 1e-6);
}

TEST(ArmGeometry, ArmPointingForwardHasAzimuth90) {
  SkeletonBody b = standing_child();
  // Forward for the child is towards the sensor: -z.
  b.joint(JointId::kElbowLeft).position_m = {0.15, -0.05, 0.85};
  ArmAngles a = arm_angles(b);
  ASSERT_TRUE(a.left);
  EXPECT_NEAR(a.left->azimuth_deg, 90, 1e-6);
  EXPECT_NEAR(a.left->elevation_deg, 0, 1e-6);
}

TEST(ArmGeometry, UntrackedShoulderGivesNoAngle) {
  SkeletonBody b = standing_child();
  b.joint(JointId::kShoulderLeft).confidence = 0;
  ArmAngles a = arm_angles(b);
  EXPECT_FALSE(a.left.has_value());
  EXPECT_FALSE(a.right.has_value());
}

TEST(ChildSelection, PrefersPreviousChoiceThenExpectedSeat) {
  std::vector<SkeletonBody> bodies{standing_child({0.8, 0, 0.5}), standing_child()};
  ChildSelectionOptions o;
  EXPECT_EQ(select_child(bodies, std::nullopt, o), 1u) << "nearest to the child's seat";
  EXPECT_EQ(select_child(bodies, cv::Vec3d(0.8, -0.05, 1.6), o), 0u) << "keeps tracking";
  EXPECT_FALSE(select_child({}, std::nullopt, o).has_value());
}

MultiFrame tick_with(std::optional<Skeleton> s, int64_t ms) {
  MultiFrame mf;
  mf.stamp = Timestamp::from_ns(ms * 1'000'000);
  if (s) mf.frames["front.skeleton"] = make_frame("front.skeleton", mf.stamp, 0, *s);
  return mf;
}

TEST(BodyAnalyzer, WritesTheChildInWorldAndAbsenceWhenNobodyIsThere) {
  BodyAnalyzerOptions o;
  o.world_from_sensor_t = {0, 0, 0.5};
  auto a = make_body_analyzer(o);
  ASSERT_TRUE(a);
  Blackboard bb;
  BlackboardWriter w("body");
  ASSERT_TRUE(
      (*a)->process(tick_with(Skeleton{{standing_child({0, 0, -0.5})}}, 0), bb.snapshot(), w));
  bb.commit(w, Timestamp::from_ns(0));
  auto e = bb.snapshot().get(keys::kChildBody);
  ASSERT_TRUE(e && e->present());
  EXPECT_NEAR(e->value->body.joint(JointId::kHead).position_m[2], 1.1, 1e-9);
  EXPECT_FLOAT_EQ(e->confidence, 1.f);
  EXPECT_EQ(e->source, "body");

  // Negative case: the tracker reports no body.
  ASSERT_TRUE((*a)->process(tick_with(Skeleton{}, 40), bb.snapshot(), w));
  bb.commit(w, Timestamp::from_ns(40'000'000));
  e = bb.snapshot().get(keys::kChildBody);
  ASSERT_TRUE(e);
  EXPECT_FALSE(e->present());

  // No skeleton frame at this tick: nothing is written (no made-up observation).
  ASSERT_TRUE((*a)->process(tick_with(std::nullopt, 80), bb.snapshot(), w));
  EXPECT_TRUE(w.empty());
}

TEST(BodyAnalyzer, ContractNamesItsStream) {
  BodyAnalyzerOptions o;
  o.skeleton_sensor = "kinect0.skeleton";
  auto a = make_body_analyzer(o);
  ASSERT_TRUE(a);
  EXPECT_EQ((*a)->contract().required_inputs, std::vector<SensorId>{"kinect0.skeleton"});
  o.skeleton_sensor.clear();
  EXPECT_FALSE(make_body_analyzer(o));
}

}  // namespace
}  // namespace dreamsense::body
