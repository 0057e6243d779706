#include "dreamsense/perception/body.hpp"

#include "dreamsense/body/body_analyzer.hpp"
#include "dreamsense/testing/analyzer_runner.hpp"

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
  testing::AnalyzerRunner runner(std::move(*a));
  ASSERT_TRUE(runner.run(tick_with(Skeleton{{standing_child({0, 0, -0.5})}}, 0)));
  auto e = runner.output(keys::kChildBody);
  ASSERT_TRUE(e && e->present());
  EXPECT_NEAR(e->value->body.joint(JointId::kHead).position_m[2], 1.1, 1e-9);
  EXPECT_FLOAT_EQ(e->confidence, 1.f);
  EXPECT_EQ(e->source, "body");

  // Negative case: the tracker reports no body.
  ASSERT_TRUE(runner.run(tick_with(Skeleton{}, 40)));
  e = runner.output(keys::kChildBody);
  ASSERT_TRUE(e);
  EXPECT_FALSE(e->present());

  // No skeleton frame at this tick: nothing is written (no made-up observation).
  ASSERT_TRUE(runner.run(tick_with(std::nullopt, 80)));
  EXPECT_TRUE(runner.last_writes().empty());
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
